//! `robot-app explore --port ... --base stdio` on hardware as the program sees it: the
//! simulator casts the scans of a small closed room, the SCIP emulator serves them on a
//! pseudo-terminal, and this test is the robot base on the other end of `--base stdio`.

use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Command, Stdio};
use std::sync::Arc;

use scan_types::{MotionBase, Pose2};
use sim_laser::{SensorPreset, Simulation, World};
use urg_driver::{Model, Profile};

/// A 3 m x 2.4 m room with its walls, the robot in its west half facing east: the wedge
/// behind it (the west wall) is unknown at the start.
const ROOM: &str = "[bounds]\nmin = [-1.5, -1.2]\nmax = [1.5, 1.2]\nboundary = true\n";

#[test]
fn a_room_is_explored_on_a_real_robot_s_code_path() {
    let world = World::from_toml_str(ROOM, Path::new("room.toml")).unwrap();
    let preset = SensorPreset::Urg04lx;
    let start = Pose2::new(-0.5, 0.0, 0.0);
    let sim = Simulation::new(
        Arc::new(world),
        preset,
        preset.default_noise(),
        sim_laser::MotionNoise::default(),
        0.3,
        start,
        1,
    );
    let (laser, mut base, truth) = sim.split();
    let server = urg_driver::serve_pty(Profile::of(Model::Urg04lx), laser).expect("a pty");
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("explore");
    let mut child = Command::new(env!("CARGO_BIN_EXE_robot-app"))
        .arg("explore")
        .args(["--port", server.path()])
        .arg("--start=-0.5,0,0")
        .args(["--base", "stdio"])
        .args(["--max-goals", "6"])
        .arg("--out")
        .arg(&dir)
        .env("RUST_LOG", "warn")
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("robot-app starts");
    let mut to_app = child.stdin.take().unwrap();
    let mut from_app = BufReader::new(child.stdout.take().unwrap());
    let (mut commands, mut stops) = (0, 0);
    let mut line = String::new();
    loop {
        line.clear();
        if from_app.read_line(&mut line).unwrap_or(0) == 0 {
            break;
        }
        let cmd = line.trim();
        let mut words = cmd.split_whitespace();
        match (words.next(), words.next().map(str::parse::<f64>)) {
            (Some("rotate"), Some(Ok(a))) => base.rotate(a).unwrap(),
            (Some("forward"), Some(Ok(d))) => base.forward(d).unwrap(),
            (Some("stop"), None) => stops += 1,
            _ => {
                // The program's one-line result, printed when it ends.
                continue;
            }
        }
        if cmd != "stop" {
            commands += 1;
        }
        let _ = writeln!(to_app, "done");
        let _ = to_app.flush();
    }
    let status = child.wait().unwrap();
    let mut stderr = String::new();
    std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut stderr).unwrap();
    server.stop();
    assert!(status.success(), "exit {status:?}; stderr:\n{stderr}");
    // The base got exactly one stop, at the end, and the robot never touched a wall.
    assert_eq!(stops, 1, "stderr:\n{stderr}");
    assert!(commands > 0);
    assert_eq!(truth.collisions(), 0);
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("explore.json")).unwrap()).unwrap();
    assert_eq!(s["end"], "explored", "{s}");
    assert!(s["goals_tried"].as_u64().unwrap() >= 1, "{s}");
    // No truth on a robot: no coverage, accuracy, error or seed, and no truth.png.
    for k in [
        "coverage_share",
        "map_accuracy_share",
        "final_position_error_m",
        "seed",
    ] {
        assert!(s[k].is_null(), "{k}: {s}");
    }
    assert!(!dir.join("truth.png").exists());
    for f in [
        "map.pgm",
        "map.yaml",
        "map.png",
        "trajectory.csv",
        "config.toml",
    ] {
        assert!(dir.join(f).is_file(), "{f}");
    }
}
