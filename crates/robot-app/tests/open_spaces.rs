//! Open spaces (issue 18): clutter-only worlds, where a drive's scan match against a lone post
//! or a short wall can turn the estimate although the base drives straight.

use std::sync::Arc;

use robot_app::cmd::sim::{SimSpec, simulate_with_geodesic};
use robot_app::config::{Method, Params};
use robot_app::outputs::Reason;
use sim_laser::{SimSetup, WorldKind, generated_world};

/// The run in clutter world `k` (its own start and target, noise seed 0) with goalseek's
/// defaults changed by `change`.
fn run(k: u64, change: impl FnOnce(&mut Params)) -> robot_app::outputs::Summary {
    run_seeded(k, 0, change)
}

/// [`run`] with noise seed `seed`.
fn run_seeded(k: u64, seed: u64, change: impl FnOnce(&mut Params)) -> robot_app::outputs::Summary {
    let (world, start, goal) = generated_world(WorldKind::Clutter, k).unwrap();
    let setup = SimSetup {
        start,
        seed,
        ..SimSetup::new(Arc::new(world), format!("clutter-{k}"))
    };
    let mut p = Params::preset(Method::Goalseek);
    change(&mut p);
    simulate_with_geodesic(&SimSpec::new(setup, goal, p), None)
        .unwrap()
        .summary
}

/// The drive and turn rules before the drive's heading prior and the skipped small turns, the
/// rays ranked by their grid path alone, partial travel taken at 0.05 m, travel measured on a
/// post's edge and every ray shift taken as if matched.
fn old_rules(p: &mut Params) {
    p.tracking.round_centre = false;
    p.localiser.drive_turn_sigma_deg = 2.0;
    p.localiser.partial_travel_max_sigma_m = 0.05;
    p.navigator.skip_turn_below_deg = 0.0;
    p.planner.line_of_sight = false;
    p.localiser.ray_shift_max_sigmas = 0.0;
    p.localiser.ray_shift_alone_sigma_deg = 0.2;
}

/// The median absolute final heading error over clutter worlds 0..20 (noise seed 0), degrees.
fn median_heading_error(change: impl Fn(&mut Params)) -> f64 {
    let mut errors: Vec<f64> = (0..20)
        .map(|k| run(k, &change).final_heading_error_deg.unwrap().abs())
        .collect();
    errors.sort_by(f64::total_cmp);
    (errors[9] + errors[10]) / 2.0
}

#[test]
fn a_straight_drive_keeps_its_heading_in_open_clutter() {
    // The simulator's base never turns while driving forward. Accepting matches that turn the
    // robot (180 deg: any) let one leg's match add 6-10 deg of heading error, and the run
    // claimed arrival 0.9-1.8 m from the target 17 m away (sin 6 deg x 17 m = 1.8 m). With
    // the 1 deg gate the heading error stays about the simulator's 1 deg per unmeasured turn
    // and the run arrives (true end within 0.3 m). Worlds 42 and 43 are regression cases: the
    // two of the 50-world clutter batch where the old behaviour ended a false arrival for this
    // reason (found by running it); the 0.3 m success radius is the batch's.
    for k in [42, 43] {
        // Before: any match taken, with the matcher's own 2 deg heading prior, every turn made.
        let before = run(k, |p| {
            old_rules(p);
            p.localiser.drive_max_turn_deg = 180.0;
        });
        assert_eq!(
            before.reason,
            Reason::FalseArrival,
            "world {k}: {}",
            before.note
        );
        assert!(before.goal_distance_m.unwrap() > 0.8, "world {k}");
        assert!(
            before.final_heading_error_deg.unwrap().abs() > 5.0,
            "world {k}"
        );
        let after = run(k, old_rules);
        assert!(after.reached, "world {k}: {}", after.note);
        assert!(after.goal_distance_m.unwrap() <= 0.3);
        assert!(
            after.final_heading_error_deg.unwrap().abs() < 1.0,
            "world {k}"
        );
        // Every leg end carries the navigator's own uncertainty, growing from 0 at the start.
        assert_eq!(after.position_sigma_m.len(), after.legs + 1);
        assert_eq!(after.position_sigma_m[0], 0.0);
        assert!(
            after
                .position_sigma_m
                .windows(2)
                .all(|w| w[1] >= w[0] && w[1].is_finite())
        );
    }
}

#[test]
fn legs_that_see_the_target_point_at_it() {
    // Ranked by its path on the 0.1 m grid (8 directions), a leg toward a target 17 m away aims
    // up to 22.5 deg off it, and the next leg turns back by several degrees, mostly with
    // nothing in range to measure the turn: each such turn keeps the base's turn error.
    // Ranked by the straight line wherever the target is in sight on the planner's map, the
    // legs point at it and fewer turns are made. Over clutter worlds 0..20 (noise seed 0) the
    // median final heading error is lower (measured: about half, 0.26 against 0.55 deg, with
    // travel measured on a post's edge; on its centre, 0.28 against 0.30 deg).
    // The final approach's extra turn (1 deg noise, nothing in range) is left out of both.
    let grid = median_heading_error(|p| {
        p.planner.line_of_sight = false;
        p.tracking.round_centre = false;
        p.navigator.final_approach_m = 0.0;
    });
    let sight = median_heading_error(|p| {
        p.planner.line_of_sight = true;
        p.tracking.round_centre = false;
        p.navigator.final_approach_m = 0.0;
    });
    assert!(
        sight < 0.75 * grid,
        "median heading error {sight:.2} deg in sight, {grid:.2} deg on the grid path"
    );
}

#[test]
fn a_drive_match_weighs_its_heading_against_a_straight_drive() {
    // The simulator's base never turns while driving, so every heading change a drive's match
    // puts into the estimate is error. Weighed against the matcher's own 2 deg prior, a match
    // on a few posts still turns the estimate by tenths of a degree per metre; against the
    // drive's own 0.1 deg the heading is held unless the scans pin it harder. Over clutter
    // worlds 0..20 (noise seed 0, every turn made in both, rays ranked by their grid path) the
    // median final heading error is lower.
    let median = |sigma_deg: f64| {
        median_heading_error(|p| {
            p.localiser.drive_turn_sigma_deg = sigma_deg;
            p.navigator.skip_turn_below_deg = 0.0;
            p.planner.line_of_sight = false;
        })
    };
    let loose = median(2.0);
    let tight = median(0.1);
    // A quarter lower at least (half, when measured).
    assert!(
        tight < 0.75 * loose,
        "median heading error {tight:.2} deg with 0.1 deg, {loose:.2} deg with 2 deg"
    );
}

#[test]
fn a_partial_travel_match_must_pin_the_travel() {
    // Clutter world 11, noise seed 0 (found in the 200-run batch): in one 1 m drive the match
    // at the commanded travel fails (too few pairs), and the partial-travel hypothesis that
    // a stalled base needs lands on 0.39 m among a few posts, its travel known to 0.04 m only.
    // The estimate falls 0.6 m behind, and the run claims arrival 0.64 m from the target.
    // Believed only when the data pin the travel to 0.02 m, the command stands and the run
    // arrives. (A stalled base is still seen: `tests/base_faults.rs`.)
    let loose = run(11, |p| p.localiser.partial_travel_max_sigma_m = 0.05);
    assert_eq!(loose.reason, Reason::FalseArrival, "{}", loose.note);
    assert!(loose.goal_distance_m.unwrap() > 0.5);
    let tight = run(11, |p| p.localiser.partial_travel_max_sigma_m = 0.02);
    assert!(tight.reached, "{}", tight.note);
    assert!(tight.goal_distance_m.unwrap() <= 0.3);
}

#[test]
fn travel_on_a_round_post_is_measured_on_its_centre() {
    // Clutter world 26 with noise seed 0 and world 6 with seed 1 (false arrivals in the
    // 200-run batch): legs whose scan match fails keep the travel measured on a disc's edge,
    // the hit where the rays graze it, and that hit slides round the disc as the robot passes
    // (world 26: 2.79 m measured for a 2.99 m drive). Measured on the disc's fitted centre,
    // both arrive.
    for (k, seed) in [(26, 0), (6, 1)] {
        let edge = run_seeded(k, seed, |p| p.tracking.round_centre = false);
        assert_eq!(
            edge.reason,
            Reason::FalseArrival,
            "world {k}: {}",
            edge.note
        );
        assert!(edge.final_position_error_m.unwrap() > 0.3, "world {k}");
        let centre = run_seeded(k, seed, |_| {});
        assert!(centre.reached, "world {k}: {}", centre.note);
        assert!(centre.final_position_error_m.unwrap() < 0.1, "world {k}");
    }
}

#[test]
fn a_landmark_at_the_range_limit_gives_no_fix() {
    // Clutter world 188, noise seed 0: in leg 6 the tracked landmark, 3.8 m off to the side
    // and behind, recedes to the 4 m range and becomes the last hit of a surface running out
    // of range, which moves with the robot. Re-identified there, it measured 0.52 m for a
    // 0.99 m drive (the scan match failed: nothing else in range), and the run claimed
    // arrival 0.37 m from the target.
    let sliding = run(188, |p| {
        p.tracking.reject_near_range_limit = false;
        p.localiser.stray_landmark_max_sigma_m = 0.0;
    });
    assert_eq!(sliding.reason, Reason::FalseArrival, "{}", sliding.note);
    assert!(sliding.final_position_error_m.unwrap() > 0.3);
    let clear = run(188, |_| {});
    assert!(clear.reached, "{}", clear.note);
    assert!(clear.final_position_error_m.unwrap() < 0.1);
    // The landmark's 0.52 m strays from the 0.99 m commanded by more than 0.2 m and 30 %, and
    // no scan match confirms it: `stray_landmark_max_sigma_m` alone also keeps the commands.
    let unconfirmed = run(188, |p| p.tracking.reject_near_range_limit = false);
    assert!(unconfirmed.reached, "{}", unconfirmed.note);
    assert!(unconfirmed.final_position_error_m.unwrap() < 0.1);
}
