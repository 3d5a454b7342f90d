//! Ray casting speed of the simulator: one paper scan in the paper world, and the cost of a scan
//! against the number of obstacles (10, 100, 1000) in a 20 m x 20 m world.

use std::hint::black_box;
use std::sync::Arc;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scan_types::{LaserSource, Pose2};
use sim_laser::{Obstacle, SensorPreset, Simulation, World, WorldDescription, true_scan};

/// `n` random boxes and discs (half each) of 0.1..0.5 m in a 20 m x 20 m walled world, kept
/// 1 m away from the origin where the robot stands.
fn cluttered(n: usize, seed: u64) -> World {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut obstacles = Vec::with_capacity(n);
    while obstacles.len() < n {
        let c = [rng.random_range(-9.5..9.5), rng.random_range(-9.5..9.5)];
        if f64::hypot(c[0], c[1]) < 1.0 {
            continue;
        }
        let s = rng.random_range(0.1..0.5);
        obstacles.push(if obstacles.len() % 2 == 0 {
            Obstacle::Box {
                centre: c,
                size: [s, rng.random_range(0.1..0.5)],
                angle_rad: rng.random_range(0.0..std::f64::consts::PI),
            }
        } else {
            Obstacle::Circle {
                centre: c,
                radius: s / 2.0,
            }
        });
    }
    WorldDescription {
        name: format!("clutter-{n}"),
        bounds: Some(([-10.0, -10.0], [10.0, 10.0])),
        boundary: true,
        obstacles,
        start: None,
        target: None,
    }
    .to_world()
    .expect("valid world")
}

fn paper(c: &mut Criterion) {
    let world = World::paper();
    let g = SensorPreset::Paper.geometry();
    let start = sim_laser::paper_start();
    c.bench_function("paper_scan_685_rays_noise_free", |b| {
        b.iter(|| true_scan(black_box(&world), black_box(&start), &g))
    });
    let centre = Pose2::new(0.5, 0.0, 0.0);
    c.bench_function("paper_scan_685_rays_noise_free_centre", |b| {
        b.iter(|| true_scan(black_box(&world), black_box(&centre), &g))
    });
    let (mut laser, _, _) =
        Simulation::with_preset(Arc::new(world.clone()), SensorPreset::Paper, start, 1).split();
    c.bench_function("paper_simlaser_next_scan_with_noise", |b| {
        b.iter(|| laser.next_scan().expect("infallible"))
    });
    c.bench_function("paper_world_build", |b| b.iter(World::paper));
}

fn obstacles(c: &mut Criterion) {
    let mut group = c.benchmark_group("scan_vs_obstacles");
    let pose = Pose2::new(0.0, 0.0, 0.3);
    for preset in [SensorPreset::Paper, SensorPreset::Utm30lx] {
        let g = preset.geometry();
        for n in [10usize, 100, 1000] {
            let world = cluttered(n, 7);
            group.bench_with_input(BenchmarkId::new(preset.name(), n), &world, |b, w| {
                b.iter(|| true_scan(black_box(w), black_box(&pose), &g))
            });
        }
    }
    group.finish();
}

criterion_group!(benches, paper, obstacles);
criterion_main!(benches);
