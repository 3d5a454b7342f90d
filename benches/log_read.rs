//! Log reading: the whole Intel Research Lab CARMEN log (decompressed, in memory: 1.74 MB,
//! 910 FLASER scans among 14 541 ODOM lines) and the BreezySLAM `exp1.dat` (756 scans of
//! 683 rays) parsed into scans with poses. Target: the Intel log in under 20 ms.
//!
//! The logs are read from `../shared/data/`; without them the bench prints a note and skips.
//!
//! Run: `cargo bench --bench log_read` (add `-- --quick` for a short run).

use std::hint::black_box;
use std::io::Read;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use scan_log::{CARMEN_DEFAULT_MAX_RANGE_M, TextFormat, TextLog, open_text};

fn load(rel: &str) -> Option<(PathBuf, Vec<u8>)> {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/")).join(rel);
    if !path.exists() {
        #[allow(clippy::print_stderr)]
        {
            eprintln!("log_read: {} not found, skipping", path.display());
        }
        return None;
    }
    let mut bytes = Vec::new();
    open_text(&path)
        .expect("opens")
        .read_to_end(&mut bytes)
        .expect("decompresses");
    Some((path, bytes))
}

/// Parses every record; returns the number of scans (all records must parse).
fn parse(bytes: &[u8], path: &Path, format: TextFormat) -> usize {
    TextLog::new(bytes, path, format, None, CARMEN_DEFAULT_MAX_RANGE_M)
        .inspect(|r| assert!(r.is_ok(), "the shared logs parse: {r:?}"))
        .count()
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("log_read");
    if let Some((path, bytes)) = load("carmen/intel-corrected.log.gz") {
        assert_eq!(parse(&bytes, &path, TextFormat::Carmen), 910);
        group.bench_function("intel_carmen_910_scans", |b| {
            b.iter(|| parse(black_box(&bytes), &path, TextFormat::Carmen))
        });
    }
    if let Some((path, bytes)) = load("breezyslam/exp1.dat") {
        assert_eq!(parse(&bytes, &path, TextFormat::Breezy), 756);
        group.bench_function("exp1_breezyslam_756_scans", |b| {
            b.iter(|| parse(black_box(&bytes), &path, TextFormat::Breezy))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
