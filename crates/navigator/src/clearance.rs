//! Ray clearances beyond what one scan's expansion gives: the robot's width, and hits seen
//! earlier from the same spot that have left the field of view.

use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

/// Cuts `clearances` (one per ray of `geometry`, robot at `pose`) where the disc of radius `r`
/// around a world point of `hits` outside the field of view enters the ray, by the expansion's
/// rule (docs/expansion.md): a robot already inside a disc is blocked at 0 m on every ray
/// within 90 deg of it. Hits inside the field of view are left to the scan.
pub(crate) fn block_by_unseen_hits(
    geometry: &ScanGeometry,
    pose: &Pose2,
    hits: &[WorldPoint],
    r: f64,
    clearances: &mut [f64],
) {
    let n = geometry.ray_count.min(clearances.len());
    let last = (n.max(1) - 1) as f64;
    let dirs = geometry.directions();
    for w in hits {
        let p = pose.inverse_transform_point(*w);
        let f = geometry.fractional_index(p.bearing_rad());
        if (0.0..=last).contains(&f) || p.range_m() == 0.0 {
            continue;
        }
        for (c, u) in clearances[..n].iter_mut().zip(dirs.iter()) {
            let tm = u[0] * p.x_m() + u[1] * p.y_m();
            let side = u[0] * p.y_m() - u[1] * p.x_m();
            let d = r * r - side * side;
            if tm > 0.0 && d >= 0.0 {
                *c = c.min((tm - d.sqrt()).max(0.0));
            }
        }
    }
}

/// `scan` with each hit replaced by the median of it and its two neighbours when all three
/// lie within 0.1 m of each other (one surface): range noise halved for judging passages.
pub(crate) fn denoised(scan: &Scan) -> Scan {
    let mut out = scan.clone();
    for i in 1..scan.len().saturating_sub(1) {
        let (Some(a), Some(b), Some(c)) = (
            scan.hit_range_m(i - 1),
            scan.hit_range_m(i),
            scan.hit_range_m(i + 1),
        ) else {
            continue;
        };
        if a.max(b).max(c) - a.min(b).min(c) <= 0.1 {
            out.ranges_m[i] = a + b + c - a.max(b).max(c) - a.min(b).min(c);
        }
    }
    out
}

/// `out[i]` = the smallest of `c[i - half ..= i + half]` (clamped to the scan): a ray's
/// clearance for the robot's whole width.
pub(crate) fn erode(c: &[f64], half: usize, out: &mut Vec<f64>) {
    out.clear();
    let n = c.len();
    out.extend((0..n).map(|i| {
        c[i.saturating_sub(half)..=(i + half).min(n - 1)]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hits_outside_the_field_of_view_block_the_rays_toward_them() {
        // Paper sensor: 240 deg, rays every 240/684 deg; robot at (1, 1) heading 90 deg.
        let g = ScanGeometry::paper();
        let pose = Pose2::new(1.0, 1.0, 90f64.to_radians());
        let at = |x: f64, y: f64| pose.transform_point(scan_types::RobotPoint::new(x, y));
        let mut c = vec![5.0; g.ray_count];
        // Straight behind at 0.35 m (inside r = 0.4): every ray more than 90 deg off the
        // heading is blocked at once, the others not at all.
        block_by_unseen_hits(&g, &pose, &[at(-0.35, 0.0)], 0.4, &mut c);
        for (i, &ci) in c.iter().enumerate() {
            let b = g.bearing_rad(i).to_degrees();
            if b.abs() > 90.0 + 1e-9 {
                assert_eq!(ci, 0.0, "bearing {b}");
            } else {
                assert_eq!(ci, 5.0, "bearing {b}");
            }
        }
        // (-0.5, -0.6) lies at bearing -129.8 deg, 0.781 m away, outside the view. The ray
        // at -120 deg passes 0.133 m from it (0.5 * 0.6 - 0.866 * 0.5) and meets its 0.4 m
        // disc at 0.5 * 0.5 + 0.866 * 0.6 - sqrt(0.16 - 0.133^2) = 0.392 m.
        let mut c = vec![5.0; g.ray_count];
        block_by_unseen_hits(&g, &pose, &[at(-0.5, -0.6)], 0.4, &mut c);
        assert!((c[0] - 0.392).abs() < 1e-3, "{}", c[0]);
        // The disc spans -129.8 +- asin(0.4 / 0.781) = 30.8 deg: up to -99.0 deg.
        for (i, &ci) in c.iter().enumerate() {
            let b = g.bearing_rad(i).to_degrees();
            assert_eq!(ci < 5.0, b < -99.0, "bearing {b}: {ci}");
        }
        // Hits inside the field of view (bearings 26.6 and 116.6 deg) are the scan's business.
        let mut c = vec![5.0; g.ray_count];
        block_by_unseen_hits(&g, &pose, &[at(0.2, 0.1), at(-0.3, 0.6)], 0.4, &mut c);
        assert!(c.iter().all(|&ci| ci == 5.0));
    }

    #[test]
    fn erosion_takes_the_narrowest_ray_of_the_window() {
        let c = [5.0, 4.0, 3.0, 9.0, 9.0, 9.0, 1.0];
        let mut out = Vec::new();
        erode(&c, 1, &mut out);
        assert_eq!(out, vec![4.0, 3.0, 3.0, 3.0, 9.0, 1.0, 1.0]);
        erode(&c, 0, &mut out);
        assert_eq!(out, c.to_vec());
    }
}
