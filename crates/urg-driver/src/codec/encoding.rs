//! The SCIP character layer: the line checksum and the 6-bit value encodings.

use crate::UrgError;

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::UrgError;

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
}
