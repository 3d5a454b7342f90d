//! Any pose, goal or tuning value given to a simulated run, finite or not, gives either a run
//! that ends or an error that names what was wrong: never a panic, an abort or unbounded
//! memory.

use navigator::{Navigator, NoMonitor, Params};
use proptest::prelude::*;
use scan_types::{Pose2, WorldPoint};
use sim_laser::{SensorPreset, SimSetup};

/// Mostly values in `lo..hi`, and sometimes what a typo or a bad file gives.
fn value(lo: f64, hi: f64) -> impl Strategy<Value = f64> {
    prop_oneof![
        40 => lo..hi,
        1 => Just(f64::NAN),
        1 => Just(f64::INFINITY),
        1 => Just(f64::NEG_INFINITY),
        1 => Just(0.0),
        1 => Just(-1.0),
        1 => Just(1e-9),
        1 => Just(1e308),
        1 => Just(-1e19),
        1 => 1e3..1e13f64,
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn any_setup_gives_a_bounded_run_or_a_named_error(
        (sx, sy, th) in (value(-4.5, 4.5), value(-4.5, 4.5), value(-3.2, 3.2)),
        (gx, gy) in (value(-4.5, 4.5), value(-4.5, 4.5)),
        (tolerance, max_leg, grid) in (value(0.05, 0.5), value(0.5, 5.0), value(0.02, 0.5)),
        (map_res, radius) in (value(0.02, 0.3), value(0.1, 0.5)),
    ) {
        let mut params = Params::goalseek();
        params.navigator.goal_tolerance_m = tolerance;
        params.navigator.max_legs = 3;
        params.planner.max_leg_m = max_leg;
        params.planner.grid_resolution_m = grid;
        params.localiser.map_resolution_m = map_res;
        params.robot.radius_m = radius;
        let start = Pose2::new(sx, sy, th);
        let goal = WorldPoint::new(gx, gy);
        let mut failure = None;
        let info = allocation_counter::measure(|| {
            let mut setup = SimSetup::paper(1);
            setup.start = start;
            setup.robot_radius_m = radius;
            let checked = params
                .validate()
                .map_err(|e| e.to_string())
                .and_then(|()| setup.check_scenario(goal).map_err(|e| e.to_string()))
                .and_then(|()| setup.build().map_err(|e| e.to_string()));
            match checked {
                Err(msg) => failure = Some(msg),
                Ok(sim) => {
                    let (mut laser, mut base, _truth) = sim.split();
                    let nav = Navigator::new(params.clone(), SensorPreset::Paper.geometry(), start, goal)
                        .expect("a checked setup is accepted");
                    let outcome = navigator::run(nav, &mut laser, &mut base, &mut NoMonitor);
                    assert!(outcome.legs_driven <= 3, "{} legs", outcome.legs_driven);
                }
            }
        });
        if let Some(msg) = failure {
            let named = [
                "robot.radius_m", "navigator.goal_tolerance_m", "planner.max_leg_m",
                "planner.grid_resolution_m", "localiser.map_resolution_m", "start", "target",
            ];
            prop_assert!(named.iter().any(|k| msg.contains(k)), "unnamed error: {msg}");
        }
        prop_assert!(info.bytes_max < 1 << 30, "{} bytes at the peak", info.bytes_max);
    }
}
