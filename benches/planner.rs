//! The planner on the paper's world: `plan()` with the path-length field cached (with and
//! without the line-of-sight ranking), `plan()` when the field must be recomputed (the map or
//! the target changed), and `add_scan`.
//!
//! Run: `cargo bench --bench planner -- --quick`.
#![allow(clippy::print_stderr, clippy::print_stdout)] // benches and tests report to the terminal

use std::hint::black_box;

#[path = "common/paper_world.rs"]
mod paper_world;

use criterion::{Criterion, criterion_group, criterion_main};
use expansion::Expander;
use planner::{PlanRule, Planner, PlannerParams};
use scan_types::{Pose2, ScanGeometry, WorldPoint};

fn bench_planner(c: &mut Criterion) {
    let world = sim_laser::World::paper();
    let g = ScanGeometry::paper();
    let scans: Vec<_> = paper_world::poses()
        .iter()
        .map(|&(x, y, h)| (Pose2::new(x, y, h), paper_world::scan(&world, &g, x, y, h)))
        .collect();
    let mut planner = Planner::new(PlannerParams::default());
    // The same without the line-of-sight ranking (the grid path alone).
    let mut grid_only = Planner::new(PlannerParams {
        line_of_sight: false,
        ..PlannerParams::default()
    });
    for (pose, scan) in &scans {
        planner.add_scan(pose, &g, scan);
        grid_only.add_scan(pose, &g, scan);
    }
    let (pose, scan) = &scans[1];
    let mut clearance = vec![0.0; g.ray_count];
    Expander::new(&g).clearances(scan, 0.4, &mut clearance);
    let target = WorldPoint::new(4.0, 4.0);
    let other = WorldPoint::new(3.0, 4.0);

    let mut group = c.benchmark_group("planner");
    group.bench_function("plan_map_path_cached_field", |b| {
        b.iter(|| black_box(planner.plan(pose, &g, scan, &clearance, target)))
    });
    group.bench_function("plan_map_path_cached_field_grid_only", |b| {
        b.iter(|| black_box(grid_only.plan(pose, &g, scan, &clearance, target)))
    });
    // Alternating targets forces a new path-length field every call.
    let mut flip = false;
    group.bench_function("plan_map_path_new_field", |b| {
        b.iter(|| {
            flip = !flip;
            let t = if flip { target } else { other };
            black_box(planner.plan(pose, &g, scan, &clearance, t))
        })
    });
    let mut greedy = Planner::new(PlannerParams {
        rule: PlanRule::Greedy,
        ..PlannerParams::default()
    });
    group.bench_function("plan_greedy", |b| {
        b.iter(|| black_box(greedy.plan(pose, &g, scan, &clearance, target)))
    });
    group.bench_function("add_scan", |b| {
        b.iter(|| planner.add_scan(pose, &g, black_box(scan)))
    });
    group.finish();
}

criterion_group!(benches, bench_planner);
criterion_main!(benches);
