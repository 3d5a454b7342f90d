//! `robot-app explore --record FILE --profile ros2` opened by readers nobody here wrote (the
//! PyPI packages `rosbags` and `mcap-ros2-support`, through `tests/tools/ros2_bag_client.py`):
//! every scan of the exploration is in it with its true pose, and its map at the end matches
//! `map.pgm`. Skipped with a notice when python3 lacks the packages, except under CI.

use std::path::Path;
use std::process::{Command, Stdio};

use serde_json::Value;

#[path = "common/python.rs"]
mod python;

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");

/// A 4 m x 3 m walled room with a 0.6 m box in it; the start is its file's.
const ROOM: &str = r#"
name = "record room"
start = [-1.2, -0.8, 30.0]
[bounds]
min = [-2.0, -1.5]
max = [2.0, 1.5]
boundary = true
[[box]]
centre = [0.8, 0.3]
size = [0.6, 0.6]
"#;

/// (width, height) of a binary PGM.
fn pgm_size(path: &Path) -> (u64, u64) {
    let bytes = std::fs::read(path).unwrap();
    let text = String::from_utf8_lossy(&bytes[..bytes.len().min(64)]).to_string();
    let mut fields = text.split_ascii_whitespace();
    assert_eq!(fields.next(), Some("P5"));
    let w = fields.next().unwrap().parse().unwrap();
    let h = fields.next().unwrap().parse().unwrap();
    (w, h)
}

#[test]
#[allow(clippy::print_stdout)]
fn an_exploration_recording_holds_every_scan_its_truth_and_its_map() {
    if !python::imports("rosbags.highlevel, mcap_ros2.decoder, mcap.reader") {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but python3 cannot import rosbags and mcap_ros2 (pip install rosbags mcap-ros2-support)"
        );
        println!("skipped: python3 lacks rosbags or mcap-ros2-support");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let world = dir.path().join("room.toml");
    std::fs::write(&world, ROOM).unwrap();
    let rec = dir.path().join("explore.mcap");
    let out = dir.path().join("out");
    let o = Command::new(BIN)
        .args(["-q", "explore", "--world"])
        .arg(&world)
        .arg("--record")
        .arg(&rec)
        .args(["--profile", "ros2", "--seed", "1", "--out"])
        .arg(&out)
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("explore.json")).unwrap()).unwrap();
    let scans = summary["scans"].as_u64().unwrap();
    assert!(scans > 10, "{summary}");

    let bag = python::ros2_bag_client(&rec);
    // Every scan the exploration took, each with its true pose.
    assert_eq!(bag["topics"]["/scan"]["count"].as_u64(), Some(scans));
    let truths = bag["truths"].as_array().unwrap();
    assert_eq!(truths.len() as u64, scans);
    // The robot (radius 0.3 m) stays in the room: 2 m x 1.5 m half-sizes less its radius.
    for t in truths {
        let (x, y) = (
            t["pose"][0].as_f64().unwrap(),
            t["pose"][1].as_f64().unwrap(),
        );
        assert!(x.abs() <= 1.7 + 1e-6 && y.abs() <= 1.2 + 1e-6, "{t}");
    }
    // The map at the end is map.pgm's grid.
    let maps = bag["maps"].as_array().unwrap();
    assert_eq!(maps.len(), 1);
    let (w, h) = pgm_size(&out.join("map.pgm"));
    assert_eq!(
        (maps[0]["width"].as_u64(), maps[0]["height"].as_u64()),
        (Some(w), Some(h))
    );
}
