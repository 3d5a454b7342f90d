//! `robot-app sim --record FILE --profile ros2` opened by readers nobody here wrote: the PyPI
//! packages `rosbags` and `mcap-ros2-support`, through `tests/tools/ros2_bag_client.py`. What
//! they decode is checked against the run's other outputs: its summary, map.pgm/map.yaml and
//! the default goalseek recording of the same seed. Skipped with a notice when python3 lacks
//! the packages, except under CI (`CI` set), where that fails the test.

use std::path::Path;
use std::process::{Command, Output, Stdio};

use scan_types::RayStatus;
use serde_json::Value;

#[path = "common/python.rs"]
mod python;

const BIN: &str = env!("CARGO_BIN_EXE_robot-app");

fn python_readers_available() -> bool {
    python::imports("rosbags.highlevel, mcap_ros2.decoder, mcap.reader")
}

fn robot_app(args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("robot-app runs")
}

/// `robot-app -q sim --seed 3 --record FILE [--profile P] --out DIR`: its stdout.
fn sim(dir: &Path, name: &str, profile: Option<&str>) -> String {
    let rec = dir.join(format!("{name}.mcap"));
    let out = dir.join(name);
    let mut args = vec![
        "-q",
        "sim",
        "--seed",
        "3",
        "--record",
        rec.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ];
    if let Some(p) = profile {
        args.extend(["--profile", p]);
    }
    let o = robot_app(&args);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    String::from_utf8(o.stdout).unwrap()
}

fn run_client(file: &Path) -> Value {
    python::ros2_bag_client(file)
}

fn f(v: &Value) -> f64 {
    v.as_f64().unwrap_or_else(|| panic!("a number: {v}"))
}

fn u(v: &Value) -> u64 {
    v.as_u64().unwrap_or_else(|| panic!("a whole number: {v}"))
}

/// `[sec, nanosec]` as seconds.
fn seconds(stamp: &Value) -> f64 {
    u(&stamp[0]) as f64 + u(&stamp[1]) as f64 * 1e-9
}

/// The yaw of a quaternion about z given as `[.., .., z, w]` at `at`.
fn yaw(q: &[Value], at: usize) -> f64 {
    assert_eq!(
        (f(&q[at]), f(&q[at + 1])),
        (0.0, 0.0),
        "a turn about z only"
    );
    2.0 * f(&q[at + 2]).atan2(f(&q[at + 3]))
}

/// The angle from `b` to `a`, in (-pi, pi].
fn angle_diff(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(std::f64::consts::TAU);
    if d > std::f64::consts::PI {
        d - std::f64::consts::TAU
    } else {
        d
    }
}

/// A P5 map.pgm: width, height and pixels (rows from the top).
fn read_pgm(path: &Path) -> (usize, usize, Vec<u8>) {
    let bytes = std::fs::read(path).unwrap();
    let mut fields = Vec::new();
    let mut at = 0;
    while fields.len() < 4 {
        while bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        let start = at;
        while !bytes[at].is_ascii_whitespace() {
            at += 1;
        }
        fields.push(String::from_utf8(bytes[start..at].to_vec()).unwrap());
    }
    assert_eq!(fields[0], "P5");
    assert_eq!(fields[3], "255");
    let (w, h) = (fields[1].parse().unwrap(), fields[2].parse().unwrap());
    let pixels = bytes[at + 1..].to_vec();
    assert_eq!(pixels.len(), w * h);
    (w, h, pixels)
}

/// A `key: value` of map.yaml.
fn yaml_value<'a>(text: &'a str, key: &str) -> &'a str {
    text.lines()
        .find_map(|l| l.strip_prefix(key)?.strip_prefix(':'))
        .unwrap_or_else(|| panic!("map.yaml has no {key}"))
        .trim()
}

#[test]
#[allow(clippy::print_stderr)] // the skip notice goes to the terminal
fn rosbags_and_mcap_ros2_read_a_ros2_recording_of_a_sim_run() {
    if !python_readers_available() {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI is set but python3 cannot import rosbags and mcap_ros2 (pip install rosbags mcap-ros2-support)"
        );
        eprintln!(
            "skipped: python3 lacks rosbags or mcap-ros2-support (pip install rosbags mcap-ros2-support); CI would fail here"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let printed_default = sim(dir.path(), "goalseek", None);
    let printed = sim(dir.path(), "ros2", Some("ros2"));
    assert_eq!(printed.replace("ros2", "goalseek"), printed_default);
    let bag = dir.path().join("ros2.mcap");
    assert!(!scan_log::partial_path(&bag).exists());
    let d = run_client(&bag);

    // Counts: every scan of the run with its estimate, truth and transform; one map.
    let out = dir.path().join("ros2");
    let summary: Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let scans = u(&summary["scans"]);
    let legs = u(&summary["legs"]);
    assert!(printed.contains(&format!("after {legs} legs")), "{printed}");
    let topics = &d["topics"];
    for (topic, ty, count) in [
        ("/scan", "sensor_msgs/msg/LaserScan", scans),
        ("/pose_estimate", "geometry_msgs/msg/PoseStamped", scans),
        ("/pose_truth", "geometry_msgs/msg/PoseStamped", scans),
        ("/tf", "tf2_msgs/msg/TFMessage", scans),
        ("/tf_static", "tf2_msgs/msg/TFMessage", 1),
        ("/map", "nav_msgs/msg/OccupancyGrid", 1),
    ] {
        assert_eq!(topics[topic]["type"], ty, "{topic}");
        assert_eq!(u(&topics[topic]["count"]), count, "{topic}");
        assert_eq!(u(&d["mcap_ros2"]["counts"][topic]), count, "{topic}");
    }
    assert_eq!(topics.as_object().unwrap().len(), 6);
    // The same topic names as goalseek's own recording.
    assert_eq!(scan_log::ROS2_POSE_ESTIMATE_TOPIC, scan_log::EST_POSE_TOPIC);
    assert_eq!(scan_log::ROS2_POSE_TRUTH_TOPIC, scan_log::TRUE_POSE_TOPIC);
    // /tf_static and /map are latched (transient local durability) as rosbag2 records them.
    for topic in ["/tf_static", "/map"] {
        assert_eq!(
            topics[topic]["durability"],
            serde_json::json!(["TRANSIENT_LOCAL"]),
            "{topic}"
        );
    }
    // base_link -> laser: the laser is the tracked point, so the identity.
    let fixed = d["tf_static"].as_array().unwrap();
    assert_eq!(fixed.len(), 1, "{fixed:?}");
    assert_eq!(
        (&fixed[0]["parent"], &fixed[0]["child"]),
        (&"base_link".into(), &"laser".into())
    );
    assert_eq!(fixed[0]["translation"], serde_json::json!([0.0, 0.0, 0.0]));
    assert_eq!(
        fixed[0]["rotation"],
        serde_json::json!([0.0, 0.0, 0.0, 1.0])
    );
    assert_eq!(d["mcap_ros2"]["profile"], "ros2");
    assert_eq!(
        d["mcap_ros2"]["metadata"],
        serde_json::json!([scan_log::RUN_METADATA, scan_log::LEGS_METADATA])
    );
    // The legs stored beside the messages are the run's.
    let (_, recorded_legs) = scan_log::read_recorded_legs(&bag).unwrap().unwrap();
    assert_eq!(recorded_legs.len() as u64, legs + 1, "start + legs");

    // The scans, stamps and poses equal those of the default recording of the same run.
    let default = scan_log::read_mcap(&dir.path().join("goalseek.mcap")).unwrap();
    let default: Vec<_> = default.into_iter().map(|r| r.unwrap()).collect();
    assert_eq!(default.len() as u64, scans);
    let stamps = d["scan_stamps"].as_array().unwrap();
    for (s, rec) in stamps.iter().zip(&default) {
        assert!((seconds(s) - rec.scan.host_time_s).abs() < 1e-9);
    }
    for (key, rec) in [
        ("first_scan", &default[0]),
        ("last_scan", &default[default.len() - 1]),
    ] {
        let m = &d[key];
        assert_eq!(m["frame_id"], "laser");
        let g = &rec.geometry;
        // The paper sensor: 100 ms a turn, 685 rays over 240 deg, so 240/684 deg of a 360 deg
        // turn between rays.
        assert_eq!(f(&m["scan_time"]), f64::from(0.1f32));
        let dt = 0.1 * (240.0 / 684.0) / 360.0;
        assert!(
            (f(&m["time_increment"]) - dt).abs() < 1e-6 * dt,
            "{}",
            m["time_increment"]
        );
        assert_eq!(f(&m["angle_min"]), f64::from(g.first_bearing_rad as f32));
        assert_eq!(f(&m["angle_increment"]), f64::from(g.increment_rad as f32));
        assert_eq!(f(&m["range_min"]), f64::from(g.min_range_m as f32));
        assert_eq!(f(&m["range_max"]), f64::from(g.max_range_m as f32));
        let ranges = m["ranges"].as_array().unwrap();
        assert_eq!(ranges.len(), g.ray_count);
        let mut kinds = [0usize; 3];
        for (i, (r, status)) in ranges.iter().zip(&rec.scan.status).enumerate() {
            match status {
                RayStatus::Hit => {
                    kinds[0] += 1;
                    assert_eq!(f(r), f64::from(rec.scan.ranges_m[i] as f32), "ray {i}");
                }
                RayStatus::MaxRange => {
                    kinds[1] += 1;
                    assert_eq!(r, "inf", "ray {i}");
                }
                RayStatus::Error(_) => {
                    kinds[2] += 1;
                    assert_eq!(r, "nan", "ray {i}");
                }
            }
        }
        assert!(kinds[0] > 0, "{key}: hits {kinds:?}");
    }
    for (key, pose_of) in [
        (
            "estimates",
            (|r: &scan_log::LogRecord| r.pose) as fn(&_) -> _,
        ),
        ("truths", |r: &scan_log::LogRecord| r.true_pose),
    ] {
        let poses = d[key].as_array().unwrap();
        assert_eq!(poses.len(), default.len());
        for (m, rec) in poses.iter().zip(&default) {
            let want = pose_of(rec).unwrap();
            assert_eq!(m["frame_id"], "map");
            assert!((seconds(&m["stamp"]) - rec.scan.host_time_s).abs() < 1e-9);
            let p = m["pose"].as_array().unwrap();
            assert_eq!((f(&p[0]), f(&p[1]), f(&p[2])), (want.x_m, want.y_m, 0.0));
            assert!(angle_diff(yaw(p, 3), want.theta_rad).abs() < 1e-12, "{key}");
        }
    }
    let tf = d["tf"].as_array().unwrap();
    assert_eq!(tf.len(), default.len());
    for (t, rec) in tf.iter().zip(&default) {
        let want = rec.pose.unwrap();
        assert_eq!(
            (&t["parent"], &t["child"]),
            (&"map".into(), &"base_link".into())
        );
        let xyz = t["translation"].as_array().unwrap();
        assert_eq!(
            (f(&xyz[0]), f(&xyz[1]), f(&xyz[2])),
            (want.x_m, want.y_m, 0.0)
        );
        let q = t["rotation"].as_array().unwrap();
        assert!(angle_diff(yaw(q, 0), want.theta_rad).abs() < 1e-12);
    }
    // The start pose of the summary is the first estimate.
    let start = &summary["start"];
    let first = d["estimates"][0]["pose"].as_array().unwrap();
    assert!((f(&first[0]) - f(&start["x_m"])).abs() < 1e-12);
    assert!((f(&first[1]) - f(&start["y_m"])).abs() < 1e-12);
    assert!((yaw(first, 3).to_degrees() - f(&start["heading_deg"])).abs() < 1e-9);

    // The map is map.pgm/map.yaml as map_server publishes them in trinary mode: rows from the
    // bottom of the image, black 100, white 0, grey -1.
    let map = &d["maps"][0];
    let (w, h, pixels) = read_pgm(&out.join("map.pgm"));
    let yaml = std::fs::read_to_string(out.join("map.yaml")).unwrap();
    assert_eq!(yaml_value(&yaml, "mode"), "trinary");
    assert_eq!(
        (u(&map["width"]) as usize, u(&map["height"]) as usize),
        (w, h)
    );
    let resolution: f64 = yaml_value(&yaml, "resolution").parse().unwrap();
    assert_eq!(f(&map["resolution"]), f64::from(resolution as f32));
    let origin: Vec<f64> = yaml_value(&yaml, "origin")
        .trim_matches(['[', ']'])
        .split(',')
        .map(|v| v.trim().parse().unwrap())
        .collect();
    let o = map["origin"].as_array().unwrap();
    for k in 0..3 {
        assert!((f(&o[k]) - origin[k]).abs() < 1e-9, "origin {k}");
    }
    assert_eq!(yaw(o, 3), 0.0);
    assert_eq!(map["frame_id"], "map");
    assert_eq!(map["stamp"], stamps[stamps.len() - 1]);
    let data = map["data"].as_array().unwrap();
    assert_eq!(data.len(), w * h);
    let mut kinds = [0usize; 3];
    for row in 0..h {
        for col in 0..w {
            let want = match pixels[(h - 1 - row) * w + col] {
                0 => 100,
                254 => 0,
                205 => -1,
                p => panic!("pixel {p}"),
            };
            kinds[match want {
                100 => 0,
                0 => 1,
                _ => 2,
            }] += 1;
            assert_eq!(
                data[row * w + col].as_i64(),
                Some(want),
                "cell {col}, {row}"
            );
        }
    }
    assert!(
        kinds.iter().all(|&k| k > 0),
        "occupied, free, unknown: {kinds:?}"
    );
}
