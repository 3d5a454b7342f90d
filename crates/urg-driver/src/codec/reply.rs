//! Reply framing: where a reply ends, and its echo, status line and body.

use super::{LF, Status, StatusLine, checksum};
use crate::UrgError;

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

pub(super) fn strip_cr(line: &[u8]) -> &[u8] {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::UrgError;

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
