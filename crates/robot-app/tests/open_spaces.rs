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
    let (world, start, goal) = generated_world(WorldKind::Clutter, k).unwrap();
    let setup = SimSetup {
        start,
        seed: 0,
        ..SimSetup::new(Arc::new(world), format!("clutter-{k}"))
    };
    let mut p = Params::preset(Method::Goalseek);
    change(&mut p);
    simulate_with_geodesic(&SimSpec::new(setup, goal, p), None)
        .unwrap()
        .summary
}

/// The drive and turn rules before the drive's heading prior and the skipped small turns.
fn old_rules(p: &mut Params) {
    p.localiser.drive_turn_sigma_deg = 2.0;
    p.navigator.skip_turn_below_deg = 0.0;
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
fn a_drive_match_weighs_its_heading_against_a_straight_drive() {
    // The simulator's base never turns while driving, so every heading change a drive's match
    // puts into the estimate is error. Weighed against the matcher's own 2 deg prior, a match
    // on a few posts still turns the estimate by tenths of a degree per metre; against the
    // drive's own 0.1 deg the heading is held unless the scans pin it harder. Over clutter
    // worlds 0..20 (noise seed 0, every turn made in both) the median final heading error is
    // lower.
    let median_heading_error = |sigma_deg: f64| {
        let mut errors: Vec<f64> = (0..20)
            .map(|k| {
                let s = run(k, |p| {
                    p.localiser.drive_turn_sigma_deg = sigma_deg;
                    p.navigator.skip_turn_below_deg = 0.0;
                });
                s.final_heading_error_deg.unwrap().abs()
            })
            .collect();
        errors.sort_by(f64::total_cmp);
        (errors[9] + errors[10]) / 2.0
    };
    let loose = median_heading_error(2.0);
    let tight = median_heading_error(0.1);
    // A quarter lower at least (half, when measured).
    assert!(
        tight < 0.75 * loose,
        "median heading error {tight:.2} deg with 0.1 deg, {loose:.2} deg with 2 deg"
    );
}
