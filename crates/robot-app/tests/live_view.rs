//! `robot-app sim --live` watched by a client nobody here wrote: the PyPI package `websockets`
//! speaking the Foxglove WebSocket protocol (`foxglove.sdk.v1`), decoding with the protobuf
//! schemas the server advertises (PyPI `protobuf`), through `tests/tools/foxglove_live_client.py`.
//! Skipped with a notice when python3 lacks the packages, except under CI (`CI` set), where
//! that fails the test.

use std::net::TcpListener;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use serde_json::Value;
use sim_laser::SensorPreset;

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");

/// Kills a child process when the test ends, however it ends (unless taken back).
struct Killed(Option<Child>);

impl Drop for Killed {
    fn drop(&mut self) {
        if let Some(c) = self.0.as_mut() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

fn python_client_available() -> bool {
    Command::new("python3")
        .args(["-c", "import websockets.asyncio.client, google.protobuf"])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// A port nothing listens on now.
fn free_port() -> u16 {
    TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// Waits for `child` to end (reading its pipes meanwhile), killing it after `limit`; its
/// stdout and stderr.
fn finish(child: Child, limit: Duration, what: &str) -> std::process::Output {
    let pid = nix::unistd::Pid::from_raw(i32::try_from(child.id()).unwrap());
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let _ = tx.send(child.wait_with_output());
    });
    match rx.recv_timeout(limit) {
        Ok(out) => out.expect("output"),
        Err(_) => {
            let _ = nix::sys::signal::kill(pid, nix::sys::signal::Signal::SIGKILL);
            let out = rx.recv().expect("output").expect("output");
            panic!(
                "{what} did not finish in {limit:?}: {}",
                String::from_utf8_lossy(&out.stderr)
            );
        }
    }
}

fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("a whole number: {v}"))
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

#[test]
#[allow(clippy::print_stderr)] // the skip notice goes to the terminal
fn a_foxglove_websocket_client_receives_the_scans_of_a_sim_run() {
    if !python_client_available() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but python3 cannot import websockets and protobuf (pip install websockets protobuf)"
        );
        eprintln!(
            "skipped: python3 lacks websockets or protobuf (pip install websockets protobuf); CI would fail here"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out_dir = dir.path().join("out");
    let port = free_port();
    let addr = format!("127.0.0.1:{port}");
    // The run waits for the client's subscription, then runs as fast as it computes.
    let sim = Command::new(BIN)
        .args([
            "-q",
            "sim",
            "--seed",
            "3",
            "--sensor",
            "urg-04lx",
            "--live",
            &addr,
            "--live-wait",
            "60",
            "--live-rate",
            "0",
            "--out",
        ])
        .arg(&out_dir)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("robot-app runs");
    let mut sim = Killed(Some(sim));
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/tools/foxglove_live_client.py"
    );
    let client = Command::new("python3")
        .args([script, &format!("ws://{addr}"), "90"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 runs");
    let client = finish(client, Duration::from_secs(120), "the live client");
    assert!(
        client.status.success(),
        "the live client failed: {}",
        String::from_utf8_lossy(&client.stderr)
    );
    let sim_child = sim.0.take().unwrap();
    let sim = finish(sim_child, Duration::from_secs(60), "robot-app sim --live");
    let d: Value = serde_json::from_slice(&client.stdout).expect("one JSON object");
    // The client saw the server close the connection when the run ended, and the run's
    // outcome is what it is without --live.
    assert_eq!(d["closed"], "normal", "{}", d["closed"]);
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("summary.json")).unwrap())
            .unwrap();
    assert_eq!(
        sim.status.success(),
        summary["reached"] == true,
        "{}",
        String::from_utf8_lossy(&sim.stderr)
    );

    // Watching changes nothing: the same run without --live writes the same trajectory.
    let plain_dir = dir.path().join("plain");
    let plain = Command::new(BIN)
        .args(["-q", "sim", "--seed", "3", "--sensor", "urg-04lx", "--out"])
        .arg(&plain_dir)
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs");
    assert_eq!(plain.status.success(), sim.status.success());
    let printed = |o: &std::process::Output, d: &std::path::Path| {
        String::from_utf8_lossy(&o.stdout).replace(d.to_str().unwrap(), "OUT")
    };
    assert_eq!(printed(&plain, &plain_dir), printed(&sim, &out_dir));
    assert_eq!(
        std::fs::read(plain_dir.join("trajectory.csv")).unwrap(),
        std::fs::read(out_dir.join("trajectory.csv")).unwrap()
    );

    // The channels and their schemas.
    let channels = &d["channels"];
    for (topic, schema) in [
        ("/scan", "foxglove.LaserScan"),
        ("/pose_estimate", "foxglove.PoseInFrame"),
        ("/pose_truth", "foxglove.PoseInFrame"),
        ("/tf", "foxglove.FrameTransforms"),
        ("/tf_static", "foxglove.FrameTransforms"),
        ("/map", "foxglove.Grid"),
        ("/markers", "foxglove.SceneUpdate"),
    ] {
        assert_eq!(channels[topic]["schema_name"], schema, "{topic}");
        assert_eq!(channels[topic]["encoding"], "protobuf", "{topic}");
        assert_eq!(channels[topic]["schema_encoding"], "protobuf", "{topic}");
    }

    // Real scans: every one with the URG-04LX's 682 rays, bearings as the sensor's.
    let geometry = SensorPreset::Urg04lx.geometry();
    assert_eq!(geometry.ray_count, 682);
    let scans = d["scans"].as_array().unwrap();
    let run_scans = u(&summary["scans"]);
    assert!(
        !scans.is_empty() && scans.len() as u64 <= run_scans,
        "{} scans received of {run_scans}",
        scans.len()
    );
    assert_eq!(u(&channels["/scan"]["count"]), scans.len() as u64);
    for s in scans {
        assert_eq!(u(&s["ranges"]) as usize, geometry.ray_count);
        assert!(u(&s["hits"]) > 0, "{s}");
        assert_eq!(s["frame_id"], "laser");
        assert!((f(&s["start_angle"]) - geometry.first_bearing_rad).abs() < 1e-12);
        assert!((f(&s["end_angle"]) - geometry.last_bearing_rad()).abs() < 1e-12);
    }
    let stamps: Vec<f64> = scans.iter().map(|s| f(&s["stamp"])).collect();
    assert!(stamps.windows(2).all(|w| w[0] <= w[1]), "{stamps:?}");

    // Poses and transforms in the map frame, one per scan (a slow client may miss some:
    // the server drops what a client cannot take); the map and the markers.
    for topic in ["/pose_estimate", "/pose_truth"] {
        let poses = d["poses"][topic].as_array().unwrap();
        assert!(
            !poses.is_empty() && poses.len() as u64 <= run_scans,
            "{topic}: {}",
            poses.len()
        );
        assert!(poses.iter().all(|p| p[4] == "map"), "{topic}");
    }
    let tf = d["tf"].as_array().unwrap();
    assert!(!tf.is_empty() && tf.len() as u64 <= run_scans);
    assert!(tf.iter().all(|t| t[0] == "map" && t[1] == "base_link"));
    // The laser sits at base_link, sent once, on subscribing.
    assert_eq!(d["tf_static"], serde_json::json!([["base_link", "laser"]]));
    let maps = d["maps"].as_array().unwrap();
    assert!(!maps.is_empty());
    let last = &maps[maps.len() - 1];
    assert_eq!(last["frame_id"], "map");
    assert_eq!(last["fields"], serde_json::json!([["occupancy", 0, 2]]));
    assert_eq!(last["values"], serde_json::json!([-1, 0, 100]));
    assert!(u(&last["columns"]) > 0 && u(&last["rows"]) > 0);
    let markers = &d["markers"];
    assert_eq!(u(&markers["target"]), 1);
    assert!(u(&markers["landmarks"]) > 0, "{markers}");
    assert!(u(&markers["points_b"]) > 0, "{markers}");
}

/// `/map` and `/tf_static` are latched: a client that subscribes after the map was sent gets
/// it at once, with the fixed transform, and nothing else (no scan was sent since).
#[test]
#[allow(clippy::print_stderr)] // the skip notice goes to the terminal
fn a_late_client_gets_the_last_map() {
    if !python_client_available() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but python3 lacks websockets"
        );
        eprintln!("skipped: python3 lacks websockets or protobuf");
        return;
    }
    // Another test may take a free port before it is bound here: a few tries.
    let (port, mut view) = (0..5)
        .find_map(|_| {
            let port = free_port();
            let view = robot_app::live::LiveView::start(&format!("127.0.0.1:{port}"), 0.05);
            view.ok().map(|v| (port, v))
        })
        .expect("a free port within 5 tries");
    // A 1 m wide wall 2 m ahead, seen from the origin.
    let geometry = scan_types::ScanGeometry::centred(41, 40f64.to_radians(), 0.02, 4.0).unwrap();
    let ranges: Vec<f64> = (0..41)
        .map(|i| 2.0 / geometry.bearing_rad(i).cos())
        .collect();
    let scan = scan_types::Scan {
        status: vec![scan_types::RayStatus::Hit; ranges.len()],
        ranges_m: ranges,
        intensities: None,
        sensor_time_ms: None,
        host_time_s: 5.0,
    };
    let mut grid = localiser::OccupancyGrid::new(0.05);
    grid.integrate(&scan_types::Pose2::default(), &geometry, &scan);
    view.send_map(&grid);
    let script = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../tests/tools/foxglove_live_client.py"
    );
    // The client connects after the map was sent and watches for 2 s.
    let client = Command::new("python3")
        .args([script, &format!("ws://127.0.0.1:{port}"), "60", "2"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("python3 runs");
    let client = finish(client, Duration::from_secs(90), "the live client");
    view.finish(None);
    assert!(
        client.status.success(),
        "{}",
        String::from_utf8_lossy(&client.stderr)
    );
    let d: Value = serde_json::from_slice(&client.stdout).expect("one JSON object");
    assert_eq!(d["closed"], "watched");
    let maps = d["maps"].as_array().unwrap();
    assert_eq!(maps.len(), 1, "{d}");
    assert_eq!(maps[0]["frame_id"], "map");
    assert_eq!(maps[0]["values"], serde_json::json!([-1, 0, 100]));
    assert_eq!(d["tf_static"], serde_json::json!([["base_link", "laser"]]));
    assert_eq!(d["scans"], serde_json::json!([]));
}

#[test]
fn a_taken_port_is_a_clear_error() {
    let taken = TcpListener::bind("127.0.0.1:0").unwrap();
    let addr = taken.local_addr().unwrap().to_string();
    let dir = tempfile::tempdir().unwrap();
    let out = Command::new(BIN)
        .args(["sim", "--live", &addr, "--out"])
        .arg(dir.path())
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs");
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains(&format!("--live {addr}")), "{err}");
    assert!(err.contains("port is taken"), "{err}");
}
