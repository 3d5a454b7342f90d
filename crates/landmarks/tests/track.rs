//! Tracking on hand-built scans: a robot driving past a box.

use landmarks::{DetectParams, TrackParams, TrackUpdate, Tracker, detect};
use scan_types::testkit::{boxed, noisy, scan_at};
use scan_types::{ScanGeometry, WorldPoint};

/// The right silhouette edge (3, 1) of the box x 2..3, y 1..2 seen from the origin.
fn start() -> (
    ScanGeometry,
    Vec<scan_types::testkit::Seg>,
    landmarks::Landmark,
) {
    let g = ScanGeometry::paper();
    let walls = boxed(2.0, 1.0, 3.0, 2.0);
    let scan = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let found = detect(&g, &scan, &DetectParams::default());
    let l = *found
        .iter()
        .find(|l| {
            let p = l.robot_point();
            WorldPoint::new(p.x_m(), p.y_m()).distance_m(&WorldPoint::new(3.0, 1.0)) < 0.03
        })
        .expect("edge (3, 1)");
    (g, walls, l)
}

#[test]
fn follows_an_edge_to_the_side_ray_and_past_it() {
    let (g, walls, l) = start();
    let mut tracker = Tracker::new(l, TrackParams::default());
    // The base really drives 2 % further than it is told (drive scale noise).
    let mut tracked = 0;
    for k in 1..=66 {
        let told = 0.05 * k as f64;
        let truth = 1.02 * told;
        let scan = noisy(&g, &scan_at(&g, &walls, truth, 0.0, 0.0), 0.01, k);
        match tracker.update(&g, &scan, told) {
            TrackUpdate::Tracked(t) => {
                tracked += 1;
                // In the true robot frame the edge is at (3 - truth, 1).
                let p = t.robot_point();
                let err = WorldPoint::new(p.x_m() + truth, p.y_m())
                    .distance_m(&WorldPoint::new(3.0, 1.0));
                // An edge ray's hit lies up to one ray spacing along the face y = 1 from
                // the true end: r^2 * increment / 1 m at range r (6 cm at 3.16 m).
                let r = (3.0 - truth).hypot(1.0);
                let along = r * r * g.increment_rad;
                assert!(err < along + 0.03, "step {k}: error {err} m, {t:?}");
            }
            TrackUpdate::Predicted(_) => {}
            TrackUpdate::Lost => panic!("lost at step {k}"),
        }
    }
    // Past x = 3 (bearing > 90 deg) the edge turns into a corner; it stays tracked.
    assert!(tracked >= 60, "tracked {tracked} of 66");
    assert!(tracker.last().bearing_rad > std::f64::consts::FRAC_PI_2);
}

#[test]
fn landmark_that_vanishes_mid_leg_is_reported_lost() {
    let (g, walls, l) = start();
    let mut tracker = Tracker::new(l, TrackParams::default());
    for k in 1..=10 {
        let d = 0.1 * k as f64;
        let scan = scan_at(&g, &walls, d, 0.0, 0.0);
        assert!(matches!(
            tracker.update(&g, &scan, d),
            TrackUpdate::Tracked(_)
        ));
    }
    // The box is carried away: the tracker coasts on its prediction.
    let empty = scan_at(&g, &[], 1.1, 0.0, 0.0);
    match tracker.update(&g, &empty, 1.1) {
        TrackUpdate::Predicted(p) => {
            // The prediction: (3 - 1.1, 1) in the robot frame.
            assert!((p.robot_point().x_m() - 1.9).abs() < 0.03);
            assert!((p.robot_point().y_m() - 1.0).abs() < 0.03);
        }
        other => panic!("expected a prediction, got {other:?}"),
    }
    // Two more predictions (max_missed_scans = 3), then lost.
    for d in [1.2, 1.3] {
        assert!(matches!(
            tracker.update(&g, &empty, d),
            TrackUpdate::Predicted(_)
        ));
    }
    assert_eq!(tracker.misses(), 3);
    assert_eq!(tracker.update(&g, &empty, 1.4), TrackUpdate::Lost);
    assert!(tracker.is_lost());
    // Once lost, always lost, even if the box comes back.
    let back = scan_at(&g, &walls, 1.5, 0.0, 0.0);
    assert_eq!(tracker.update(&g, &back, 1.5), TrackUpdate::Lost);
}

#[test]
fn gate_refuses_a_feature_that_jumped() {
    let (g, _, l) = start();
    let params = TrackParams {
        max_missed_scans: 0,
        ..TrackParams::default()
    };
    let mut tracker = Tracker::new(l, params);
    // The box is now 30 cm further on: its edge lies 30 cm from the prediction, far
    // outside the 6 cm gate (+0.3 cm growth for 0.1 m driven).
    let moved = boxed(2.3, 1.0, 3.3, 2.0);
    let scan = scan_at(&g, &moved, 0.1, 0.0, 0.0);
    assert_eq!(tracker.update(&g, &scan, 0.1), TrackUpdate::Lost);
    // With a 40 cm gate it is accepted.
    let wide = TrackParams {
        gate_m: 0.4,
        ..params
    };
    let mut t2 = Tracker::new(l, wide);
    assert!(matches!(t2.update(&g, &scan, 0.1), TrackUpdate::Tracked(_)));
    // The point fallback accepts any hit near the prediction: here a point on the face
    // y = 1 where no edge is (why it is off by default).
    let sliding = TrackParams {
        point_fallback: true,
        ..params
    };
    let mut t3 = Tracker::new(l, sliding);
    match t3.update(&g, &scan, 0.1) {
        TrackUpdate::Tracked(t) => assert!((t.robot_point().y_m() - 1.0).abs() < 0.03),
        other => panic!("{other:?}"),
    }
}

#[test]
fn a_wall_running_out_of_range_gives_no_fix() {
    // A wall along y = -1.5: its last hit before the 4 m range lies sqrt(4^2 - 1.5^2) = 3.708 m
    // ahead whatever the robot's x, so it moves with the robot.
    let g = ScanGeometry::paper();
    let wall = vec![((-20.0, -1.5), (20.0, -1.5))];
    let scan = scan_at(&g, &wall, 0.0, 0.0, 0.0);
    let found = detect(&g, &scan, &DetectParams::default().permissive());
    let l = *found
        .iter()
        .find(|l| (l.robot_point().x_m() - 3.708).abs() < 0.05)
        .expect("the wall's last hit");
    assert!(l.near_range_limit, "{l:?}");
    let sliding = TrackParams {
        reject_near_range_limit: false,
        ..TrackParams::default()
    };
    let (mut off, mut on) = (
        Tracker::new(l, sliding),
        Tracker::new(l, TrackParams::default()),
    );
    let mut last_x = None;
    for k in 1..=10 {
        let told = 0.05 * k as f64;
        let scan = scan_at(&g, &wall, told, 0.0, 0.0);
        // Without the rule it is re-identified where it was: no travel after 0.5 m.
        match off.update(&g, &scan, told) {
            TrackUpdate::Tracked(t) => last_x = Some(t.robot_point().x_m()),
            other => panic!("step {k}: {other:?}"),
        }
        assert!(!matches!(
            on.update(&g, &scan, told),
            TrackUpdate::Tracked(_)
        ));
    }
    let x = last_x.unwrap();
    assert!((x - 3.708).abs() < 0.05, "{x}");
    assert!(on.is_lost());
}
