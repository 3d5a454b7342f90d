//! The grid-accelerated ray caster against a brute-force reference written here: the nearest
//! intersection with every obstacle's boundary, computed shape by shape.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scan_types::WorldPoint;
use sim_laser::{Obstacle, World, WorldParts};

fn ray_segment(o: [f64; 2], d: [f64; 2], a: [f64; 2], b: [f64; 2]) -> Option<f64> {
    // Solve o + t d = a + s (b - a) by Cramer's rule.
    let e = [b[0] - a[0], b[1] - a[1]];
    let det = -d[0] * e[1] + d[1] * e[0];
    if det.abs() < 1e-15 {
        return None;
    }
    let r = [a[0] - o[0], a[1] - o[1]];
    let t = (-r[0] * e[1] + r[1] * e[0]) / det;
    let s = (d[0] * r[1] - d[1] * r[0]) / det;
    (t >= 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
}

fn ray_circle(o: [f64; 2], d: [f64; 2], c: [f64; 2], r: f64) -> Option<f64> {
    // |o + t d - c|^2 = r^2 with |d| = 1: t^2 + 2 b t + k = 0.
    let b = d[0] * (o[0] - c[0]) + d[1] * (o[1] - c[1]);
    let k = (o[0] - c[0]).powi(2) + (o[1] - c[1]).powi(2) - r * r;
    let disc = b * b - k;
    if disc < 0.0 {
        return None;
    }
    let t = -b - disc.sqrt();
    (t >= 0.0).then_some(t)
}

fn reference(obstacles: &[Obstacle], o: [f64; 2], ang: f64, max: f64) -> Option<f64> {
    let d = [ang.cos(), ang.sin()];
    let mut best = f64::INFINITY;
    for ob in obstacles {
        let t = match ob {
            Obstacle::Circle { centre, radius } => ray_circle(o, d, *centre, *radius),
            Obstacle::Segment { a, b } => ray_segment(o, d, *a, *b),
            _ => {
                let p = ob.polygon_points().unwrap();
                (0..p.len())
                    .filter_map(|i| ray_segment(o, d, p[i], p[(i + 1) % p.len()]))
                    .min_by(f64::total_cmp)
            }
        };
        if let Some(t) = t {
            best = best.min(t);
        }
    }
    (best <= max).then_some(best)
}

#[test]
fn grid_ray_caster_matches_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    let mut checked = 0;
    for world_seed in 0..6 {
        let n = [3usize, 20, 60][world_seed % 3];
        // Coordinates on a 0.05 m lattice half the time, to land edges on cell borders.
        let coord = |lo: f64, hi: f64, rng: &mut ChaCha8Rng| {
            let v: f64 = rng.random_range(lo..hi);
            if world_seed % 2 == 0 {
                (v / 0.05).round() * 0.05
            } else {
                v
            }
        };
        let mut obstacles = Vec::new();
        for k in 0..n {
            let c = [coord(-5.0, 5.0, &mut rng), coord(-5.0, 5.0, &mut rng)];
            obstacles.push(match k % 4 {
                0 => Obstacle::Circle {
                    centre: c,
                    radius: rng.random_range(0.05..0.6),
                },
                1 => Obstacle::Box {
                    centre: c,
                    size: [
                        coord(0.1, 1.0, &mut rng).max(0.05),
                        coord(0.1, 1.0, &mut rng).max(0.05),
                    ],
                    angle_rad: if world_seed % 2 == 0 {
                        0.0
                    } else {
                        rng.random_range(0.0..3.2)
                    },
                },
                2 => Obstacle::Segment {
                    a: c,
                    b: [coord(-5.0, 5.0, &mut rng), c[1]],
                },
                _ => Obstacle::Polygon {
                    points: vec![c, [c[0] + 0.5, c[1] + 0.1], [c[0] + 0.2, c[1] + 0.7]],
                },
            });
        }
        let world = World::from_parts(WorldParts {
            name: "random".into(),
            obstacles: obstacles.clone(),
            ..Default::default()
        })
        .unwrap();
        for _ in 0..400 {
            let o = [coord(-6.0, 6.0, &mut rng), coord(-6.0, 6.0, &mut rng)];
            if world.is_occupied(WorldPoint::new(o[0], o[1])) {
                continue;
            }
            let ang = match rng.random_range(0..4) {
                0 => rng.random_range(0..8) as f64 * std::f64::consts::FRAC_PI_4,
                _ => rng.random_range(-3.2..3.2),
            };
            let max = rng.random_range(0.5..12.0);
            let want = reference(&obstacles, o, ang, max);
            let got = world.raycast(WorldPoint::new(o[0], o[1]), ang, max);
            match (want, got) {
                (Some(w), Some(g)) => assert!((w - g).abs() < 1e-9, "{o:?} {ang}: {w} vs {g}"),
                (None, None) => {}
                (w, g) => {
                    panic!("world {world_seed} o={o:?} ang={ang} max={max}: want {w:?} got {g:?}")
                }
            }
            checked += 1;
        }
    }
    assert!(checked > 1500, "{checked}");
}
