//! ROS 2 bags and Foxglove files through the commands (`replay`, `emulate --source`, `slam`)
//! with `--topic`. The fixtures and their numbers are written by
//! `crates/scan-log/tests/fixtures/make_fixtures.py` (24 scans of 61 rays from -2 to 2 rad;
//! ROS ranges `offset + 0.05 k + 0.01 i` as float32, the rear topic's offset 2.0).

use std::path::PathBuf;

use robot_app::cmd::Noise;
use robot_app::cmd::emulate::{self, EmulateArgs};
use robot_app::cmd::replay::{self, ReplayArgs};
use robot_app::cmd::scan::{self, ScanArgs, ScanFormat};
use scan_log::read_scan_csv;
use scan_types::RayStatus;
use urg_driver::Model;

fn fixture(name: &str) -> PathBuf {
    PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scan-log/tests/fixtures"
    ))
    .join(name)
}

fn replay_args(file: PathBuf, topic: Option<&str>) -> ReplayArgs {
    ReplayArgs {
        file,
        rate: 0.0,
        sensor: None,
        topic: topic.map(str::to_string),
        count: None,
        format: ScanFormat::Csv,
        record: None,
        profile: Default::default(),
        through_loop: false,
        out: None,
        live: Default::default(),
    }
}

#[test]
fn replay_picks_a_topic_of_a_bag() {
    let mut out = Vec::new();
    replay::run_to(
        &replay_args(fixture("ros2_mcap"), Some("/scan_rear")),
        &mut out,
    )
    .unwrap();
    let text = String::from_utf8(out).unwrap();
    let blocks: Vec<_> = text
        .split("\n\n")
        .map(|b| read_scan_csv(b.as_bytes(), "output").unwrap())
        .collect();
    assert_eq!(blocks.len(), 24);
    let (g, first) = &blocks[0];
    assert_eq!(g.ray_count, 61);
    // Ray 30 of scan 0: 2.0 + 0.01 * 30 as float32 (the CSV prints it rounded).
    let got = first.hit_range_m(30).unwrap();
    assert!((got - f64::from(2.3f32)).abs() < 1e-6, "{got}");
    // Ray 7 is NaN in the bag, ray 11 is 7 m (beyond range_max 5.6 m): not distances.
    assert!(matches!(first.status[7], RayStatus::Error(_)));
    assert!(matches!(first.status[11], RayStatus::Error(_)));
}

#[test]
fn several_laser_topics_without_topic_are_listed() {
    let mut out = Vec::new();
    let e = replay::run_to(&replay_args(fixture("ros2_mcap"), None), &mut out).unwrap_err();
    let text = format!("{e:#}");
    assert!(
        text.contains("several laser scan topics (/scan, /scan_rear); choose one with --topic"),
        "{text}"
    );
}

#[test]
fn the_emulator_serves_a_bag_topic() {
    let server = emulate::start(&EmulateArgs {
        model: Model::Urg04lx,
        scip1: false,
        sim: false,
        world: None,
        pose: None,
        seed: 0,
        noise: Noise::Off,
        no_stdin: true,
        source: Some(fixture("ros2_mcap")),
        topic: Some("/scan_rear".into()),
        tcp: None,
    })
    .unwrap();
    let mut out = Vec::new();
    let args = ScanArgs {
        port: Some(server.location()),
        count: 1,
        format: ScanFormat::Csv,
        stream: false,
        sim: false,
        world: None,
        pose: None,
        sensor: "paper".into(),
        seed: 0,
        noise: Noise::Off,
        record: None,
        profile: Default::default(),
    };
    scan::run_to(&args, &mut out).unwrap();
    let (g, scan) = read_scan_csv(&out[..], "scan output").unwrap();
    // The SCIP step nearest straight ahead reads the bag's ray 30 (bearing 0), in millimetres.
    let ahead = g.nearest_index(0.0).unwrap();
    let got = scan.hit_range_m(ahead).unwrap();
    assert!((got - 2.3).abs() <= 0.0005 + 1e-6, "{got}");
}

#[test]
fn slam_reads_a_foxglove_file() {
    let (front, loops) = robot_app::cmd::slam::load_params(None).unwrap();
    let run = robot_app::cmd::slam::run_log_topic(
        &fixture("foxglove_protobuf.mcap"),
        None,
        &front,
        Some(&loops),
    )
    .unwrap();
    assert_eq!(run.report.scans, 24);
}
