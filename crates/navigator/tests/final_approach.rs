//! `[navigator] final_approach_m`: an arrival within the goal tolerance but not at the target
//! first turns to the target and drives to it, once.

use navigator::{Action, Navigator, Params, Reason};
use scan_types::testkit::boxed;
use scan_types::{Pose2, ScanGeometry, WorldPoint};

#[path = "common/base.rs"]
mod base;
#[path = "common/stored.rs"]
mod stored;

/// The target 3 m to the left of the start, in a 6 m x 7 m room whose walls measure every turn.
const GOAL: (f64, f64) = (0.0, 3.0);

/// The base turns 2 % more than it is told: the 90 deg turn to the target is 91.8 deg, which
/// the scans measure. The target then lies 1.8 deg off the heading, within the final leg's
/// 3 deg, so the final leg drives straight on and ends 3 sin(1.8 deg) = 0.094 m beside the
/// target, inside the 0.15 m tolerance.
const TURN_SCALE: f64 = 1.02;

/// Runs from the origin, heading along x; the end, the true pose and the legs driven.
fn run(final_approach_m: f64) -> (Action, Pose2, usize) {
    let mut p = Params::goalseek();
    p.navigator.final_approach_m = final_approach_m;
    let start = Pose2::new(0.0, 0.0, 0.0);
    let goal = WorldPoint::new(GOAL.0, GOAL.1);
    let mut nav = Navigator::new(p, ScanGeometry::paper(), start, goal).unwrap();
    let room = boxed(-3.0, -2.0, 3.0, 5.0);
    let truth = base::drive(&mut nav, &room, start, (TURN_SCALE, 1.0), |_| {});
    (nav.pending(), truth, nav.legs().len())
}

#[test]
fn an_arrival_beside_the_target_drives_onto_it() {
    let goal = WorldPoint::new(GOAL.0, GOAL.1);
    let beside = 3.0 * (0.02 * 90f64).to_radians().sin();
    // Off: the run ends where the straight leg did, beside the target.
    let (end, truth, legs_off) = run(0.0);
    assert_eq!(end, Action::Finish(Reason::Reached));
    let miss = truth.position().distance_m(&goal);
    assert!((miss - beside).abs() < 0.005, "{miss:.4} m from the target");
    // On (0.05 m): one more leg, turned onto the target, ends on it.
    let (end, truth, legs_on) = run(0.05);
    assert_eq!(end, Action::Finish(Reason::Reached));
    let miss = truth.position().distance_m(&goal);
    assert!(miss < 0.01, "{miss:.4} m from the target");
    assert_eq!(legs_on, legs_off + 1);
    // An approach only from farther than 0.1 m: none.
    let (_, truth, legs) = run(0.1);
    assert_eq!(legs, legs_off);
    assert!((truth.position().distance_m(&goal) - beside).abs() < 0.005);
}

#[test]
fn a_stored_configuration_without_the_key_makes_no_approach() {
    let (old, removed) = stored::without("navigator", &["final_approach_m"]);
    assert_eq!(removed, [serde_json::json!(0.05)]);
    assert_eq!(old.navigator.final_approach_m, 0.0);
    assert_eq!(Params::paper().navigator.final_approach_m, 0.0);
    let mut bad = Params::goalseek();
    bad.navigator.final_approach_m = -1.0;
    let err = bad.validate().unwrap_err().to_string();
    assert!(err.contains("navigator.final_approach_m"), "{err}");
}
