//! Parsing a command line as the sensor does, with the status it answers on failure.

use super::{
    Command, DataKind, MAX_TAG_LEN, ScanRequest, Status, StreamRequest, TimeCode, is_valid_tag,
};

impl Command {
    /// Parses a command line (terminator removed) as the sensor does; on failure gives the
    /// status the sensor answers. Returns the command and its tag string.
    pub fn parse(line: &[u8]) -> Result<(Command, Option<&[u8]>), Status> {
        let (body, tag) = match line.iter().position(|&c| c == b';') {
            Some(p) => (&line[..p], Some(&line[p + 1..])),
            None => (line, None),
        };
        if let Some(t) = tag {
            if t.len() > MAX_TAG_LEN {
                return Err(Status(*b"0G"));
            }
            if !is_valid_tag(t) {
                return Err(Status(*b"0H"));
            }
        }
        if body == b"SCIP2.0" {
            return Ok((Command::Scip2, tag));
        }
        if body.len() < 2 {
            return Err(Status::UNDEFINED);
        }
        let (name, p) = body.split_at(2);
        let fixed = |c: Command| {
            if p.is_empty() {
                Ok(c)
            } else {
                Err(Status(*b"0C"))
            }
        };
        let cmd = match name {
            b"VV" => fixed(Command::Version)?,
            b"PP" => fixed(Command::Parameters)?,
            b"II" => fixed(Command::State)?,
            b"BM" => fixed(Command::LaserOn)?,
            b"QT" => fixed(Command::LaserOff)?,
            b"RS" => fixed(Command::Reset)?,
            b"TM" => match p {
                b"0" => Command::Time(TimeCode::Enter),
                b"1" => Command::Time(TimeCode::Read),
                b"2" => Command::Time(TimeCode::Leave),
                [_] => return Err(Status(*b"01")),
                _ => return Err(Status(*b"0C")),
            },
            b"SS" => Command::BitRate(digits(p, 6, *b"0C", *b"01")?),
            b"CR" => Command::MotorSpeed(digits(p, 2, *b"0C", *b"01")? as u8),
            b"HS" => match p {
                b"0" => Command::HighSensitivity(false),
                b"1" => Command::HighSensitivity(true),
                [_] => return Err(Status(*b"01")),
                _ => return Err(Status(*b"0C")),
            },
            [b'G', k] => {
                let kind = DataKind::from_letter(*k).ok_or(Status::UNDEFINED)?;
                if p.len() != 10 {
                    return Err(Status(*b"0C"));
                }
                Command::Get(scan_params(kind, p)?)
            }
            [b'M', k] => {
                let kind = DataKind::from_letter(*k).ok_or(Status::UNDEFINED)?;
                if p.len() != 13 {
                    return Err(Status(*b"0C"));
                }
                let scan = scan_params(kind, &p[..10])?;
                let skip = digits(&p[10..11], 1, *b"0C", *b"06")? as u8;
                let count = digits(&p[11..13], 2, *b"0C", *b"07")? as u8;
                Command::Stream(StreamRequest { scan, skip, count })
            }
            _ => return Err(Status::UNDEFINED),
        };
        Ok((cmd, tag))
    }
}

fn digits(p: &[u8], width: usize, short: [u8; 2], bad: [u8; 2]) -> Result<u32, Status> {
    if p.len() != width {
        return Err(Status(short));
    }
    let mut v = 0u32;
    for &c in p {
        if !c.is_ascii_digit() {
            return Err(Status(bad));
        }
        v = v * 10 + u32::from(c - b'0');
    }
    Ok(v)
}

fn scan_params(kind: DataKind, p: &[u8]) -> Result<ScanRequest, Status> {
    let start_step = digits(&p[0..4], 4, *b"0C", *b"01")? as u16;
    let end_step = digits(&p[4..8], 4, *b"0C", *b"02")? as u16;
    let cluster = digits(&p[8..10], 2, *b"0C", *b"03")? as u8;
    Ok(ScanRequest {
        kind,
        start_step,
        end_step,
        cluster,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn commands_encode_with_fixed_widths_and_parse_back() {
        let cmds = [
            (Command::Version, "VV"),
            (Command::Time(TimeCode::Read), "TM1"),
            (Command::BitRate(115_200), "SS115200"),
            (Command::MotorSpeed(0), "CR00"),
            (Command::HighSensitivity(true), "HS1"),
            (
                Command::Get(ScanRequest {
                    kind: DataKind::Range3,
                    start_step: 44,
                    end_step: 725,
                    cluster: 1,
                }),
                "GD0044072501",
            ),
            (
                Command::Stream(StreamRequest {
                    scan: ScanRequest {
                        kind: DataKind::RangeIntensity,
                        start_step: 0,
                        end_step: 1080,
                        cluster: 1,
                    },
                    skip: 0,
                    count: 1,
                }),
                "ME0000108001001",
            ),
            (Command::Scip2, "SCIP2.0"),
        ];
        for (c, text) in cmds {
            let mut o = Vec::new();
            c.encode_line(None, &mut o).unwrap();
            assert_eq!(o, text.as_bytes());
            assert_eq!(Command::parse(text.as_bytes()).unwrap(), (c, None));
        }
        let mut o = Vec::new();
        Command::Time(TimeCode::Read)
            .encode(Some("a"), &mut o)
            .unwrap();
        assert_eq!(o, b"TM1;a\n");
        assert!(Command::Version.encode(Some("bad;tag"), &mut o).is_err());
        assert_eq!(Command::parse(b"XX"), Err(Status(*b"0E")));
        assert_eq!(Command::parse(b"VV;0123456789abcdefg"), Err(Status(*b"0G")));
        assert_eq!(Command::parse(b"GD004407250"), Err(Status(*b"0C")));
        assert_eq!(Command::parse(b"GD00x4072501"), Err(Status(*b"01")));
    }
}
