//! Laser-only SLAM front end over whole real logs (scans read beforehand): `slam/exp1` is a
//! URG-04LX at 10 Hz (consecutive scans; `slam/exp1_thinned` with `icp_target_voxel_m` 0.02),
//! `slam/intel` the subsampled Intel log (large steps, the wide window). Throughput is scans
//! per second; the time per scan is the median divided by the scan count printed at the start.
//!
//! `pose_graph/optimise_5000` optimises a synthetic 5 000-node pose graph.
//!
//! Run: `cargo bench --bench slam -- --quick` (the log benches need ../shared/data).
#![allow(clippy::print_stdout)] // benches report to the terminal

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use scan_log::{LogOptions, LogReader};
use scan_types::Pose2;
use scan_types::{Scan, ScanGeometry};
use slam::graph::{Edge, OptimiseParams, PoseGraph};
use slam::{FrontEnd, FrontEndParams, Placement};
use std::f64::consts::FRAC_PI_2;

fn scans(rel: &str) -> Option<Vec<(ScanGeometry, Scan)>> {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/")).join(rel);
    let reader = LogReader::open(&p, &LogOptions::default()).ok()?;
    Some(
        reader
            .filter_map(Result::ok)
            .map(|r| (r.geometry, r.scan))
            .collect(),
    )
}

fn placed(scans: &[(ScanGeometry, Scan)], params: &FrontEndParams) -> usize {
    let mut fe = FrontEnd::new(params.clone()).unwrap();
    scans
        .iter()
        .filter(|(g, s)| matches!(fe.add_scan(g, s), Placement::Placed { .. }))
        .count()
}

fn bench_slam(c: &mut Criterion) {
    let mut group = c.benchmark_group("slam");
    group.sample_size(10);
    let thinned = FrontEndParams {
        icp_target_voxel_m: 0.02,
        ..FrontEndParams::default()
    };
    for (name, rel, params) in [
        ("exp1", "breezyslam/exp1.dat", FrontEndParams::default()),
        ("exp1_thinned", "breezyslam/exp1.dat", thinned),
        (
            "intel",
            "carmen/intel-corrected.log.gz",
            FrontEndParams::default(),
        ),
    ] {
        let Some(log) = scans(rel) else {
            println!("skipping {name}: {rel} not found");
            continue;
        };
        println!(
            "{name}: {} scans, {} placed",
            log.len(),
            placed(&log, &params)
        );
        group.throughput(Throughput::Elements(log.len() as u64));
        group.bench_function(name, |b| b.iter(|| black_box(placed(&log, &params))));
    }
    group.finish();
}

/// A robot driving 25 laps of a 10 m square in 0.2 m steps (5 000 poses), its odometry off by
/// a steady 1 % in length and 0.2 deg per step, with a closure to the previous lap every tenth
/// pose: the pose graph `slam::graph` optimises after loop closure.
fn lap_graph() -> PoseGraph {
    let side_steps = 50;
    let lap = 4 * side_steps;
    let step = |k: usize| {
        let turn = if (k + 1).is_multiple_of(side_steps) {
            FRAC_PI_2
        } else {
            0.0
        };
        Pose2::new(0.2, 0.0, turn)
    };
    let mut truth = vec![Pose2::default()];
    let mut drifted = vec![Pose2::default()];
    for k in 0..25 * lap - 1 {
        let s = step(k);
        truth.push(truth[k].compose(&s));
        let off = Pose2::new(s.x_m * 1.01, 0.0, s.theta_rad + 0.2f64.to_radians());
        drifted.push(drifted[k].compose(&off));
    }
    let mut g = PoseGraph::new(drifted);
    let edge = |from, to, measured, robust| Edge {
        from,
        to,
        measured,
        sigma: [0.02, 0.02, 0.01],
        robust,
    };
    for k in 0..truth.len() - 1 {
        g.add_edge(edge(k, k + 1, step(k), false)).unwrap();
    }
    for k in (lap..truth.len()).step_by(10) {
        let z = truth[k - lap].inverse().compose(&truth[k]);
        g.add_edge(edge(k - lap, k, z, true)).unwrap();
    }
    g
}

fn bench_graph(c: &mut Criterion) {
    let graph = lap_graph();
    let mut group = c.benchmark_group("pose_graph");
    group.sample_size(10);
    group.bench_function("optimise_5000", |b| {
        b.iter(|| {
            let mut g = graph.clone();
            black_box(g.optimise(&OptimiseParams::default()).unwrap())
        })
    });
    group.finish();
}

criterion_group!(benches, bench_slam, bench_graph);
criterion_main!(benches);
