//! `[navigator] skip_turn_below_deg`: a turn of a few degrees onto a ray is left out when the
//! scan holds too little to measure it and the way straight ahead is as clear, since a base's
//! turn error does not shrink with the turn.

use navigator::{Action, Navigator, Params, Reason};
use scan_types::testkit::boxed;
use scan_types::{Pose2, ScanGeometry, WorldPoint};

#[path = "common/base.rs"]
mod base;

/// A 40 m x 30 m hall: from its middle nothing lies within the 4 m range.
fn hall() -> Vec<scan_types::testkit::Seg> {
    boxed(-20.0, -15.0, 20.0, 15.0)
}

/// The target 10 m ahead and 0.35 m to the left: atan(0.35 / 10) = 2.0 deg off the heading.
/// The plan's ray toward it is a few degrees off too (its end's path on a 0.1 m grid).
const GOAL: (f64, f64) = (10.0, 0.35);

/// Turns under this are left out in these tests (goalseek's default is 4 deg), degrees.
const SKIP_DEG: f64 = 8.0;

fn navigator(skip_deg: f64) -> Navigator {
    navigator_with(skip_deg, Params::goalseek().navigator.skip_turn_max_hits)
}

/// [`navigator`] whose scans measure a turn from `max_hits` hits on.
fn navigator_with(skip_deg: f64, max_hits: usize) -> Navigator {
    let mut p = Params::goalseek();
    p.navigator.skip_turn_below_deg = skip_deg;
    p.navigator.skip_turn_max_hits = max_hits;
    Navigator::new(
        p,
        ScanGeometry::paper(),
        Pose2::new(0.0, 0.0, 0.0),
        WorldPoint::new(GOAL.0, GOAL.1),
    )
    .unwrap()
}

/// The hall with a long wall 1 m to the right of the start, along the way.
fn hall_with_wall() -> Vec<scan_types::testkit::Seg> {
    let mut segs = hall();
    segs.push(((-19.0, -1.0), (19.0, -1.0)));
    segs
}

/// The first motion `nav` asks for, fed scans of `segs` from the start.
fn first_motion(nav: &mut Navigator, segs: &[scan_types::testkit::Seg]) -> Action {
    let g = *nav.geometry();
    let scan = scan_types::testkit::scan_at(&g, segs, 0.0, 0.0, 0.0);
    let mut action = nav.pending();
    while action == Action::Scan {
        action = nav.on_scan(&scan);
    }
    action
}

#[test]
fn a_small_turn_in_the_open_is_not_made() {
    // Every turn made: the plan turns onto its ray toward the target, under SKIP_DEG.
    match first_motion(&mut navigator(0.0), &hall()) {
        Action::Rotate { angle_rad } => {
            let deg = angle_rad.to_degrees();
            assert!(deg.abs() > 0.0 && deg.abs() < SKIP_DEG, "{deg} deg");
        }
        other => panic!("expected a turn, got {other:?}"),
    }
    // Turns under SKIP_DEG left out: the first motion is the drive, straight ahead.
    let mut nav = navigator(SKIP_DEG);
    assert!(
        matches!(first_motion(&mut nav, &hall()), Action::Forward { distance_m } if distance_m > 0.0),
        "expected a drive"
    );
}

#[test]
fn a_small_turn_the_laser_can_measure_is_made() {
    // The wall 1 m to the right is hit by every ray from -120 deg to -14.5 deg (asin(1 / 4):
    // the 4 m range), about 300 hits, more than the 60 that make a turn measurable.
    match first_motion(&mut navigator(SKIP_DEG), &hall_with_wall()) {
        Action::Rotate { angle_rad } => {
            let deg = angle_rad.to_degrees();
            assert!(deg.abs() > 0.0 && deg.abs() < SKIP_DEG, "{deg} deg");
        }
        other => panic!("expected a turn, got {other:?}"),
    }
    // The same wall, with a turn counted as measurable only from 1 000 hits: left out.
    let mut nav = navigator_with(SKIP_DEG, 1000);
    assert!(
        matches!(
            first_motion(&mut nav, &hall_with_wall()),
            Action::Forward { .. }
        ),
        "expected a drive"
    );
}

#[test]
fn a_run_that_skips_small_turns_still_arrives() {
    // On an exact base the run ends where the estimate says: within the goal tolerance
    // (0.15 m) of the target, the final leg turned onto the target itself. Its first drive
    // keeps the start's heading (the turn left out); with every turn made it does not.
    let first_heading = |skip_deg: f64| {
        let mut nav = navigator(skip_deg);
        let mut first = None;
        let start = Pose2::new(0.0, 0.0, 0.0);
        let truth = base::drive(&mut nav, &hall(), start, (1.0, 1.0), |p| {
            first.get_or_insert(p.theta_rad);
        });
        assert_eq!(nav.pending(), Action::Finish(Reason::Reached));
        (first.unwrap(), truth)
    };
    assert_ne!(first_heading(0.0).0, 0.0);
    let (heading, truth) = first_heading(SKIP_DEG);
    assert_eq!(heading, 0.0);
    let miss = truth
        .position()
        .distance_m(&WorldPoint::new(GOAL.0, GOAL.1));
    assert!(miss <= 0.15, "{miss:.3} m from the target");
}
