//! A long simulated run replayed through `robot-app slam`: an exploration of Stage's mbicp
//! floor plan recorded with `explore --record`, then mapped from its scans alone and checked
//! against the simulator's true poses stored in the recording (issue 18's bar: more than 60 m
//! driven, final error at most 0.05 m).

use std::path::Path;
use std::process::Command;

use serde_json::Value;

#[path = "common/tum.rs"]
mod tum;

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");

fn json(path: &Path) -> Value {
    serde_json::from_slice(&std::fs::read(path).unwrap()).unwrap()
}

#[test]
#[allow(clippy::print_stdout)]
fn a_recorded_exploration_of_mbicp_replays_within_five_centimetres_of_the_truth() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let world = root.join("sim/floorplans/mbicp.toml");
    if !root.join("../shared/worlds/stage/mbicp.png").exists() {
        println!("skipping: ../shared/worlds/stage/mbicp.png not found");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    // A laser scans every few degrees of a turn; 90 deg between scans in a square room is
    // a symmetry no scan matcher can resolve.
    let config = dir.path().join("chunks.toml");
    std::fs::write(&config, "[navigator]\nrotation_chunk_deg = 20\n").unwrap();
    let rec = dir.path().join("run.mcap");
    let out = dir.path().join("explore");
    let o = Command::new(BIN)
        .args([
            "-q",
            "explore",
            "--seed",
            "1",
            "--max-goals",
            "15",
            "--world",
        ])
        .arg(&world)
        .arg("--config")
        .arg(&config)
        .arg("--record")
        .arg(&rec)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let driven = json(&out.join("explore.json"))["true_path_length_m"]
        .as_f64()
        .unwrap();
    assert!(driven > 60.0, "drove {driven} m");

    let slam = dir.path().join("slam");
    let o = Command::new(BIN)
        .args(["-q", "slam", "--log"])
        .arg(&rec)
        .arg("--out")
        .arg(&slam)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let report = json(&slam.join("slam.json"));
    let e = &report["evaluation"];
    let (ate, last) = (
        e["absolute_m"]["rmse"].as_f64().unwrap(),
        e["final_position_error_m"].as_f64().unwrap(),
    );
    println!("mbicp replay: {driven:.1} m driven, ATE {ate:.3} m, final error {last:.3} m");
    assert_eq!(report["placed"], report["scans"], "{report}");
    assert_eq!(report["motion_prior"], false, "{report}");
    assert!(last <= 0.05, "final error {last} m");
    assert!(ate <= 0.05, "ATE {ate} m");
    // The reference is the simulator's truth (the explore run's truth.tum ends at the same
    // pose), not the navigator's estimate (estimate.tum, a few centimetres off).
    let dist = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).hypot(a[1] - b[1]);
    let reference = tum::last_xy(&slam.join("reference.tum"));
    assert!(dist(reference, tum::last_xy(&out.join("truth.tum"))) < 1e-6);
    assert!(dist(reference, tum::last_xy(&out.join("estimate.tum"))) > 1e-3);
}

#[test]
fn sim_with_slam_map_maps_the_run_within_five_centimetres_of_the_truth() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    // The paper's scenario, turns of up to 90 deg between scans (the default).
    let o = Command::new(BIN)
        .args(["-q", "sim", "--slam-map", "--out"])
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.join("run.mcap").exists());
    let report = json(&out.join("slam/slam.json"));
    assert_eq!(report["placed"], report["scans"], "{report}");
    // The navigator's estimate centred the searches.
    assert_eq!(report["motion_prior"], true, "{report}");
    let e = &report["evaluation"];
    let (ate, last) = (
        e["absolute_m"]["rmse"].as_f64().unwrap(),
        e["final_position_error_m"].as_f64().unwrap(),
    );
    assert!(ate <= 0.05 && last <= 0.05, "ATE {ate} m, final {last} m");
    for f in [
        "map.pgm",
        "map.yaml",
        "map.png",
        "trajectory.tum",
        "reference.tum",
    ] {
        assert!(out.join("slam").join(f).exists(), "{f}");
    }
}
