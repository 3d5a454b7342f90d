//! Encoding a command line, its parameters and its tag string.

use super::{Command, LF, MAX_TAG_LEN, ScanRequest, TimeCode};
use crate::UrgError;

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
}

fn push_scan_params(out: &mut Vec<u8>, r: &ScanRequest) -> Result<(), UrgError> {
    push_decimal(out, u32::from(r.start_step), 4)?;
    push_decimal(out, u32::from(r.end_step), 4)?;
    push_decimal(out, u32::from(r.cluster), 2)
}
