//! The pure SCIP 2.0 codec: checksums, character encodings, commands, reply framing,
//! information lines and scan data. No I/O happens here.
//!
//! ```
//! use urg_driver::codec::{checksum, decode_value, encode_value};
//! assert_eq!(checksum(b"Hokuyo"), b'o');
//! assert_eq!(decode_value(b"CB").unwrap(), 1234);
//! assert_eq!(decode_value(b"1Dh").unwrap(), 5432);
//! assert_eq!(decode_value(b"m2@0").unwrap(), 16_000_000);
//! let mut out = Vec::new();
//! encode_value(5432, 3, &mut out).unwrap();
//! assert_eq!(out, b"1Dh");
//! ```

use std::fmt;

use crate::UrgError;

/// Line feed, the SCIP line terminator.
pub const LF: u8 = b'\n';
/// Payload characters per data line before the line's checksum.
pub const DATA_LINE_CHARS: usize = 64;
/// Longest tag string the sensor accepts after `;`.
pub const MAX_TAG_LEN: usize = 16;

/// The SCIP checksum of `bytes`: the low 6 bits of their sum, plus 0x30.
#[inline]
pub fn checksum(bytes: &[u8]) -> u8 {
    // Only the low 6 bits matter, so a wrapping byte sum is exact (and vectorises).
    let s = bytes.iter().fold(0u8, |a, &b| a.wrapping_add(b));
    (s & 0x3F) + 0x30
}

/// True when `b` is a character of the 6-bit data alphabet (`0`..=`o`).
#[inline]
pub fn is_data_char(b: u8) -> bool {
    b.wrapping_sub(0x30) < 0x40
}

/// Decodes 1 to 5 characters of the 6-bit encoding (2-, 3- and 4-character values included).
pub fn decode_value(chars: &[u8]) -> Result<u32, UrgError> {
    if chars.is_empty() || chars.len() > 5 {
        return Err(UrgError::InvalidValue(format!(
            "a SCIP value has 1 to 5 characters, got {}",
            chars.len()
        )));
    }
    let mut v = 0u32;
    for (i, &c) in chars.iter().enumerate() {
        if !is_data_char(c) {
            return Err(UrgError::BadChar { byte: c, offset: i });
        }
        v = (v << 6) | u32::from(c - 0x30);
    }
    Ok(v)
}

/// Appends `value` encoded in `width` characters (1 to 5).
pub fn encode_value(value: u32, width: usize, out: &mut Vec<u8>) -> Result<(), UrgError> {
    if !(1..=5).contains(&width) || (width < 5 && value >> (6 * width) != 0) {
        return Err(UrgError::InvalidValue(format!(
            "{value} does not fit in {width} SCIP characters"
        )));
    }
    for i in (0..width).rev() {
        out.push(((value >> (6 * i)) & 0x3F) as u8 + 0x30);
    }
    Ok(())
}

/// A two-character SCIP 2.0 status, kept as characters (never parsed as a number).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Status(pub [u8; 2]);

impl Status {
    /// `00`: command accepted.
    pub const OK: Status = Status(*b"00");
    /// `99`: scan data follows (MD/MS/ME scan replies).
    pub const SCAN_DATA: Status = Status(*b"99");
    /// `0E`: undefined command (the model does not have it).
    pub const UNDEFINED: Status = Status(*b"0E");

    /// The two status characters as text.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.0).unwrap_or("??")
    }

    /// The numeric value when both characters are decimal digits.
    pub fn decimal(&self) -> Option<u8> {
        let [a, b] = self.0;
        (a.is_ascii_digit() && b.is_ascii_digit()).then(|| (a - b'0') * 10 + (b - b'0'))
    }

    /// True for a hardware-fault status (50..=97 for scan commands).
    pub fn is_hardware_fault(&self) -> bool {
        matches!(self.decimal(), Some(50..=97))
    }

    /// What this status means in answer to `command` (its two-letter name).
    pub fn meaning(&self, command: &str) -> &'static str {
        let scan_cmd = matches!(
            command,
            "GD" | "GS" | "GE" | "MD" | "MS" | "ME" | "HD" | "ND" | "HE" | "NE"
        );
        match &self.0 {
            b"00" => "OK",
            b"99" => "OK, scan data follows",
            b"0A" => "cannot create the reply internally",
            b"0B" => "buffer shortage, or a command repeated while still being processed",
            b"0C" => "insufficient parameters",
            b"0D" => "undefined command (1)",
            b"0E" => "undefined command: not supported by this model",
            b"0F" => "insufficient parameters (2)",
            b"0G" => "string longer than 16 characters",
            b"0H" => "invalid characters in the string",
            b"0I" => "sensor in firmware-update mode",
            b"0L" => "abnormal state: only a reboot recovers",
            b"0M" => "unstable state",
            _ => match (command, self.decimal()) {
                (_, Some(1)) if scan_cmd => "starting step has a non-numeric value",
                (_, Some(2)) if scan_cmd => "end step has a non-numeric value",
                (_, Some(3)) if scan_cmd => "cluster count has a non-numeric value",
                (_, Some(4)) if scan_cmd => "end step out of range",
                (_, Some(5)) if scan_cmd => "end step smaller than starting step",
                (_, Some(6)) if scan_cmd => "scan interval has a non-numeric value",
                (_, Some(7)) if scan_cmd => "number of scans has a non-numeric value",
                (_, Some(10)) if scan_cmd => "laser is off",
                (_, Some(21..=49)) if scan_cmd => "measurement stopped to verify an error",
                (_, Some(50..=97)) => "hardware fault",
                (_, Some(98)) if scan_cmd => "resumed after a hardware fault",
                ("BM", Some(1)) => "unable to switch the laser on: laser malfunction",
                ("BM", Some(2)) => "laser already on",
                ("TM", Some(1)) => "invalid control code",
                ("TM", Some(2)) => "already in time-adjust mode",
                ("TM", Some(3)) => "already out of time-adjust mode",
                ("TM", Some(4)) => "time requested while not in time-adjust mode",
                ("SS", Some(1)) => "bit rate has non-numeric characters",
                ("SS", Some(2)) => "invalid bit rate",
                ("SS", Some(3)) => "already at this bit rate",
                ("SS", Some(4)) => "not compatible with this sensor",
                ("CR", Some(1)) => "invalid speed parameter",
                ("CR", Some(2)) => "speed out of range",
                ("CR", Some(3)) => "already at this speed",
                ("CR", Some(4)) => "not compatible with this sensor",
                ("HS", Some(1)) => "invalid parameter",
                ("HS", Some(2)) => "already in this mode",
                ("HS", Some(3)) => "not compatible with this sensor",
                _ => "unknown status",
            },
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", String::from_utf8_lossy(&self.0))
    }
}

impl fmt::Debug for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Status({self})")
    }
}

/// The status line of a reply: SCIP 2.0 (two characters and a checksum) or SCIP 1.1 (one character).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StatusLine {
    /// A SCIP 2.0 status.
    Scip2(Status),
    /// A SCIP 1.1 one-character status (`0` is OK): the sensor is not in SCIP 2.0 mode.
    Scip1(u8),
}

/// The data a scan command asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DataKind {
    /// Ranges, 3-character encoding (`GD`/`MD`).
    Range3,
    /// Ranges, 2-character encoding (`GS`/`MS`), saturating at 4095 mm.
    Range2,
    /// Range and intensity pairs, 3+3 characters (`GE`/`ME`).
    RangeIntensity,
}

impl DataKind {
    /// Characters per measurement step.
    pub fn chars_per_step(self) -> usize {
        match self {
            DataKind::Range3 => 3,
            DataKind::Range2 => 2,
            DataKind::RangeIntensity => 6,
        }
    }

    /// The two-letter single-scan (`G?`) command name.
    pub fn get_name(self) -> &'static str {
        match self {
            DataKind::Range3 => "GD",
            DataKind::Range2 => "GS",
            DataKind::RangeIntensity => "GE",
        }
    }

    /// The two-letter streaming (`M?`) command name.
    pub fn stream_name(self) -> &'static str {
        match self {
            DataKind::Range3 => "MD",
            DataKind::Range2 => "MS",
            DataKind::RangeIntensity => "ME",
        }
    }

    fn from_letter(c: u8) -> Option<DataKind> {
        match c {
            b'D' => Some(DataKind::Range3),
            b'S' => Some(DataKind::Range2),
            b'E' => Some(DataKind::RangeIntensity),
            _ => None,
        }
    }
}

/// Which steps a scan command asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ScanRequest {
    /// Encoding of the reply.
    pub kind: DataKind,
    /// First step (0..=9999).
    pub start_step: u16,
    /// Last step, inclusive (0..=9999).
    pub end_step: u16,
    /// Steps merged into one value (0 and 1 both mean one).
    pub cluster: u8,
}

impl ScanRequest {
    /// Number of values one reply carries.
    pub fn value_count(&self) -> usize {
        if self.end_step < self.start_step {
            return 0;
        }
        let steps = usize::from(self.end_step - self.start_step) + 1;
        steps.div_ceil(usize::from(self.cluster.max(1)))
    }
}

/// A streaming request: steps, scans skipped between sends, and how many scans (0 = until `QT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StreamRequest {
    /// Which steps and encoding.
    pub scan: ScanRequest,
    /// Scans skipped after each sent scan (0..=9).
    pub skip: u8,
    /// Number of scans (1..=99), or 0 to stream until `QT`.
    pub count: u8,
}

/// The `TM` control code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeCode {
    /// `TM0`: enter time-adjust mode (laser off).
    Enter,
    /// `TM1`: read the sensor's 24-bit millisecond timer.
    Read,
    /// `TM2`: leave time-adjust mode.
    Leave,
}

/// A host-to-sensor command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// `SCIP2.0`: switch a SCIP 1.1 sensor to SCIP 2.0.
    Scip2,
    /// `VV`: version information.
    Version,
    /// `PP`: sensor parameters.
    Parameters,
    /// `II`: sensor state.
    State,
    /// `BM`: laser on.
    LaserOn,
    /// `QT`: laser off, stops streaming.
    LaserOff,
    /// `RS`: reset laser, motor speed, bit rate and timer.
    Reset,
    /// `TM0`/`TM1`/`TM2`: time adjustment.
    Time(TimeCode),
    /// `SS`: bit rate in bit/s (6 digits).
    BitRate(u32),
    /// `CR`: motor speed code (00 default, 01..=10 levels, 99 reset).
    MotorSpeed(u8),
    /// `HS`: high-sensitivity mode on or off.
    HighSensitivity(bool),
    /// `GD`/`GS`/`GE`: one scan.
    Get(ScanRequest),
    /// `MD`/`MS`/`ME`: streamed scans.
    Stream(StreamRequest),
}

fn push_decimal(out: &mut Vec<u8>, value: u32, width: usize) -> Result<(), UrgError> {
    let s = format!("{value:0width$}");
    if s.len() != width {
        return Err(UrgError::InvalidValue(format!(
            "{value} does not fit in {width} decimal digits"
        )));
    }
    out.extend_from_slice(s.as_bytes());
    Ok(())
}

/// True when `tag` is a valid command string: at most 16 letters, digits, space, `.`, `_`, `+`, `@`.
pub fn is_valid_tag(tag: &[u8]) -> bool {
    tag.len() <= MAX_TAG_LEN
        && tag
            .iter()
            .all(|&c| c.is_ascii_alphanumeric() || matches!(c, b' ' | b'.' | b'_' | b'+' | b'@'))
}

impl Command {
    /// The command's name as it appears on the wire (`VV`, `TM`, `GD`, `SCIP2.0`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Command::Scip2 => "SCIP2.0",
            Command::Version => "VV",
            Command::Parameters => "PP",
            Command::State => "II",
            Command::LaserOn => "BM",
            Command::LaserOff => "QT",
            Command::Reset => "RS",
            Command::Time(_) => "TM",
            Command::BitRate(_) => "SS",
            Command::MotorSpeed(_) => "CR",
            Command::HighSensitivity(_) => "HS",
            Command::Get(r) => r.kind.get_name(),
            Command::Stream(r) => r.scan.kind.stream_name(),
        }
    }

    /// Appends the command line (without its terminator) with an optional tag string.
    pub fn encode_line(&self, tag: Option<&str>, out: &mut Vec<u8>) -> Result<(), UrgError> {
        out.extend_from_slice(self.name().as_bytes());
        match *self {
            Command::Time(c) => out.push(match c {
                TimeCode::Enter => b'0',
                TimeCode::Read => b'1',
                TimeCode::Leave => b'2',
            }),
            Command::BitRate(b) => push_decimal(out, b, 6)?,
            Command::MotorSpeed(s) => push_decimal(out, u32::from(s), 2)?,
            Command::HighSensitivity(on) => out.push(if on { b'1' } else { b'0' }),
            Command::Get(r) => push_scan_params(out, &r)?,
            Command::Stream(s) => {
                push_scan_params(out, &s.scan)?;
                push_decimal(out, u32::from(s.skip), 1)?;
                push_decimal(out, u32::from(s.count), 2)?;
            }
            _ => {}
        }
        if let Some(t) = tag {
            if !is_valid_tag(t.as_bytes()) {
                return Err(UrgError::InvalidValue(format!(
                    "tag {t:?}: at most 16 letters, digits, space, '.', '_', '+', '@'"
                )));
            }
            out.push(b';');
            out.extend_from_slice(t.as_bytes());
        }
        Ok(())
    }

    /// Appends the command line and its LF terminator.
    pub fn encode(&self, tag: Option<&str>, out: &mut Vec<u8>) -> Result<(), UrgError> {
        self.encode_line(tag, out)?;
        out.push(LF);
        Ok(())
    }

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

fn push_scan_params(out: &mut Vec<u8>, r: &ScanRequest) -> Result<(), UrgError> {
    push_decimal(out, u32::from(r.start_step), 4)?;
    push_decimal(out, u32::from(r.end_step), 4)?;
    push_decimal(out, u32::from(r.cluster), 2)
}

/// Finds the end of the first complete reply in `buf` (the index just past its blank line).
///
/// A reply ends with an empty line, so its end is the first `LF LF`. Leading blank lines
/// count as (empty) replies of one byte.
///
/// ```
/// use urg_driver::codec::find_reply_end;
/// assert_eq!(find_reply_end(b"QT\n00P\n\nVV"), Some(8));
/// assert_eq!(find_reply_end(b"QT\n00P\n"), None);
/// ```
pub fn find_reply_end(buf: &[u8]) -> Option<usize> {
    find_reply_end_from(buf, 0)
}

/// As [`find_reply_end`], starting the search at `from` (bytes before it are known to hold no
/// reply end, except that `buf[from - 1]` may be the first LF of one).
pub fn find_reply_end_from(buf: &[u8], from: usize) -> Option<usize> {
    if buf.first() == Some(&LF) {
        return Some(1);
    }
    let mut i = from.saturating_sub(1).max(1);
    while i < buf.len() {
        match buf[i..].iter().position(|&c| c == LF) {
            Some(p) => {
                let j = i + p;
                if buf[j - 1] == LF {
                    return Some(j + 1);
                }
                i = j + 1;
            }
            None => return None,
        }
    }
    None
}

/// One reply split into its parts; `body` holds the lines after the status line, each ending
/// in LF, without the final blank line.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reply<'a> {
    /// The echoed command line (CR removed).
    pub echo: &'a [u8],
    /// The status line.
    pub status: StatusLine,
    /// The lines after the status, each ending in LF.
    pub body: &'a [u8],
    /// Byte offset of `body` inside the reply.
    pub body_offset: usize,
}

fn strip_cr(line: &[u8]) -> &[u8] {
    line.strip_suffix(b"\r").unwrap_or(line)
}

/// Splits one complete reply (as delimited by [`find_reply_end`], blank line included) into
/// echo, status and body, checking the status line's checksum.
pub fn parse_reply(reply: &[u8]) -> Result<Reply<'_>, UrgError> {
    let framing = |what: &str, offset| UrgError::Framing {
        what: what.to_string(),
        offset,
    };
    if reply.len() < 2 || !reply.ends_with(b"\n\n") {
        return Err(framing("a reply must end with an empty line", reply.len()));
    }
    let echo_end = reply
        .iter()
        .position(|&c| c == LF)
        .ok_or_else(|| framing("no echo line", 0))?;
    let echo = strip_cr(&reply[..echo_end]);
    let st_start = echo_end + 1;
    let st_len = reply[st_start..]
        .iter()
        .position(|&c| c == LF)
        .ok_or_else(|| framing("no status line", st_start))?;
    let st = strip_cr(&reply[st_start..st_start + st_len]);
    let status = match *st {
        [a, b, s] => {
            let sum = checksum(&[a, b]);
            if sum != s {
                return Err(UrgError::Checksum {
                    line: 2,
                    offset: st_start,
                    expected: sum as char,
                    found: s as char,
                });
            }
            StatusLine::Scip2(Status([a, b]))
        }
        [c] => StatusLine::Scip1(c),
        [] => return Err(framing("empty status line", st_start)),
        _ => {
            return Err(framing(
                "status line must be 2 characters and a checksum",
                st_start,
            ));
        }
    };
    let body_offset = st_start + st_len + 1;
    // The reply ends in "\n\n": drop the final LF (the blank line).
    let body_end = (reply.len() - 1).max(body_offset);
    Ok(Reply {
        echo,
        status,
        body: &reply[body_offset..body_end],
        body_offset,
    })
}

/// Iterates over the `KEY:value` pairs of a VV/PP/II body, checking each line's checksum
/// (which covers `KEY:value` and excludes the `;`).
pub fn info_lines<'a>(
    reply: &Reply<'a>,
) -> impl Iterator<Item = Result<(&'a str, &'a str), UrgError>> + 'a {
    let body = reply.body;
    let base = reply.body_offset;
    let mut pos = 0usize;
    let mut line_no = 2usize;
    std::iter::from_fn(move || {
        if pos >= body.len() {
            return None;
        }
        let len = body[pos..].iter().position(|&c| c == LF)?;
        let line = strip_cr(&body[pos..pos + len]);
        let offset = base + pos;
        pos += len + 1;
        line_no += 1;
        Some(parse_info_line(line, line_no, offset))
    })
}

/// Parses one `KEY:value;S` information line.
pub fn parse_info_line(
    line: &[u8],
    line_no: usize,
    offset: usize,
) -> Result<(&str, &str), UrgError> {
    let framing = |what: &str| UrgError::Framing {
        what: format!("information line {line_no}: {what}"),
        offset,
    };
    let n = line.len();
    if n < 3 || line[n - 2] != b';' {
        return Err(framing("expected 'KEY:value;' and a checksum"));
    }
    let text = &line[..n - 2];
    let sum = checksum(text);
    if sum != line[n - 1] {
        return Err(UrgError::Checksum {
            line: line_no,
            offset,
            expected: sum as char,
            found: line[n - 1] as char,
        });
    }
    let text = std::str::from_utf8(text).map_err(|_| framing("not ASCII text"))?;
    let (k, v) = text.split_once(':').ok_or_else(|| framing("no ':'"))?;
    Ok((k, v))
}

/// One decoded scan in sensor units, reused from scan to scan (no allocation once warm).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct RawScan {
    /// The sensor's 24-bit millisecond timer at the scan's step 0.
    pub timestamp_ms: u32,
    /// One value per output step: a distance in mm, or an error code below DMIN.
    pub ranges_mm: Vec<u32>,
    /// Intensities, for `GE`/`ME` replies (empty otherwise).
    pub intensities: Vec<u32>,
    payload: Vec<u8>,
}

impl RawScan {
    /// An empty scan with room for `steps` values.
    pub fn with_capacity(steps: usize) -> Self {
        RawScan {
            timestamp_ms: 0,
            ranges_mm: Vec::with_capacity(steps),
            intensities: Vec::with_capacity(steps),
            payload: Vec::with_capacity(steps * 6),
        }
    }
}

/// Decodes and verifies a scan reply body (timestamp line and data lines) into `out`.
///
/// Every line's checksum is checked; values straddling the 64-character lines are joined;
/// a character outside the encoding or a payload whose length is not a whole number of
/// values is an error. `body_offset` is added to error offsets.
pub fn decode_scan_body(
    body: &[u8],
    body_offset: usize,
    first_line_no: usize,
    kind: DataKind,
    out: &mut RawScan,
) -> Result<(), UrgError> {
    out.ranges_mm.clear();
    out.intensities.clear();
    out.payload.clear();
    let mut pos = 0usize;
    let mut line_no = first_line_no;
    let mut first = true;
    while pos < body.len() {
        // Full data lines are 64 characters and a checksum: try that before searching.
        let full = DATA_LINE_CHARS + 1;
        let fast = (body.get(pos + full) == Some(&LF)).then_some(full);
        let Some(len) = fast.or_else(|| body[pos..].iter().position(|&c| c == LF)) else {
            return Err(UrgError::Framing {
                what: format!("line {line_no} has no LF"),
                offset: body_offset + pos,
            });
        };
        let line = &body[pos..pos + len];
        let offset = body_offset + pos;
        if line.len() < 2 || line.len() > DATA_LINE_CHARS + 1 {
            return Err(UrgError::Framing {
                what: format!(
                    "line {line_no} has {} characters, a data line has 2 to 65",
                    line.len()
                ),
                offset,
            });
        }
        let (payload, sum) = line.split_at(line.len() - 1);
        let expected = checksum(payload);
        if expected != sum[0] {
            return Err(UrgError::Checksum {
                line: line_no,
                offset,
                expected: expected as char,
                found: sum[0] as char,
            });
        }
        let bad = payload
            .iter()
            .fold(0u8, |a, &b| a | (b.wrapping_sub(0x30) & 0xC0));
        if bad != 0 {
            let i = payload.iter().position(|&b| !is_data_char(b)).unwrap_or(0);
            return Err(UrgError::BadChar {
                byte: payload[i],
                offset: offset + i,
            });
        }
        if first {
            if payload.len() != 4 {
                return Err(UrgError::Framing {
                    what: format!(
                        "time stamp line {line_no} has {} characters, expected 4",
                        payload.len()
                    ),
                    offset,
                });
            }
            out.timestamp_ms = dec4(payload);
            first = false;
        } else {
            out.payload.extend_from_slice(payload);
        }
        pos += len + 1;
        line_no += 1;
    }
    if first {
        return Err(UrgError::Framing {
            what: "scan reply has no time stamp line".into(),
            offset: body_offset,
        });
    }
    let w = kind.chars_per_step();
    if !out.payload.len().is_multiple_of(w) {
        return Err(UrgError::Framing {
            what: format!(
                "{} data characters is not a whole number of {w}-character values",
                out.payload.len()
            ),
            offset: body_offset + body.len(),
        });
    }
    let n = out.payload.len() / w;
    // Every character was checked to lie in 0x30..=0x6F, so the subtractions cannot wrap.
    out.ranges_mm.resize(n, 0);
    match kind {
        DataKind::Range3 => {
            for (d, c) in out.ranges_mm.iter_mut().zip(out.payload.chunks_exact(3)) {
                *d = dec3(c);
            }
        }
        DataKind::Range2 => {
            for (d, c) in out.ranges_mm.iter_mut().zip(out.payload.chunks_exact(2)) {
                *d = (u32::from(c[0] - 0x30) << 6) | u32::from(c[1] - 0x30);
            }
        }
        DataKind::RangeIntensity => {
            out.intensities.resize(n, 0);
            let pairs = out.ranges_mm.iter_mut().zip(out.intensities.iter_mut());
            for ((r, i), c) in pairs.zip(out.payload.chunks_exact(6)) {
                *r = dec3(&c[..3]);
                *i = dec3(&c[3..]);
            }
        }
    }
    Ok(())
}

#[inline]
fn dec3(c: &[u8]) -> u32 {
    (u32::from(c[0] - 0x30) << 12) | (u32::from(c[1] - 0x30) << 6) | u32::from(c[2] - 0x30)
}

#[inline]
fn dec4(c: &[u8]) -> u32 {
    (u32::from(c[0] - 0x30) << 18) | dec3(&c[1..4])
}

/// Decodes a complete scan reply (echo through blank line): checks the status (`00` or `99`)
/// and decodes its data into `out`. Returns the parsed reply parts.
pub fn decode_scan_reply<'a>(
    reply: &'a [u8],
    kind: DataKind,
    out: &mut RawScan,
) -> Result<Reply<'a>, UrgError> {
    let r = parse_reply(reply)?;
    match r.status {
        StatusLine::Scip2(s) if s == Status::OK || s == Status::SCAN_DATA => {}
        StatusLine::Scip2(s) => {
            let command = String::from_utf8_lossy(r.echo.get(..2).unwrap_or(b"??"));
            return Err(UrgError::from_status(&command, s));
        }
        StatusLine::Scip1(_) => {
            return Err(UrgError::Framing {
                what: "SCIP 1.1 status on a scan reply".into(),
                offset: r.body_offset,
            });
        }
    }
    decode_scan_body(r.body, r.body_offset, 3, kind, out)?;
    Ok(r)
}

/// Appends one `KEY:value;S` information line with its checksum and LF.
pub fn encode_info_line(key: &str, value: &str, out: &mut Vec<u8>) {
    let start = out.len();
    out.extend_from_slice(key.as_bytes());
    out.push(b':');
    out.extend_from_slice(value.as_bytes());
    let sum = checksum(&out[start..]);
    out.push(b';');
    out.push(sum);
    out.push(LF);
}

/// Appends a status line (two characters, checksum, LF).
pub fn encode_status_line(status: Status, out: &mut Vec<u8>) {
    out.extend_from_slice(&status.0);
    out.push(checksum(&status.0));
    out.push(LF);
}

/// Appends a scan body: the timestamp line, then the values (and intensities for
/// [`DataKind::RangeIntensity`]) broken into 64-character lines, each with its checksum.
/// Values are clamped to what the encoding can carry. Does not append the blank line.
pub fn encode_scan_body(
    timestamp_ms: u32,
    ranges_mm: &[u32],
    intensities: &[u32],
    kind: DataKind,
    out: &mut Vec<u8>,
) {
    let start = out.len();
    for i in (0..4).rev() {
        out.push(((timestamp_ms >> (6 * i)) & 0x3F) as u8 + 0x30);
    }
    let sum = checksum(&out[start..]);
    out.push(sum);
    out.push(LF);
    let mut line_start = out.len();
    let mut push = |c: u8, out: &mut Vec<u8>| {
        out.push(c);
        if out.len() - line_start == DATA_LINE_CHARS {
            let s = checksum(&out[line_start..]);
            out.push(s);
            out.push(LF);
            line_start = out.len();
        }
    };
    let mut chars = |v: u32, width: usize, out: &mut Vec<u8>| {
        let v = v.min((1u32 << (6 * width)) - 1);
        for i in (0..width).rev() {
            push(((v >> (6 * i)) & 0x3F) as u8 + 0x30, out);
        }
    };
    for (i, &r) in ranges_mm.iter().enumerate() {
        match kind {
            DataKind::Range3 => chars(r, 3, out),
            DataKind::Range2 => chars(r, 2, out),
            DataKind::RangeIntensity => {
                chars(r, 3, out);
                chars(intensities.get(i).copied().unwrap_or(0), 3, out);
            }
        }
    }
    if out.len() > line_start {
        let s = checksum(&out[line_start..]);
        out.push(s);
        out.push(LF);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn checksums_of_status_lines_match_the_digest_table() {
        for (st, sum) in [
            ("00", b'P'),
            ("99", b'b'),
            ("01", b'Q'),
            ("02", b'R'),
            ("03", b'S'),
            ("04", b'T'),
            ("0E", b'e'),
            ("0L", b'l'),
            ("10", b'Q'),
        ] {
            assert_eq!(checksum(st.as_bytes()), sum, "{st}");
        }
    }

    #[test]
    fn encodings_round_trip_and_reject_overflow() {
        for (v, w) in [(0, 1), (63, 1), (4095, 2), (262_143, 3), (16_777_215, 4)] {
            let mut o = Vec::new();
            encode_value(v, w, &mut o).unwrap();
            assert_eq!(o.len(), w);
            assert_eq!(decode_value(&o).unwrap(), v);
        }
        assert!(encode_value(4096, 2, &mut Vec::new()).is_err());
        assert!(decode_value(b"").is_err());
        assert!(matches!(
            decode_value(b"0p"),
            Err(UrgError::BadChar {
                byte: b'p',
                offset: 1
            })
        ));
    }

    #[test]
    fn status_is_never_read_as_a_number() {
        let s = Status(*b"0E");
        assert_eq!(s.decimal(), None);
        assert_ne!(s, Status::OK);
        assert!(Status(*b"55").is_hardware_fault());
        assert!(!Status(*b"0F").is_hardware_fault());
        assert_eq!(Status(*b"02").meaning("BM"), "laser already on");
    }

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

    #[test]
    fn straddling_values_are_joined() {
        // 30 three-character values = 90 characters: value 21 straddles the first line break.
        let values: Vec<u32> = (0..30).map(|i| i * 1000 + 7).collect();
        let mut body = Vec::new();
        encode_scan_body(123_456, &values, &[], DataKind::Range3, &mut body);
        let second_line = &body[6..];
        assert_eq!(second_line[64], checksum(&second_line[..64]));
        let mut raw = RawScan::default();
        decode_scan_body(&body, 0, 3, DataKind::Range3, &mut raw).unwrap();
        assert_eq!(raw.timestamp_ms, 123_456);
        assert_eq!(raw.ranges_mm, values);
    }

    #[test]
    fn range_intensity_pairs_decode() {
        let r = [45, 48, 60000];
        let i = [1809, 1780, 3];
        let mut body = Vec::new();
        encode_scan_body(4_821_609, &r, &i, DataKind::RangeIntensity, &mut body);
        let mut raw = RawScan::default();
        decode_scan_body(&body, 0, 3, DataKind::RangeIntensity, &mut raw).unwrap();
        assert_eq!(raw.ranges_mm, r);
        assert_eq!(raw.intensities, i);
    }

    #[test]
    fn info_checksum_excludes_the_semicolon() {
        let mut o = Vec::new();
        encode_info_line("DMAX", "5600", &mut o);
        assert_eq!(o, b"DMAX:5600;_\n");
        assert_eq!(parse_info_line(b"AMIN:44;7", 3, 0).unwrap(), ("AMIN", "44"));
        assert!(matches!(
            parse_info_line(b"AMIN:44;8", 3, 0),
            Err(UrgError::Checksum { line: 3, .. })
        ));
    }

    #[test]
    fn reply_framing() {
        assert_eq!(find_reply_end(b"\nQT\n00P\n\n"), Some(1));
        assert_eq!(find_reply_end(b"QT\n00P\n\n"), Some(8));
        let r = parse_reply(b"QT\n00P\n\n").unwrap();
        assert_eq!(r.echo, b"QT");
        assert_eq!(r.status, StatusLine::Scip2(Status::OK));
        assert!(r.body.is_empty());
        let r = parse_reply(b"QT\nE\n\n").unwrap();
        assert_eq!(r.status, StatusLine::Scip1(b'E'));
        assert!(matches!(
            parse_reply(b"QT\n00Q\n\n"),
            Err(UrgError::Checksum { line: 2, .. })
        ));
        assert!(parse_reply(b"\n\n").is_err());
    }
}
