//! `[navigator] blocked_target_plans`: a target closer to a wall than the robot may stand is
//! reached at the nearest place clear of the wall, instead of being circled until the leg
//! limit.

use navigator::{Navigator, Params, Reason};
use scan_types::testkit::{Seg, boxed};
use scan_types::{Pose2, ScanGeometry, WorldPoint};

#[path = "common/base.rs"]
mod base;

/// The room's east wall, x metres.
const WALL_X: f64 = 6.0;
/// The target's distance from that wall, metres: less than r = 0.3 m.
const GAP_M: f64 = 0.15;

/// Drives an exact base from the room's west end toward a target `GAP_M` from the east wall;
/// the outcome and the true pose at the end.
fn run(blocked_target_plans: usize) -> (navigator::Outcome, Pose2) {
    let mut p = Params::goalseek();
    p.navigator.blocked_target_plans = blocked_target_plans;
    let segs: Vec<Seg> = boxed(-1.0, -3.0, WALL_X, 3.0);
    let start = Pose2::new(0.0, 0.0, 0.0);
    let goal = WorldPoint::new(WALL_X - GAP_M, 0.5);
    let mut nav = Navigator::new(p, ScanGeometry::paper(), start, goal).unwrap();
    let end = base::drive(&mut nav, &segs, start, (1.0, 1.0), |_| {});
    (nav.into_outcome(), end)
}

#[test]
fn a_target_beside_a_wall_is_reached_at_the_nearest_clear_place() {
    let p = Params::goalseek();
    let (r, full) = (p.robot.radius_m, p.expansion_radius_m());
    let tolerance = p.navigator.goal_tolerance_m;
    // The memory's cells are 0.1 m: a hit's cell centre lies within 0.05 sqrt 2 of the hit.
    let cell = p.planner.grid_resolution_m / std::f64::consts::SQRT_2;
    // The target lies more than the tolerance inside the full clearance (0.4 - 0.15 - 0.071),
    // so the estimate can never come within the tolerance of it.
    assert!(full - GAP_M - cell > tolerance);

    let (on, end) = run(p.navigator.blocked_target_plans);
    assert_eq!(on.reason, Reason::Reached, "{}", on.note);
    assert!(on.note.contains("nearest place clear"), "{}", on.note);
    // No contact: the centre stays r from the wall. Ended within the tolerance of the nearest
    // place the full clearance leaves, (full - gap) from the target, up to a cell.
    assert!(WALL_X - end.x_m >= r, "{end:?}");
    let off = (end.x_m - (WALL_X - GAP_M)).hypot(end.y_m - 0.5);
    assert!(
        off <= full - GAP_M + cell + tolerance,
        "{off:.3} m: {end:?}"
    );
    assert!(off > tolerance, "{off:.3} m");

    // Without the rule the run circles the place it cannot stand on until its leg limit.
    let (off_rule, _) = run(0);
    assert_eq!(off_rule.reason, Reason::LegLimit, "{}", off_rule.note);
    assert!(
        on.legs_driven < off_rule.legs_driven / 4,
        "{} legs",
        on.legs_driven
    );
}
