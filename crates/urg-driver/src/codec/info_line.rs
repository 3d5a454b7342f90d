//! Information lines (`KEY:value;S`) of VV/PP/II replies, read and written.

use super::reply::strip_cr;
use super::{LF, Reply, checksum};
use crate::UrgError;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::UrgError;

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
}
