//! The paper's world reproduces the paper's first scan (section 5).

use scan_types::{Pose2, RayStatus, ScanGeometry, WorldPoint};
use sim_laser::{SensorPreset, World, true_scan};

/// Hit points at max-range jumps: for each neighbouring pair of rays where one is a miss and the
/// other a hit, the hit's world point.
fn max_range_jumps(pose: &Pose2, g: &ScanGeometry, world: &World) -> Vec<WorldPoint> {
    let scan = true_scan(world, pose, g);
    let mut out = Vec::new();
    for i in 0..scan.len() - 1 {
        let (a, b) = (scan.status[i], scan.status[i + 1]);
        let hit = match (a, b) {
            (RayStatus::MaxRange, RayStatus::Hit) => i + 1,
            (RayStatus::Hit, RayStatus::MaxRange) => i,
            _ => continue,
        };
        out.push(pose.transform_point(g.robot_point(hit, scan.ranges_m[hit])));
    }
    out
}

#[test]
fn paper_start_sees_six_jumps_nearest_at_papers_point() {
    let world = World::paper();
    let pose = sim_laser::paper_start();
    let g = SensorPreset::Paper.geometry();
    let jumps = max_range_jumps(&pose, &g, &world);
    assert_eq!(jumps.len(), 6, "jumps: {jumps:?}");
    let nearest = jumps
        .iter()
        .min_by(|a, b| {
            a.distance_m(&pose.position())
                .total_cmp(&b.distance_m(&pose.position()))
        })
        .unwrap();
    let paper = WorldPoint::new(-2.38, -2.06);
    assert!(
        nearest.distance_m(&paper) < 0.08,
        "nearest jump at {nearest:?}, paper says (-2.38, -2.06)"
    );
}

#[test]
fn paper_world_bounds_and_boundary_wall() {
    let w = World::paper();
    let (lo, hi) = w.bounds();
    assert!((lo.x_m() + 5.0).abs() < 1e-9 && (lo.y_m() + 5.0).abs() < 1e-9);
    assert!((hi.x_m() - 5.0).abs() < 1e-9 && (hi.y_m() - 5.0).abs() < 1e-9);
    // 0.02 m cells: the boundary ring's inner faces are at +-4.98 m; nothing is hit beyond.
    for k in 0..360 {
        let a = (k as f64).to_radians();
        let r = w.raycast(WorldPoint::new(0.1, 0.1), a, 100.0);
        let r = r.expect("the boundary encloses the world");
        assert!(r < 4.98 * 2f64.sqrt() + 0.2, "ray {k} deg went {r} m");
    }
}
