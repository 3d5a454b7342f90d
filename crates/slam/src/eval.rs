//! Trajectory evaluation against reference poses, as the SLAM literature measures: relative
//! pose errors over relations `k -> k + delta` and the absolute trajectory error after an
//! SE(2) alignment (the figures `evo_rpe` and `evo_ape -a` print for the same TUM files), and
//! the [`median`] and interpolated [`percentile`] that batch tables report.

use scan_types::{Pose2, angle_diff_rad};
use serde::Serialize;

use crate::SlamError;

/// Mean and population standard deviation of a set of errors.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    /// Mean.
    pub mean: f64,
    /// Standard deviation (population).
    pub std: f64,
    /// Root mean square.
    pub rmse: f64,
    /// Largest.
    pub max: f64,
    /// How many.
    pub count: usize,
}

impl Stats {
    /// The statistics of `values` (all zero for none).
    pub fn of(values: &[f64]) -> Stats {
        let n = values.len();
        if n == 0 {
            return Stats {
                mean: 0.0,
                std: 0.0,
                rmse: 0.0,
                max: 0.0,
                count: 0,
            };
        }
        let mean = values.iter().sum::<f64>() / n as f64;
        let var = values.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n as f64;
        let sq = values.iter().map(|v| v * v).sum::<f64>() / n as f64;
        Stats {
            mean,
            std: var.sqrt(),
            rmse: sq.sqrt(),
            max: values.iter().copied().fold(0.0, f64::max),
            count: n,
        }
    }
}

/// The median of `v` (sorted in place); NaN when empty.
pub fn median(v: &mut [f64]) -> f64 {
    percentile(v, 0.5)
}

/// The `q` quantile of `v` (sorted in place), interpolated between ranks; NaN when empty.
pub fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let pos = q * (v.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < v.len() {
        v[i] * (1.0 - f) + v[i + 1] * f
    } else {
        v[i]
    }
}

/// Relative pose errors over the relations `k -> k + delta`: translation (metres) and
/// rotation (degrees) of `(ref_k^-1 ref_k+d)^-1 (est_k^-1 est_k+d)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RelativeError {
    /// The relation's step, in poses.
    pub delta: usize,
    /// Translational error, metres.
    pub translation_m: Stats,
    /// Rotational error, degrees.
    pub rotation_deg: Stats,
}

fn same_length(est: &[Pose2], reference: &[Pose2]) -> Result<(), SlamError> {
    if est.len() != reference.len() {
        return Err(SlamError::LengthMismatch {
            estimate: est.len(),
            reference: reference.len(),
        });
    }
    Ok(())
}

/// The relative pose error of `est` against `reference` (same length, pose for pose).
pub fn relative_error(
    est: &[Pose2],
    reference: &[Pose2],
    delta: usize,
) -> Result<RelativeError, SlamError> {
    same_length(est, reference)?;
    if delta == 0 || est.len() <= delta {
        return Err(SlamError::TooFewPoses {
            what: "a relative error",
            needed: delta.max(1) + 1,
            got: est.len(),
        });
    }
    let (mut t, mut r) = (Vec::new(), Vec::new());
    for k in 0..est.len() - delta {
        let de = est[k].inverse().compose(&est[k + delta]);
        let dr = reference[k].inverse().compose(&reference[k + delta]);
        let e = dr.inverse().compose(&de);
        t.push(e.x_m.hypot(e.y_m));
        r.push(e.theta_rad.abs().to_degrees());
    }
    Ok(RelativeError {
        delta,
        translation_m: Stats::of(&t),
        rotation_deg: Stats::of(&r),
    })
}

/// The rigid motion (rotation, then translation) that best maps `est`'s positions onto
/// `reference`'s, in least squares.
pub fn align_se2(est: &[Pose2], reference: &[Pose2]) -> Result<Pose2, SlamError> {
    same_length(est, reference)?;
    if est.len() < 2 {
        return Err(SlamError::TooFewPoses {
            what: "an alignment",
            needed: 2,
            got: est.len(),
        });
    }
    let n = est.len() as f64;
    let mean = |ps: &[Pose2]| {
        let (x, y) = ps
            .iter()
            .fold((0.0, 0.0), |(x, y), p| (x + p.x_m, y + p.y_m));
        (x / n, y / n)
    };
    let (ex, ey) = mean(est);
    let (rx, ry) = mean(reference);
    // The rotation maximising sum (R e_i) . r_i over centred points.
    let (mut dot, mut cross) = (0.0, 0.0);
    for (e, r) in est.iter().zip(reference) {
        let (ax, ay) = (e.x_m - ex, e.y_m - ey);
        let (bx, by) = (r.x_m - rx, r.y_m - ry);
        dot += ax * bx + ay * by;
        cross += ax * by - ay * bx;
    }
    let theta = cross.atan2(dot);
    let (s, c) = theta.sin_cos();
    Ok(Pose2::new(
        rx - (c * ex - s * ey),
        ry - (s * ex + c * ey),
        theta,
    ))
}

/// The absolute trajectory error: position error (metres) of every pose of `est` after the
/// SE(2) alignment onto `reference`.
pub fn absolute_error(est: &[Pose2], reference: &[Pose2]) -> Result<Stats, SlamError> {
    Ok(Stats::of(&absolute_errors(est, reference)?))
}

/// The position error of each pose after the SE(2) alignment of [`absolute_error`], metres.
pub fn absolute_errors(est: &[Pose2], reference: &[Pose2]) -> Result<Vec<f64>, SlamError> {
    let a = align_se2(est, reference)?;
    Ok(est
        .iter()
        .zip(reference)
        .map(|(e, r)| a.compose(e).position().distance_m(&r.position()))
        .collect())
}

/// Accepted loop closures against reference poses: how many lie outside the bounds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ClosureCheck {
    /// Accepted closures checked.
    pub accepted: usize,
    /// Bound on the translation error, metres.
    pub bound_m: f64,
    /// Bound on the heading error, degrees.
    pub bound_deg: f64,
    /// Accepted closures more than `bound_m` or `bound_deg` off the reference relative pose.
    pub outside: usize,
    /// Of those, the ones within `bound_m` (outside by their heading only).
    pub outside_heading_only: usize,
    /// Largest translation error of an accepted closure, metres.
    pub worst_m: f64,
    /// Largest heading error of an accepted closure, degrees.
    pub worst_deg: f64,
}

/// Checks each accepted closure `(from, to, measured)` (the pose of scan `to` in the frame of
/// scan `from`) against the relative pose of `reference[from]` and `reference[to]`; `None`
/// when a closure names a scan without a reference pose.
pub fn closure_check(
    closures: &[(usize, usize, Pose2)],
    reference: &[Pose2],
    bound_m: f64,
    bound_deg: f64,
) -> Option<ClosureCheck> {
    let mut c = ClosureCheck {
        accepted: closures.len(),
        bound_m,
        bound_deg,
        outside: 0,
        outside_heading_only: 0,
        worst_m: 0.0,
        worst_deg: 0.0,
    };
    for (from, to, measured) in closures {
        let want = reference.get(*from)?.inverse().compose(reference.get(*to)?);
        let e = want.inverse().compose(measured);
        let (m, deg) = (e.x_m.hypot(e.y_m), e.theta_rad.abs().to_degrees());
        c.worst_m = c.worst_m.max(m);
        c.worst_deg = c.worst_deg.max(deg);
        if m > bound_m || deg > bound_deg {
            c.outside += 1;
            if m <= bound_m {
                c.outside_heading_only += 1;
            }
        }
    }
    Some(c)
}

/// The heading difference of two poses, degrees (for reports).
pub fn heading_error_deg(a: &Pose2, b: &Pose2) -> f64 {
    angle_diff_rad(a.theta_rad, b.theta_rad).abs().to_degrees()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_hand() {
        let mut v = vec![4.0, 1.0, 3.0, 2.0];
        assert_eq!(median(&mut v), 2.5);
        let mut v = vec![0.0, 10.0];
        assert!((percentile(&mut v, 0.9) - 9.0).abs() < 1e-12);
        assert!(median(&mut []).is_nan());
    }

    #[test]
    fn relative_error_of_a_hand_made_pair() {
        // The reference steps 1 m ahead each time; the estimate steps 1.1 m: every relation
        // k -> k+1 is 0.1 m off, k -> k+2 0.2 m, with no rotation error.
        let reference: Vec<Pose2> = (0..5).map(|i| Pose2::new(i as f64, 0.0, 0.0)).collect();
        let est: Vec<Pose2> = (0..5)
            .map(|i| Pose2::new(1.1 * i as f64, 0.0, 0.0))
            .collect();
        let r1 = relative_error(&est, &reference, 1).unwrap();
        assert!((r1.translation_m.mean - 0.1).abs() < 1e-12);
        assert!(r1.translation_m.std < 1e-12);
        assert_eq!(r1.translation_m.count, 4);
        let r2 = relative_error(&est, &reference, 2).unwrap();
        assert!((r2.translation_m.mean - 0.2).abs() < 1e-12);
        assert!(r2.rotation_deg.max < 1e-12);
        assert!(relative_error(&est, &reference[..4], 1).is_err());
        assert!(relative_error(&est, &reference, 5).is_err());
    }

    #[test]
    fn alignment_undoes_a_rigid_motion() {
        // A square path moved by 30 deg and (2, -1): aligned, the error vanishes.
        let reference: Vec<Pose2> = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)]
            .iter()
            .map(|&(x, y)| Pose2::new(x, y, 0.0))
            .collect();
        let m = Pose2::new(2.0, -1.0, 30f64.to_radians());
        let est: Vec<Pose2> = reference.iter().map(|p| m.compose(p)).collect();
        let a = align_se2(&est, &reference).unwrap();
        assert!(
            a.compose(&m)
                .position()
                .distance_m(&Pose2::default().position())
                < 1e-12
        );
        assert!(absolute_error(&est, &reference).unwrap().max < 1e-12);
        // Unaligned the first pose would be sqrt(5) m off.
        assert!(
            (est[0].position().distance_m(&reference[0].position()) - 5f64.sqrt()).abs() < 1e-12
        );
    }

    #[test]
    fn closures_outside_the_bounds_are_counted() {
        // References: scan 1 is 2 m ahead of scan 0, turned 90 deg.
        let reference = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(2.0, 0.0, std::f64::consts::FRAC_PI_2),
        ];
        let turn = std::f64::consts::FRAC_PI_2;
        let closures = [
            // Exact.
            (0, 1, Pose2::new(2.0, 0.0, turn)),
            // 0.1 m and 1.5 deg off: inside.
            (0, 1, Pose2::new(2.1, 0.0, turn + 1.5f64.to_radians())),
            // 0.3 m off.
            (0, 1, Pose2::new(2.0, 0.3, turn)),
            // 2.5 deg off, position exact: outside by its heading only.
            (0, 1, Pose2::new(2.0, 0.0, turn - 2.5f64.to_radians())),
        ];
        let c = closure_check(&closures, &reference, 0.2, 2.0).unwrap();
        assert_eq!((c.accepted, c.outside, c.outside_heading_only), (4, 2, 1));
        assert!((c.worst_m - 0.3).abs() < 1e-9, "{c:?}");
        assert!((c.worst_deg - 2.5).abs() < 1e-9, "{c:?}");
        // Seen from scan 1, scan 0 is 2 m to its left and turned -90 deg: (0, 2, -90 deg) in
        // scan 1's frame (x ahead is +y of the world).
        let back = [(1, 0, Pose2::new(0.0, 2.0, -turn))];
        assert_eq!(
            closure_check(&back, &reference, 0.2, 2.0).unwrap().outside,
            0
        );
        assert!(closure_check(&[(0, 2, Pose2::default())], &reference, 0.2, 2.0).is_none());
    }

    #[test]
    fn per_pose_errors_after_the_alignment() {
        // The estimate (0, 0.05) .. (2, -0.05) against the reference (0, 0) .. (2, 0).
        let reference = [Pose2::new(0.0, 0.0, 0.0), Pose2::new(2.0, 0.0, 0.0)];
        let est = [Pose2::new(0.0, 0.05, 0.0), Pose2::new(2.0, -0.05, 0.0)];
        let e = absolute_errors(&est, &reference).unwrap();
        assert_eq!(e.len(), 2);
        // The fit rotates the estimate onto the line: the chord of length sqrt(4 + 0.01)
        // centred on (1, 0), so each end lies (sqrt(4.01) - 2) / 2 m beyond its reference.
        let off = (4.01f64.sqrt() - 2.0) / 2.0;
        assert!(
            (e[0] - off).abs() < 1e-9 && (e[1] - off).abs() < 1e-9,
            "{e:?}"
        );
        assert!((absolute_error(&est, &reference).unwrap().rmse - off).abs() < 1e-9);
    }
}
