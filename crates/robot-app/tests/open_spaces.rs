//! Open spaces (issue 18): clutter-only worlds, where a drive's scan match against a lone post
//! or a short wall can turn the estimate although the base drives straight.

use std::sync::Arc;

use robot_app::cmd::sim::{SimSpec, simulate_with_geodesic};
use robot_app::config::{Method, Params};
use robot_app::outputs::Reason;
use sim_laser::{SimSetup, WorldKind, generated_world};

/// The run in clutter world `k` (its own start and target, noise seed 0) with `max_turn_deg`.
fn run(k: u64, max_turn_deg: f64) -> robot_app::outputs::Summary {
    let (world, start, goal) = generated_world(WorldKind::Clutter, k).unwrap();
    let setup = SimSetup {
        start,
        seed: 0,
        ..SimSetup::new(Arc::new(world), format!("clutter-{k}"))
    };
    let mut p = Params::preset(Method::Goalseek);
    p.localiser.drive_max_turn_deg = max_turn_deg;
    simulate_with_geodesic(&SimSpec::new(setup, goal, p), None)
        .unwrap()
        .summary
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
        let before = run(k, 180.0);
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
        let after = run(k, 1.0);
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
