//! A whole leg on hand-built scans: a landmark detected, tracked step by step and the arrival
//! at its point B checked, the pieces the navigator combines.

use landmarks::{DetectParams, TrackParams, TrackUpdate, Tracker, detect};
use localiser::{ArrivalParams, check_arrival, triangle};
use scan_types::testkit::{boxed, scan_at};
use scan_types::{Pose2, ScanGeometry, WorldPoint};

#[test]
fn whole_leg_on_hand_built_scans() {
    // Box x 2..3, y 1..2; the robot starts at the origin facing +x and drives in 5 cm steps.
    // It selects the silhouette edge (3, 1), tracks it, and arrives near B = (3, 0).
    let g = ScanGeometry::paper();
    let walls = boxed(2.0, 1.0, 3.0, 2.0);
    let first = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let l = *detect(&g, &first, &DetectParams::default())
        .iter()
        .find(|l| !l.hidden_at_side && l.kind == landmarks::LandmarkKind::MaxRangeJump)
        .unwrap();
    let o = Pose2::new(0.0, 0.0, 0.0);
    let t = triangle(&o, l.range_m, l.bearing_rad);
    assert!(
        t.point_b.distance_m(&WorldPoint::new(3.0, 0.0)) < 0.04,
        "{t:?}"
    );
    for params in [ArrivalParams::default(), ArrivalParams::paper()] {
        let mut tracker = Tracker::new(l, TrackParams::default());
        let mut arrived = None;
        for k in 1..=80 {
            let d = 0.05 * k as f64;
            let scan = scan_at(&g, &walls, d, 0.0, 0.0);
            let seen = match tracker.update(&g, &scan, d) {
                TrackUpdate::Tracked(s) => s,
                TrackUpdate::Predicted(_) => continue,
                TrackUpdate::Lost => break,
            };
            if let Some(a) = check_arrival(&t, &g, seen.range_m, seen.bearing_rad, &params) {
                arrived = Some((a, d));
                break;
            }
        }
        let (a, truth) = arrived.expect("arrived");
        // The estimate agrees with the true distance within the edge quantisation (4 cm).
        assert!((a.travelled_m - truth).abs() < 0.04, "{a:?} truth {truth}");
        assert!((truth - 3.0).abs() <= 0.15, "arrived at {truth}");
    }
}
