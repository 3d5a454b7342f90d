//! `[planner] replan_step_m`: a leg into a dead end whose back wall comes into view only while
//! driving ends when the wall is seen.

use navigator::{Action, Navigator, Params, Reason};
use scan_types::testkit::{Seg, boxed};
use scan_types::{Pose2, ScanGeometry, WorldPoint};

#[path = "common/base.rs"]
mod base;

/// The paper's laser reads at most this far, metres.
const MAX_RANGE_M: f64 = 4.0;
/// The pocket's back wall, x metres.
const BACK_X: f64 = 8.0;

/// A 12 m x 6 m room with a pocket 1.4 m wide open toward the start: side walls y = +-0.7
/// from x = 2 to the back wall at x = 8. The target (10, 0) lies behind the back wall.
fn world() -> Vec<Seg> {
    let mut segs = boxed(-1.0, -3.0, 11.0, 3.0);
    segs.push(((2.0, 0.7), (BACK_X, 0.7)));
    segs.push(((2.0, -0.7), (BACK_X, -0.7)));
    segs.push(((BACK_X, -0.7), (BACK_X, 0.7)));
    segs
}

/// Drives an exact base from (0.9, 0) facing the pocket until the run ends; how it ended,
/// the farthest x the robot reached and the legs cut short.
fn run(replan_step_m: f64) -> (Action, f64, usize) {
    let mut p = Params::goalseek();
    p.planner.replan_step_m = replan_step_m;
    // Long legs: without a landmark in the bare pocket a leg would end after 1 m anyway.
    p.navigator.short_leg_m = 3.0;
    let segs = world();
    let g = ScanGeometry::paper();
    assert_eq!(g.max_range_m, MAX_RANGE_M);
    let start = Pose2::new(0.9, 0.0, 0.0);
    let mut nav = Navigator::new(p, g, start, WorldPoint::new(10.0, 0.0)).unwrap();
    let mut farthest = start.x_m;
    base::drive(&mut nav, &segs, start, (1.0, 1.0), |t| {
        // Inside the pocket only (the target lies behind it).
        if t.y_m.abs() < 0.7 && t.x_m < BACK_X {
            farthest = farthest.max(t.x_m);
        }
    });
    (nav.pending(), farthest, nav.legs_cut_short())
}

#[test]
#[allow(clippy::print_stdout)]
fn a_leg_into_a_dead_end_ends_when_its_back_wall_is_seen() {
    let step = 0.25;
    let (end_on, far_on, cut_on) = run(step);
    let (end_off, far_off, cut_off) = run(0.0);
    println!(
        "on: {end_on:?} farthest x {far_on:.2} cut {cut_on}; off: {end_off:?} farthest x {far_off:.2} cut {cut_off}"
    );
    assert_eq!(end_on, Action::Finish(Reason::Reached));
    assert_eq!(end_off, Action::Finish(Reason::Reached));
    assert_eq!(cut_off, 0);
    assert!(cut_on >= 1);
    // The back wall is in range once the robot is past x = 8 - 4 = 4. The next check comes
    // within one replan step of travel and ends the leg; a leg with less than a step left
    // is not checked but ends within that step: no farther than x = 4 + 2 x 0.25.
    let bound = BACK_X - MAX_RANGE_M + 2.0 * step;
    assert!(far_on <= bound + 1e-6, "on: {far_on:.3} > {bound:.3}");
    // Without the check a leg started before the wall came into view runs to its end (3 m
    // from the start of the leg into the pocket), beyond that bound.
    assert!(far_off > bound, "off: {far_off:.3}");
}
