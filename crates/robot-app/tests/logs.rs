//! Logs through the commands: `replay`, `scan --record`, `emulate --source`, `map`.

use std::path::PathBuf;

use robot_app::cmd::Noise;
use robot_app::cmd::emulate::{self, EmulateArgs};
use robot_app::cmd::replay::{self, ReplayArgs};
use robot_app::cmd::scan::{self, ScanArgs, ScanFormat};
use robot_app::record::{Recorder, open_log};
use scan_log::read_scan_csv;
use scan_types::{LaserSource, Pose2, RayStatus, Scan, ScanGeometry};
use urg_driver::Model;

fn replay_args(file: PathBuf) -> ReplayArgs {
    ReplayArgs {
        file,
        rate: 0.0,
        sensor: None,
        topic: None,
        count: None,
        format: ScanFormat::Csv,
        record: None,
        profile: Default::default(),
        through_loop: false,
        out: None,
        live: Default::default(),
    }
}

/// Splits the CSV output of several scans (blocks separated by a blank line).
fn blocks(out: &[u8]) -> Vec<(ScanGeometry, Scan)> {
    String::from_utf8(out.to_vec())
        .unwrap()
        .split("\n\n")
        .map(|b| read_scan_csv(b.as_bytes(), "output").unwrap())
        .collect()
}

#[test]
fn replay_prints_every_scan_of_a_carmen_log() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.log");
    std::fs::write(
        &path,
        "FLASER 3 1.5 99 2.25 0 0 0 0 0 0 10.0 h 10.0\nODOM 0 0 0 0 0 0 10.1 h 10.1\nFLASER 3 broken\nFLASER 3 0.5 0.75 60 1 2 0.5 1 2 0.5 10.2 h 10.2\n",
    )
    .unwrap();
    let mut out = Vec::new();
    let mut args = replay_args(path.clone());
    args.record = Some(dir.path().join("two.mcap"));
    replay::run_to(&args, &mut out).unwrap();
    let b = blocks(&out);
    assert_eq!(b.len(), 2);
    assert_eq!(b[0].0.ray_count, 3);
    assert_eq!(b[0].1.ranges_m, vec![1.5, 50.0, 2.25]);
    assert_eq!(b[1].1.status[2], RayStatus::MaxRange);
    // The MCAP copy carries the log's pose as the estimated pose.
    let mut src = open_log(&dir.path().join("two.mcap"), None).unwrap();
    src.next_scan().unwrap();
    src.next_scan().unwrap();
    assert_eq!(src.pose(), Some(Pose2::new(1.0, 2.0, 0.5)));
}

#[test]
fn scan_record_then_replay_prints_the_same_csv() {
    let dir = tempfile::tempdir().unwrap();
    let rec = dir.path().join("sim.mcap");
    let args = ScanArgs {
        port: None,
        count: 3,
        format: ScanFormat::Csv,
        stream: false,
        sim: true,
        world: None,
        pose: None,
        sensor: "paper".into(),
        seed: 4,
        noise: Noise::On,
        record: Some(rec.clone()),
        profile: Default::default(),
    };
    let mut live = Vec::new();
    scan::run_to(&args, &mut live).unwrap();
    let mut replayed = Vec::new();
    replay::run_to(&replay_args(rec), &mut replayed).unwrap();
    assert_eq!(blocks(&live).len(), 3);
    assert_eq!(
        String::from_utf8(live).unwrap(),
        String::from_utf8(replayed).unwrap()
    );
}

#[test]
fn emulate_source_serves_a_recording_over_scip() {
    // A recording in the URG-04LX step geometry with whole-millimetre ranges, so the SCIP
    // round trip (millimetres on the wire) gives back exactly the recorded values.
    let g = sim_laser::SensorPreset::Urg04lx.geometry();
    let ranges: Vec<f64> = (0..g.ray_count)
        .map(|i| {
            if i % 50 == 7 {
                g.max_range_m
            } else {
                (500 + i) as f64 / 1000.0
            }
        })
        .collect();
    let scan = Scan::from_ranges(&g, &ranges, 1.0);
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("urg.mcap");
    let mut r = Recorder::create(&path, &g).unwrap();
    r.write(&scan).unwrap();
    r.finish().unwrap();

    let server = emulate::start(&EmulateArgs {
        model: Model::Urg04lx,
        scip1: false,
        sim: false,
        world: None,
        pose: None,
        seed: 0,
        noise: Noise::Off,
        no_stdin: true,
        source: Some(path),
        topic: None,
        tcp: None,
    })
    .unwrap();
    let mut out = Vec::new();
    let args = ScanArgs {
        port: Some(server.location()),
        count: 2, // the one-scan log loops
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
    for (gg, got) in blocks(&out) {
        assert_eq!(gg.ray_count, g.ray_count);
        for (i, want) in ranges.iter().enumerate() {
            if i % 50 == 7 {
                assert_eq!(got.status[i], RayStatus::MaxRange, "ray {i}");
            } else {
                assert_eq!(got.status[i], RayStatus::Hit, "ray {i}");
                assert!((got.ranges_m[i] - want).abs() < 1e-9, "ray {i}");
            }
        }
    }
}

#[test]
fn intel_map_endpoints_fit_the_map() {
    let path = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/carmen/intel-corrected.log.gz"
    ));
    if !path.exists() {
        #[allow(clippy::print_stdout)]
        {
            println!("skipping: {} not found", path.display());
        }
        return;
    }
    let mut src = open_log(&path, None).unwrap();
    let g = *src.geometry();
    let mut scans = Vec::new();
    while let Ok(r) = src.next_record() {
        scans.push((r.pose.unwrap(), r.scan.clone()));
    }
    assert_eq!(scans.len(), 910);
    let (_, stats) = localiser::build_map(&g, &scans, 0.05, 20.0, false);
    // Acceptance: at least 90 % of the endpoints within one 5 cm cell of an occupied cell.
    assert!(stats.endpoint_fit() >= 0.90, "{:.3}", stats.endpoint_fit());
}
