//! A landmark that moves with the robot (issue 15): in Stage's simple_rooms, seen by the
//! URG-04LX preset, a leg's landmark is the last hit of a wall that leaves the 5.6 m range,
//! and it stays 5.4 m ahead while the robot drives 1 m toward it.

use std::path::Path;

use serde_json::Value;

#[path = "common/sim_run.rs"]
mod sim_run;

/// `summary.json` of simple_rooms pair 59 of the 60-pair batch (noise seed 59) with the
/// URG-04LX preset and `config`.
fn run(dir: &Path, name: &str, config: &str) -> Value {
    let args = [
        "--seed",
        "59",
        "--sensor",
        "urg-04lx",
        "--start=6.25,1.8500000000000005,148.47890463531806",
        "--goal=-0.8499999999999996,2.450000000000001",
    ];
    sim_run::summary(dir, name, "simple_rooms", &args, config)
}

#[test]
#[allow(clippy::print_stdout)]
fn a_landmark_the_scans_do_not_confirm_does_not_stop_the_robot() {
    if !sim_run::stage_image_present("simple_rooms.png") {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // Leg 6 (`-v`: `the laser saw the robot not move`): the landmark says 0.07 m of the
    // commanded 1 m, and the scan match, started there, pins the travel only to 0.025 m.
    // Trusted, the estimate stays behind by the 0.95 m the robot drove: a false arrival. The
    // landmark lies 0.2 m inside the 5.6 m range, so the range-limit margin is held at its
    // fixed 0.15 m here (`range_limit_gaps = 0`) to leave it to this check.
    let trusted = run(
        dir.path(),
        "trusted",
        "[landmarks]\nrange_limit_gaps = 0\n[localiser]\nstray_landmark_max_sigma_m = 0\n",
    );
    assert_eq!(trusted["reason"], "false_arrival", "{trusted}");
    assert!(trusted["final_position_error_m"].as_f64().unwrap() > 0.5);
    // Not confirmed to 0.01 m, the match starts from the commands: the run arrives within
    // the 0.3 m success radius, its estimate as close to the truth.
    let checked = run(
        dir.path(),
        "checked",
        "[landmarks]\nrange_limit_gaps = 0\n[localiser]\nstray_landmark_max_sigma_m = 0.01\n",
    );
    assert_eq!(checked["reason"], "reached", "{checked}");
    assert!(
        checked["goal_distance_m"].as_f64().unwrap() < 0.3,
        "{checked}"
    );
    assert!(checked["final_position_error_m"].as_f64().unwrap() < 0.3);
}
