//! Number helpers for hot loops.

/// `x.floor() as i64`, bit for bit (saturating, NaN to 0), without a libm call.
///
/// ```
/// assert_eq!(scan_types::floor_i64(-0.5), -1);
/// assert_eq!(scan_types::floor_i64(2.0), 2);
/// ```
#[inline]
pub fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `x.floor() as i32`, bit for bit, as [`floor_i64`].
#[inline]
pub fn floor_i32(x: f64) -> i32 {
    let t = x as i32;
    if f64::from(t) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floors_equal_the_standard_floor_and_cast() {
        let two63 = 2f64.powi(63);
        let mut xs = vec![
            0.0,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            -1e-300,
            1e-300,
            2.999_999_999_999_999_6,
            -2.000_000_000_000_000_4,
            4503599627370495.5,
            -4503599627370495.5,
            2f64.powi(52),
            -2f64.powi(52) - 1.0,
            two63,
            -two63,
            -two63 * 2.0,
            two63 * 2.0,
            1e300,
            -1e300,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::NAN,
            f64::MIN_POSITIVE,
            2147483647.5,
            2147483648.0,
            -2147483648.0,
            -2147483648.5,
            -2147483649.0,
            -2.5,
            -2.0,
            3.999,
            1e15 + 0.5,
        ];
        // The four floats just inside a few integers, either sign.
        for k in [-3.0f64, -1.0, 1.0, 7.0, 1e6] {
            let mut x = k;
            for _ in 0..4 {
                x = f64::from_bits(x.to_bits() - 1);
                xs.push(x);
                xs.push(-x);
            }
        }
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x:e}");
            assert_eq!(floor_i32(x), x.floor() as i32, "{x:e}");
        }
    }
}
