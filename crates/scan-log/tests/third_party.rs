//! Logs written by other tools (`tests/fixtures/make_fixtures.py`): ROS 2 bags by `rosbags`
//! (SQLite and MCAP) and by `mcap-ros2-support` (lz4 chunks), Foxglove `LaserScan` by the
//! Foxglove SDK (protobuf, zstd) and the `mcap` library (plain JSON), and goalseek's own
//! recording recompressed by the `mcap` library. Every expected number is the writer's,
//! from `tests/fixtures/expected.json`.

use std::path::{Path, PathBuf};

use scan_log::{LogError, LogOptions, LogReader, LogRecord, open_log_topic};
use scan_types::{LaserSource, RayStatus};
use serde_json::Value;

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn expected(key: &str) -> Value {
    let text = std::fs::read_to_string(fixture("expected.json")).unwrap();
    let all: Value = serde_json::from_str(&text).unwrap();
    all.get(key)
        .unwrap_or_else(|| panic!("expected.json has no {key}"))
        .clone()
}

/// A number of expected.json (NaN and the infinities are written as strings).
fn num(v: &Value) -> f64 {
    match v.as_str() {
        Some("nan") => f64::NAN,
        Some("inf") => f64::INFINITY,
        Some("-inf") => f64::NEG_INFINITY,
        _ => v.as_f64().unwrap(),
    }
}

fn nums(v: &Value) -> Vec<f64> {
    v.as_array().unwrap().iter().map(num).collect()
}

fn stamp_s(v: &Value) -> f64 {
    let a = nums(v);
    a[0] + a[1] * 1e-9
}

/// Every record of `path` (topic `topic`), none of them an error.
fn read(path: &Path, topic: Option<&str>) -> Vec<LogRecord> {
    let options = LogOptions {
        topic: topic.map(str::to_string),
        ..LogOptions::default()
    };
    LogReader::open(path, &options)
        .unwrap_or_else(|e| panic!("{e}"))
        .map(|r| r.unwrap_or_else(|e| panic!("{e}")))
        .collect()
}

fn open_err(path: &Path, topic: Option<&str>) -> LogError {
    let options = LogOptions {
        topic: topic.map(str::to_string),
        ..LogOptions::default()
    };
    match LogReader::open(path, &options) {
        Ok(_) => panic!("{} opened", path.display()),
        Err(e) => e,
    }
}

/// Checks ROS scans against what the script wrote: geometry, stamps, every reading of the
/// first and last scan with its REP 117 meaning, intensities.
fn check_ros(records: &[LogRecord], exp: &Value) {
    assert_eq!(records.len() as u64, exp["count"].as_u64().unwrap());
    let (min, max) = (num(&exp["range_min"]), num(&exp["range_max"]));
    for r in records {
        let g = &r.geometry;
        assert_eq!(g.ray_count as u64, exp["rays"].as_u64().unwrap());
        assert_eq!(g.first_bearing_rad, num(&exp["angle_min"]));
        assert_eq!(g.increment_rad, num(&exp["angle_increment"]));
        assert_eq!((g.min_range_m, g.max_range_m), (min, max));
    }
    let (first, last) = (&records[0], &records[records.len() - 1]);
    assert_eq!(first.scan.host_time_s, stamp_s(&exp["first_stamp"]));
    assert_eq!(last.scan.host_time_s, stamp_s(&exp["last_stamp"]));
    for (rec, ranges) in [(first, &exp["first_ranges"]), (last, &exp["last_ranges"])] {
        let written = nums(ranges);
        assert_eq!(rec.scan.len(), written.len());
        for (i, &w) in written.iter().enumerate() {
            let (got, status) = (rec.scan.ranges_m[i], rec.scan.status[i]);
            if w.is_finite() && (min..=max).contains(&w) {
                assert_eq!((status, got), (RayStatus::Hit, w), "ray {i}");
            } else if w == f64::INFINITY {
                assert_eq!((status, got), (RayStatus::MaxRange, max), "ray {i}");
            } else {
                assert!(matches!(status, RayStatus::Error(_)), "ray {i}: {status:?}");
                assert!(got.is_nan(), "ray {i} reads {got}, not a distance");
            }
        }
    }
    let intensities = nums(&exp["first_intensities"]);
    match &first.scan.intensities {
        None => assert!(intensities.is_empty()),
        Some(v) => {
            let v: Vec<f64> = v.iter().map(|&x| f64::from(x)).collect();
            assert_eq!(v, intensities);
        }
    }
}

/// Checks Foxglove scans against what the script wrote.
fn check_foxglove(records: &[LogRecord], exp: &Value) {
    assert_eq!(records.len() as u64, exp["count"].as_u64().unwrap());
    let n = exp["rays"].as_u64().unwrap() as usize;
    let (start, end) = (num(&exp["start_angle"]), num(&exp["end_angle"]));
    for r in records {
        let g = &r.geometry;
        assert_eq!(g.ray_count, n);
        assert_eq!(g.first_bearing_rad, start);
        assert!((g.last_bearing_rad() - end).abs() < 1e-12);
        assert_eq!(
            (g.min_range_m, g.max_range_m),
            (0.0, num(&exp["max_range"]))
        );
    }
    let (first, last) = (&records[0], &records[records.len() - 1]);
    assert_eq!(first.scan.host_time_s, stamp_s(&exp["first_stamp"]));
    assert_eq!(last.scan.host_time_s, stamp_s(&exp["last_stamp"]));
    for (rec, ranges) in [(first, &exp["first_ranges"]), (last, &exp["last_ranges"])] {
        for (i, w) in nums(ranges).into_iter().enumerate() {
            if w > 0.0 {
                assert_eq!(rec.scan.hit_range_m(i), Some(w), "ray {i}");
            } else {
                assert!(matches!(rec.scan.status[i], RayStatus::Error(_)), "ray {i}");
            }
        }
    }
    let intensities = nums(&exp["first_intensities"]);
    match &first.scan.intensities {
        None => assert!(intensities.is_empty()),
        Some(v) => assert_eq!(
            v.iter().map(|&x| f64::from(x)).collect::<Vec<_>>(),
            intensities
        ),
    }
}

#[test]
fn rosbags_sqlite_bag_folder_and_file() {
    let exp = expected("ros2_db3:/scan");
    check_ros(&read(&fixture("ros2_db3"), None), &exp);
    check_ros(&read(&fixture("ros2_db3/ros2_db3.db3"), None), &exp);
    check_ros(&read(&fixture("ros2_db3"), Some("/scan")), &exp);
}

#[test]
fn rosbags_mcap_bag_with_two_laser_topics() {
    let e = open_err(&fixture("ros2_mcap"), None);
    let text = e.to_string();
    assert!(matches!(e, LogError::SeveralTopics { .. }), "{text}");
    assert!(
        text.contains("ros2_mcap")
            && text.contains("/scan, /scan_rear")
            && text.contains("--topic"),
        "{text}"
    );
    check_ros(
        &read(&fixture("ros2_mcap"), Some("/scan")),
        &expected("ros2_mcap:/scan"),
    );
    check_ros(
        &read(&fixture("ros2_mcap"), Some("/scan_rear")),
        &expected("ros2_mcap:/scan_rear"),
    );
    // The bag's MCAP file on its own.
    check_ros(
        &read(&fixture("ros2_mcap/ros2_mcap.mcap"), Some("/scan_rear")),
        &expected("ros2_mcap:/scan_rear"),
    );
}

#[test]
fn mcap_ros2_support_with_lz4_chunks() {
    check_ros(
        &read(&fixture("ros2_lz4.mcap"), None),
        &expected("ros2_lz4.mcap:/base_scan"),
    );
}

#[test]
fn foxglove_sdk_protobuf_with_zstd_chunks() {
    check_foxglove(
        &read(&fixture("foxglove_protobuf.mcap"), None),
        &expected("foxglove_protobuf.mcap:/lidar"),
    );
}

#[test]
fn foxglove_plain_json() {
    check_foxglove(
        &read(&fixture("foxglove_json.mcap"), None),
        &expected("foxglove_json.mcap:/laser"),
    );
}

#[test]
fn goalseek_recording_recompressed_reads_the_same() {
    let plain = read(&fixture("goalseek.mcap"), None);
    // robot-app scan --sim --count 4 --record goalseek.mcap
    assert_eq!(plain.len(), 4);
    let meta = scan_log::read_mcap_metadata(&fixture("goalseek.mcap")).unwrap();
    for name in ["goalseek_zstd.mcap", "goalseek_lz4.mcap"] {
        let again = read(&fixture(name), None);
        // Debug text compares the NaN of error rays too, bit for bit in shortest form.
        assert_eq!(format!("{again:?}"), format!("{plain:?}"), "{name}");
        assert_eq!(
            scan_log::read_mcap_metadata(&fixture(name)).unwrap(),
            meta,
            "{name}"
        );
    }
}

#[test]
fn the_format_comes_from_the_content_not_the_name() {
    let dir = tempfile::tempdir().unwrap();
    let as_log = dir.path().join("scans.log");
    std::fs::copy(fixture("ros2_db3/ros2_db3.db3"), &as_log).unwrap();
    check_ros(&read(&as_log, None), &expected("ros2_db3:/scan"));
    let as_dat = dir.path().join("scans.dat");
    std::fs::copy(fixture("foxglove_protobuf.mcap"), &as_dat).unwrap();
    check_foxglove(
        &read(&as_dat, None),
        &expected("foxglove_protobuf.mcap:/lidar"),
    );
}

#[test]
fn a_bag_without_laser_scans_is_refused_with_what_it_holds() {
    let e = open_err(&fixture("chatter_db3"), None);
    let text = e.to_string();
    assert!(matches!(e, LogError::Unsupported { .. }), "{text}");
    assert!(text.contains("chatter_db3"), "{text}");
    assert!(
        text.contains("/chatter (std_msgs/msg/String in cdr)"),
        "{text}"
    );
    assert!(text.contains("sensor_msgs/msg/LaserScan in CDR"), "{text}");
}

#[test]
fn an_unknown_topic_names_the_laser_topics() {
    let e = open_err(&fixture("ros2_db3"), Some("/chatter"));
    let text = e.to_string();
    assert!(matches!(e, LogError::NoSuchTopic { .. }), "{text}");
    assert!(
        text.contains("no laser scan topic /chatter (laser topics: /scan; other topics: /chatter (std_msgs/msg/String in cdr))"),
        "{text}"
    );
}

#[test]
fn an_mcap_with_an_unknown_schema_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("points.mcap");
    let mut w = mcap::Writer::new(std::io::BufWriter::new(
        std::fs::File::create(&path).unwrap(),
    ))
    .unwrap();
    let schema = w.add_schema("acme.PointCloud", "protobuf", b"").unwrap();
    let ch = w
        .add_channel(schema, "/points", "protobuf", &Default::default())
        .unwrap();
    let header = mcap::records::MessageHeader {
        channel_id: ch,
        sequence: 0,
        log_time: 1,
        publish_time: 1,
    };
    w.write_to_known_channel(&header, b"\x08\x01").unwrap();
    w.finish().unwrap();
    drop(w);
    let e = open_err(&path, None);
    let text = e.to_string();
    assert!(
        text.contains("points.mcap")
            && text.contains("/points (acme.PointCloud in protobuf, schema encoding protobuf)")
            && text.contains("foxglove.LaserScan in protobuf or JSON"),
        "{text}"
    );
}

#[test]
fn a_damaged_sqlite_file_is_an_error_not_a_panic() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.db3");
    let mut bytes = scan_log::SQLITE_MAGIC.to_vec();
    bytes.extend([0xff; 200]);
    std::fs::write(&path, bytes).unwrap();
    let e = open_err(&path, None);
    assert!(matches!(e, LogError::Bag { .. }), "{e}");
    assert!(e.to_string().contains("bad.db3"), "{e}");
}

#[test]
fn a_bag_is_a_laser_source() {
    let mut src = open_log_topic(&fixture("ros2_mcap"), None, Some("/scan_rear")).unwrap();
    let exp = expected("ros2_mcap:/scan_rear");
    assert_eq!(
        src.geometry().ray_count as u64,
        exp["rays"].as_u64().unwrap()
    );
    let mut n = 0;
    while src.next_scan().is_ok() {
        n += 1;
    }
    assert_eq!(n, exp["count"].as_u64().unwrap());
}

mod damaged {
    use super::fixture;
    use proptest::prelude::*;
    use std::path::Path;

    /// Compressed files of other writers: zstd (Foxglove SDK), lz4 (mcap-ros2-support).
    const FILES: [&str; 3] = [
        "foxglove_protobuf.mcap",
        "ros2_lz4.mcap",
        "goalseek_zstd.mcap",
    ];

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// Any byte changed to any value, in a compressed chunk or elsewhere: records or
        /// errors, never a panic.
        #[test]
        fn a_changed_byte_never_panics(file in 0..FILES.len(), at in any::<prop::sample::Index>(), value in any::<u8>()) {
            let mut bytes = std::fs::read(fixture(FILES[file])).unwrap();
            let i = at.index(bytes.len());
            bytes[i] = value;
            let _ = scan_log::parse_mcap(&bytes, Path::new(FILES[file]));
        }

        /// A file cut anywhere gives the scans before the cut and an error, never a panic.
        #[test]
        fn a_cut_file_never_panics(file in 0..FILES.len(), at in any::<prop::sample::Index>()) {
            let bytes = std::fs::read(fixture(FILES[file])).unwrap();
            let cut = &bytes[..at.index(bytes.len())];
            let records = scan_log::parse_mcap(cut, Path::new(FILES[file]));
            prop_assert!(records.iter().any(Result::is_err));
        }
    }
}

#[test]
fn a_folder_that_is_not_a_bag_says_so() {
    let dir = tempfile::tempdir().unwrap();
    let e = open_err(dir.path(), None);
    assert!(
        e.to_string()
            .contains("a folder without metadata.yaml, not a rosbag2 bag"),
        "{e}"
    );
}
