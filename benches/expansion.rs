//! Obstacle expansion: the reference kernel (paper eqs. 1-5, every hit against every ray)
//! against the fast kernel, at 685 (paper), 1081 (UTM-30LX) and 1440 rays, r = 0.3 m, on
//! scans of the paper's world and on random scans.
//!
//! The paper's world is sim-laser's embedded `cave.png` at 10 m x 10 m with a boundary wall;
//! its scans are cast noise-free from the paper's start pose and a few more poses.
//!
//! Run: `cargo bench --bench expansion` (add `-- --quick` for a short run).
#![allow(clippy::print_stderr, clippy::print_stdout)] // benches and tests report to the terminal

use std::hint::black_box;

#[path = "common/paper_world.rs"]
mod paper_world;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use expansion::{Expander, clearances_reference};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scan_types::{Scan, ScanGeometry};
use sim_laser::World;

const RADIUS_M: f64 = 0.3;

/// The three sensors: (label, geometry).
fn sensors() -> Vec<(&'static str, ScanGeometry)> {
    vec![
        ("685", ScanGeometry::paper()),
        // UTM-30LX: 270 deg at 0.25 deg, 30 m.
        (
            "1081",
            ScanGeometry::centred(1081, 270f64.to_radians(), 0.1, 30.0).unwrap(),
        ),
        // A full-turn scanner at 0.25 deg, 4 m (exercises the wrap-around windows).
        (
            "1440",
            ScanGeometry::new(-std::f64::consts::PI, 0.25f64.to_radians(), 1440, 0.0, 4.0).unwrap(),
        ),
    ]
}

fn random_scans(g: &ScanGeometry, count: usize, seed: u64) -> Vec<Scan> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..count)
        .map(|_| {
            let ranges: Vec<f64> = (0..g.ray_count)
                .map(|_| match rng.random_range(0..20) {
                    0 => f64::NAN,
                    1..=4 => g.max_range_m,
                    _ => rng.random_range(0.3..g.max_range_m),
                })
                .collect();
            Scan::from_ranges(g, &ranges, 0.0)
        })
        .collect()
}

fn bench_expansion(c: &mut Criterion) {
    let world = World::paper();
    for (label, g) in sensors() {
        let mut sets: Vec<(&str, Vec<Scan>)> = vec![("random", random_scans(&g, 4, 7))];
        let scans = paper_world::poses()
            .iter()
            .map(|&(x, y, h)| paper_world::scan(&world, &g, x, y, h))
            .collect();
        sets.push(("paper_world", scans));
        for (world, scans) in &sets {
            let mut group = c.benchmark_group(format!("expansion/{world}"));
            let mut out = vec![0.0; g.ray_count];
            let mut expander = Expander::new(&g);
            // One iteration = one scan (cycling through the set).
            group.bench_with_input(BenchmarkId::new("fast", label), scans, |b, scans| {
                let mut k = 0;
                b.iter(|| {
                    k = (k + 1) % scans.len();
                    expander.clearances(black_box(&scans[k]), RADIUS_M, &mut out);
                    black_box(out[0])
                })
            });
            group.bench_with_input(BenchmarkId::new("reference", label), scans, |b, scans| {
                let mut k = 0;
                b.iter(|| {
                    k = (k + 1) % scans.len();
                    clearances_reference(&g, black_box(&scans[k]), RADIUS_M, &mut out);
                    black_box(out[0])
                })
            });
            group.finish();
        }
    }
}

criterion_group!(benches, bench_expansion);
criterion_main!(benches);
