//! Scan data: decoding and verifying scan replies into a reusable [`RawScan`], and encoding
//! scan bodies.

use super::{
    DATA_LINE_CHARS, DataKind, LF, Reply, Status, StatusLine, checksum, is_data_char, parse_reply,
};
use crate::UrgError;

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
        let (payload, len, offset) = checked_data_line(body, pos, body_offset, line_no)?;
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
    unpack_values(kind, w, out);
    Ok(())
}

/// The line of `body` starting at `pos`, checked for its length, checksum and characters:
/// its payload (checksum removed), its length without the LF, and its offset in the reply.
#[inline]
fn checked_data_line(
    body: &[u8],
    pos: usize,
    body_offset: usize,
    line_no: usize,
) -> Result<(&[u8], usize, usize), UrgError> {
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
    Ok((payload, len, offset))
}

/// Splits the joined payload of `out` (a whole number of `w`-character values) into its
/// ranges and intensities.
#[inline]
fn unpack_values(kind: DataKind, w: usize, out: &mut RawScan) {
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
}
