//! Test scenes for the scan matcher: ray-cast scans of wall segments.

use scan_types::{Pose2, Scan, ScanGeometry};

/// Ray-casts `segments` from `pose` with the paper's geometry (no noise unless `noise`).
pub(super) fn cast(segments: &[[f64; 4]], pose: Pose2, noise: Option<u64>) -> Scan {
    let g = ScanGeometry::paper();
    let walls: Vec<scan_types::testkit::Seg> = segments
        .iter()
        .map(|s| ((s[0], s[1]), (s[2], s[3])))
        .collect();
    let mut rng = scan_types::testkit::Noise::new(noise.unwrap_or(0));
    let ranges: Vec<f64> = (0..g.ray_count)
        .map(|i| {
            let a = pose.theta_rad + g.bearing_rad(i);
            let best = scan_types::testkit::raycast(&walls, pose.x_m, pose.y_m, a)
                .map_or(g.max_range_m, |t| t.min(g.max_range_m));
            if noise.is_some() && best < g.max_range_m {
                // Uniform noise of standard deviation 1 cm.
                best + (rng.uniform() - 0.5) * 0.01 * 12f64.sqrt()
            } else {
                best
            }
        })
        .collect();
    Scan::from_ranges(&g, &ranges, 0.0)
}

/// A 6 m x 4 m room centred on the origin with a 0.6 m box at (1.5, 1.0).
pub(super) fn room() -> Vec<[f64; 4]> {
    vec![
        [-3.0, -2.0, 3.0, -2.0],
        [3.0, -2.0, 3.0, 2.0],
        [3.0, 2.0, -3.0, 2.0],
        [-3.0, 2.0, -3.0, -2.0],
        [1.2, 0.7, 1.8, 0.7],
        [1.8, 0.7, 1.8, 1.3],
        [1.8, 1.3, 1.2, 1.3],
        [1.2, 1.3, 1.2, 0.7],
    ]
}
