//! Angle normalisation.

use std::f64::consts::{PI, TAU};

/// Normalises an angle in radians to the half-open interval (-pi, pi].
///
/// ```
/// use scan_types::normalize_angle_rad;
/// use std::f64::consts::PI;
/// assert_eq!(normalize_angle_rad(-PI), PI);
/// assert!((normalize_angle_rad(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-12);
/// ```
pub fn normalize_angle_rad(angle_rad: f64) -> f64 {
    if !angle_rad.is_finite() || (angle_rad > -PI && angle_rad <= PI) {
        return angle_rad;
    }
    let mut a = angle_rad.rem_euclid(TAU); // [0, 2pi)
    if a > PI {
        a -= TAU;
    }
    // rem_euclid can return exactly TAU for tiny negative inputs.
    if a <= -PI { a + TAU } else { a }
}

/// The signed difference `a - b` normalised to (-pi, pi].
///
/// ```
/// use scan_types::angle_diff_rad;
/// assert!((angle_diff_rad(-3.1, 3.1) - (2.0 * std::f64::consts::PI - 6.2)).abs() < 1e-12);
/// ```
pub fn angle_diff_rad(a_rad: f64, b_rad: f64) -> f64 {
    normalize_angle_rad(a_rad - b_rad)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wraps_into_half_open_interval() {
        assert_eq!(normalize_angle_rad(PI), PI);
        assert_eq!(normalize_angle_rad(-PI), PI);
        assert_eq!(normalize_angle_rad(0.0), 0.0);
        assert!((normalize_angle_rad(TAU + 0.5) - 0.5).abs() < 1e-12);
        assert!((normalize_angle_rad(-TAU - 0.5) + 0.5).abs() < 1e-12);
        // Just past pi wraps to just above -pi.
        let a = normalize_angle_rad(PI + 1e-9);
        assert!((a + PI - 1e-9).abs() < 1e-12, "{a}");
        // Just below -pi wraps to just below pi.
        let b = normalize_angle_rad(-PI - 1e-9);
        assert!((b - PI + 1e-9).abs() < 1e-12, "{b}");
    }

    #[test]
    fn many_turns_and_tiny_values() {
        for k in -20..=20 {
            let base = 0.3;
            let a = normalize_angle_rad(base + k as f64 * TAU);
            assert!((a - base).abs() < 1e-9, "k={k} a={a}");
        }
        assert_eq!(normalize_angle_rad(-1e-300), -1e-300);
        let a = normalize_angle_rad(-f64::EPSILON);
        assert!(a > -PI && a <= PI);
    }

    #[test]
    fn non_finite_passes_through() {
        assert!(normalize_angle_rad(f64::NAN).is_nan());
        assert!(normalize_angle_rad(f64::INFINITY).is_infinite());
    }

    #[test]
    fn difference_takes_short_way_round() {
        assert!((angle_diff_rad(0.1, -0.1) - 0.2).abs() < 1e-12);
        assert!((angle_diff_rad(-PI + 0.1, PI - 0.1) - 0.2).abs() < 1e-12);
        assert!((angle_diff_rad(PI - 0.1, -PI + 0.1) + 0.2).abs() < 1e-12);
    }
}
