//! Bitmap worlds against a brute-force reference written here (every occupied cell intersected as a
//! closed square), and whole scans (cast several rays at once) against single rays.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use scan_types::{Pose2, ScanGeometry, WorldPoint};
use sim_laser::{Bitmap, Obstacle, SensorPreset, World, WorldParts, true_scan};

/// Entry distance of the ray `o + t d` (t >= 0) into the closed box `lo`..`hi`, by slabs.
fn ray_box(o: [f64; 2], d: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> Option<f64> {
    let (mut t0, mut t1) = (0.0f64, f64::INFINITY);
    for k in 0..2 {
        if d[k] == 0.0 {
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
        } else {
            let (a, b) = ((lo[k] - o[k]) / d[k], (hi[k] - o[k]) / d[k]);
            t0 = t0.max(a.min(b));
            t1 = t1.min(a.max(b));
        }
    }
    (t0 <= t1).then_some(t0)
}

fn random_bitmap(rng: &mut ChaCha8Rng, width: usize, height: usize, fill: f64) -> Bitmap {
    Bitmap {
        width,
        height,
        cell_w_m: 0.05,
        cell_h_m: 0.04,
        origin: [-1.3, -0.7],
        occupied: (0..width * height).map(|_| rng.random_bool(fill)).collect(),
    }
}

fn reference(b: &Bitmap, o: [f64; 2], d: [f64; 2], max: f64) -> Option<f64> {
    let mut best = f64::INFINITY;
    for row in 0..b.height {
        for col in 0..b.width {
            if b.occupied[row * b.width + col] {
                let lo = [
                    b.origin[0] + col as f64 * b.cell_w_m,
                    b.origin[1] + row as f64 * b.cell_h_m,
                ];
                let hi = [lo[0] + b.cell_w_m, lo[1] + b.cell_h_m];
                if let Some(t) = ray_box(o, d, lo, hi) {
                    best = best.min(t);
                }
            }
        }
    }
    (best <= max).then_some(best)
}

#[test]
fn bitmap_ray_caster_matches_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(7);
    let mut checked = 0;
    for (w, h, fill) in [(60, 45, 0.02), (40, 70, 0.1), (80, 30, 0.3)] {
        let b = random_bitmap(&mut rng, w, h, fill);
        let world = World::from_parts(WorldParts {
            name: "bits".into(),
            bitmap: Some(b.clone()),
            ..Default::default()
        })
        .unwrap();
        for _ in 0..300 {
            // Inside and around the bitmap (its box is about 3 m x 2 m from (-1.3, -0.7)).
            let o = [rng.random_range(-2.0..2.5), rng.random_range(-1.5..2.5)];
            if world.is_occupied(WorldPoint::new(o[0], o[1])) {
                continue;
            }
            let ang: f64 = rng.random_range(-3.2..3.2);
            let d = [ang.cos(), ang.sin()];
            let max = rng.random_range(0.2..5.0);
            let want = reference(&b, o, d, max);
            let got = world.raycast(WorldPoint::new(o[0], o[1]), ang, max);
            match (want, got) {
                (Some(w), Some(g)) => assert!((w - g).abs() < 1e-9, "{o:?} {ang}: {w} vs {g}"),
                (None, None) => {}
                (w, g) => panic!("o={o:?} ang={ang} max={max}: want {w:?} got {g:?}"),
            }
            checked += 1;
        }
        // Whole scans (several rays at once) against the reference too.
        let g = ScanGeometry::new(-2.0, 0.01, 400, 0.0, 3.0).unwrap();
        for _ in 0..5 {
            let pose = Pose2::new(
                rng.random_range(-1.2..1.6),
                rng.random_range(-0.6..1.0),
                rng.random_range(-3.2..3.2),
            );
            if world.is_occupied(pose.position()) {
                continue;
            }
            let scan = true_scan(&world, &pose, &g);
            for (i, &r) in scan.ranges_m.iter().enumerate() {
                let a = pose.theta_rad + g.bearing_rad(i);
                let want = reference(&b, [pose.x_m, pose.y_m], [a.cos(), a.sin()], 3.0);
                let want = want.unwrap_or(3.0);
                assert!((r - want).abs() < 1e-9, "{pose:?} ray {i}: {r} vs {want}");
            }
        }
    }
    assert!(checked > 500, "{checked}");
}

/// Every ray of `true_scan` (cast several at once) against the same ray cast alone.
fn scan_matches_single_rays(world: &World, pose: &Pose2, g: &ScanGeometry) {
    let scan = true_scan(world, pose, g);
    for (i, &r) in scan.ranges_m.iter().enumerate() {
        let a = pose.theta_rad + g.bearing_rad(i);
        let single = world
            .raycast(pose.position(), a, g.max_range_m)
            .unwrap_or(g.max_range_m);
        assert!(
            (r - single).abs() < 1e-9 || (r.is_nan() && single < g.min_range_m),
            "pose {pose:?} ray {i}: scan {r} vs single {single}"
        );
    }
}

#[test]
fn whole_scans_equal_single_rays() {
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let paper = World::paper();
    let shapes = World::from_parts(WorldParts {
        name: "shapes".into(),
        obstacles: (0..30)
            .map(|k| {
                let c = [rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0)];
                match k % 3 {
                    0 => Obstacle::Circle {
                        centre: c,
                        radius: rng.random_range(0.05..0.5),
                    },
                    1 => Obstacle::Box {
                        centre: c,
                        size: [rng.random_range(0.1..1.0), rng.random_range(0.1..1.0)],
                        angle_rad: rng.random_range(0.0..3.2),
                    },
                    _ => Obstacle::Segment {
                        a: c,
                        b: [rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0)],
                    },
                }
            })
            .collect(),
        ..Default::default()
    })
    .unwrap();
    for world in [&paper, &shapes] {
        for preset in SensorPreset::ALL {
            let g = preset.geometry();
            for _ in 0..20 {
                let pose = Pose2::new(
                    rng.random_range(-4.9..4.9),
                    rng.random_range(-4.9..4.9),
                    rng.random_range(-3.2..3.2),
                );
                scan_matches_single_rays(world, &pose, &g);
            }
            // From outside the grid, looking in.
            scan_matches_single_rays(world, &Pose2::new(-9.0, 0.3, 0.1), &g);
        }
    }
}

fn ray_segment(o: [f64; 2], d: [f64; 2], a: [f64; 2], b: [f64; 2]) -> Option<f64> {
    // o + t d = a + s (b - a), by Cramer's rule.
    let e = [b[0] - a[0], b[1] - a[1]];
    let det = e[0] * d[1] - d[0] * e[1];
    if det.abs() < 1e-15 {
        return None;
    }
    let r = [a[0] - o[0], a[1] - o[1]];
    let t = (e[0] * r[1] - r[0] * e[1]) / det;
    let s = (d[0] * r[1] - d[1] * r[0]) / det;
    (t >= 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
}

fn point_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let e = [b[0] - a[0], b[1] - a[1]];
    let l2 = e[0] * e[0] + e[1] * e[1];
    let s = (((p[0] - a[0]) * e[0] + (p[1] - a[1]) * e[1]) / l2).clamp(0.0, 1.0);
    (p[0] - a[0] - s * e[0]).hypot(p[1] - a[1] - s * e[1])
}

/// Oblique walls and discs (whose cells the grid lists only where the shape passes, and whose
/// inner cells are solid): rays and clearances against brute force over every shape.
#[test]
fn oblique_walls_and_discs_match_brute_force() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let mut walls = Vec::new();
    let mut discs = Vec::new();
    for _ in 0..25 {
        let a = [rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0)];
        walls.push((
            a,
            [
                a[0] + rng.random_range(-2.0..2.0),
                a[1] + rng.random_range(-2.0..2.0),
            ],
        ));
        let c = [rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0)];
        discs.push((c, rng.random_range(0.05..0.8)));
    }
    let obstacles = walls
        .iter()
        .map(|&(a, b)| Obstacle::Segment { a, b })
        .chain(
            discs
                .iter()
                .map(|&(centre, radius)| Obstacle::Circle { centre, radius }),
        )
        .collect();
    let world = World::from_parts(WorldParts {
        name: "oblique".into(),
        obstacles,
        cell_size_m: Some(0.05),
        ..Default::default()
    })
    .unwrap();
    let mut checked = 0;
    for _ in 0..1500 {
        let o = [rng.random_range(-5.0..5.0), rng.random_range(-5.0..5.0)];
        // Clearance: distance to the nearest shape (0 inside a disc), capped at 1 m.
        let mut near = 1.0f64;
        for &(a, b) in &walls {
            near = near.min(point_segment(o, a, b));
        }
        for &(c, r) in &discs {
            near = near.min(((o[0] - c[0]).hypot(o[1] - c[1]) - r).max(0.0));
        }
        let got = world.clearance(WorldPoint::new(o[0], o[1]), 1.0);
        assert!(
            (got - near).abs() < 1e-9,
            "clearance at {o:?}: {got} vs {near}"
        );
        if near == 0.0 {
            continue;
        }
        let ang: f64 = rng.random_range(-3.2..3.2);
        let d = [ang.cos(), ang.sin()];
        let max = rng.random_range(0.5..10.0);
        let mut best = f64::INFINITY;
        for &(a, b) in &walls {
            if let Some(t) = ray_segment(o, d, a, b) {
                best = best.min(t);
            }
        }
        for &(c, r) in &discs {
            let b = d[0] * (o[0] - c[0]) + d[1] * (o[1] - c[1]);
            let k = (o[0] - c[0]).powi(2) + (o[1] - c[1]).powi(2) - r * r;
            if b * b - k >= 0.0 && -b - (b * b - k).sqrt() >= 0.0 {
                best = best.min(-b - (b * b - k).sqrt());
            }
        }
        let want = (best <= max).then_some(best);
        let got = world.raycast(WorldPoint::new(o[0], o[1]), ang, max);
        match (want, got) {
            (Some(w), Some(g)) => assert!((w - g).abs() < 1e-9, "{o:?} {ang}: {w} vs {g}"),
            (None, None) => {}
            (w, g) => panic!("o={o:?} ang={ang} max={max}: want {w:?} got {g:?}"),
        }
        checked += 1;
    }
    assert!(checked > 1000, "{checked}");
}
