//! The Python test clients nobody here wrote: whether python3 can import them, and the ROS 2
//! bag client's report of a recording.
#![allow(dead_code)] // each test file uses part of it

use std::path::Path;
use std::process::{Command, Stdio};

/// True when python3 runs `import <modules>` (e.g. `"rosbags.highlevel, mcap.reader"`).
pub fn imports(modules: &str) -> bool {
    Command::new("python3")
        .args(["-c", &format!("import {modules}")])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// `tests/tools/ros2_bag_client.py FILE`: what `rosbags` and `mcap-ros2-support` decode.
pub fn ros2_bag_client(file: &Path) -> serde_json::Value {
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/tools/ros2_bag_client.py"
    );
    let out = Command::new("python3")
        .arg(script)
        .arg(file)
        .output()
        .expect("python3 runs");
    assert!(
        out.status.success(),
        "ros2 bag client failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("the client prints one JSON object")
}
