//! Poses, points and sizes written as comma-separated numbers (command-line options).

use crate::{Pose2, ScanTypesError, WorldPoint};

/// Splits `s` at commas into exactly `n` finite numbers; `what` names the value in errors.
fn parse_numbers(s: &str, n: usize, what: &'static str) -> Result<Vec<f64>, ScanTypesError> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| {
            t.trim()
                .parse::<f64>()
                .ok()
                .filter(|x| x.is_finite())
                .ok_or_else(|| ScanTypesError::NotANumber {
                    what,
                    text: s.to_string(),
                    token: t.trim().to_string(),
                })
        })
        .collect::<Result<_, _>>()?;
    if v.len() != n {
        return Err(ScanTypesError::WrongCount {
            what,
            text: s.to_string(),
            expected: n,
            found: v.len(),
        });
    }
    Ok(v)
}

/// Parses a pose written `X,Y,THETA_DEG` (metres, metres, degrees).
///
/// ```
/// let p = scan_types::parse_pose_deg("-3.92,-4.26,45").unwrap();
/// assert!((p.theta_rad - std::f64::consts::FRAC_PI_4).abs() < 1e-12);
/// assert!(scan_types::parse_pose_deg("1,2").is_err());
/// ```
pub fn parse_pose_deg(s: &str) -> Result<Pose2, ScanTypesError> {
    let v = parse_numbers(s, 3, "pose")?;
    Ok(Pose2::new(v[0], v[1], v[2].to_radians()))
}

/// Parses a point written `X,Y` (metres).
pub fn parse_point(s: &str) -> Result<WorldPoint, ScanTypesError> {
    let v = parse_numbers(s, 2, "point")?;
    Ok(WorldPoint::new(v[0], v[1]))
}

/// Parses a size written `W,H` (metres, both > 0).
pub fn parse_size(s: &str) -> Result<(f64, f64), ScanTypesError> {
    let v = parse_numbers(s, 2, "size")?;
    if v[0] <= 0.0 || v[1] <= 0.0 {
        return Err(ScanTypesError::NotPositive {
            what: "size",
            text: s.to_string(),
        });
    }
    Ok((v[0], v[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn poses_points_and_sizes() {
        let p = parse_pose_deg(" 1.5, -2 ,90").unwrap();
        assert_eq!((p.x_m, p.y_m), (1.5, -2.0));
        assert!((p.theta_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
        let e = parse_pose_deg("1,2,x").unwrap_err();
        assert!(e.to_string().contains("\"x\""), "{e}");
        assert!(e.to_string().starts_with("pose \"1,2,x\""), "{e}");
        assert!(matches!(
            parse_pose_deg("1,2,3,4"),
            Err(ScanTypesError::WrongCount {
                expected: 3,
                found: 4,
                ..
            })
        ));
        assert!(parse_pose_deg("1,nan,3").is_err());
        assert!(parse_pose_deg("1,inf,3").is_err());
        assert_eq!(parse_point("4,4").unwrap(), WorldPoint::new(4.0, 4.0));
        assert!(parse_point("4").is_err());
        assert_eq!(parse_size("10, 5").unwrap(), (10.0, 5.0));
        assert!(matches!(
            parse_size("10,-1"),
            Err(ScanTypesError::NotPositive { what: "size", .. })
        ));
    }
}
