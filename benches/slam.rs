//! Laser-only SLAM front end over whole real logs (scans read beforehand): `slam/exp1` is a
//! URG-04LX at 10 Hz (consecutive scans), `slam/intel` the subsampled Intel log (large steps,
//! the wide window). Throughput is scans per second; the time per scan is the median divided
//! by the scan count printed at the start.
//!
//! Run: `cargo bench --bench slam -- --quick` (needs ../shared/data).
#![allow(clippy::print_stdout)] // benches report to the terminal

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use scan_log::{LogOptions, LogReader};
use scan_types::{Scan, ScanGeometry};
use slam::{FrontEnd, FrontEndParams, Placement};

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

fn placed(scans: &[(ScanGeometry, Scan)]) -> usize {
    let mut fe = FrontEnd::new(FrontEndParams::default()).unwrap();
    scans
        .iter()
        .filter(|(g, s)| matches!(fe.add_scan(g, s), Placement::Placed { .. }))
        .count()
}

fn bench_slam(c: &mut Criterion) {
    let mut group = c.benchmark_group("slam");
    group.sample_size(10);
    for (name, rel) in [
        ("exp1", "breezyslam/exp1.dat"),
        ("intel", "carmen/intel-corrected.log.gz"),
    ] {
        let Some(log) = scans(rel) else {
            println!("skipping {name}: {rel} not found");
            continue;
        };
        println!("{name}: {} scans, {} placed", log.len(), placed(&log));
        group.throughput(Throughput::Elements(log.len() as u64));
        group.bench_function(name, |b| b.iter(|| black_box(placed(&log))));
    }
    group.finish();
}

criterion_group!(benches, bench_slam);
criterion_main!(benches);
