//! The simulated robot and laser: noise statistics, seeding, drives, collisions.

use std::sync::Arc;

use scan_types::{LaserSource, MotionBase, Pose2, RayStatus};
use sim_laser::{LaserNoise, MotionNoise, Obstacle, SensorPreset, Simulation, World, WorldParts};

/// A wall x = 2 from y = -10 to 10, nothing else.
fn wall_world() -> Arc<World> {
    Arc::new(
        World::from_parts(WorldParts {
            name: "wall".into(),
            obstacles: vec![Obstacle::Segment {
                a: [2.0, -10.0],
                b: [2.0, 10.0],
            }],
            ..Default::default()
        })
        .unwrap(),
    )
}

fn sim(noise: LaserNoise, motion: MotionNoise, seed: u64) -> Simulation {
    Simulation::new(
        wall_world(),
        SensorPreset::Paper,
        noise,
        motion,
        0.3,
        Pose2::new(0.0, 0.0, 0.0),
        seed,
    )
}

fn std_dev(v: &[f64]) -> f64 {
    let m = v.iter().sum::<f64>() / v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (v.len() - 1) as f64).sqrt()
}

#[test]
fn noise_free_ranges_and_misses() {
    let (mut laser, _, _) = sim(LaserNoise::off(), MotionNoise::off(), 1).split();
    let g = *laser.geometry();
    let s = laser.next_scan().unwrap();
    for i in 0..g.ray_count {
        let b = g.bearing_rad(i);
        let true_r = 2.0 / b.cos();
        if b.cos() > 0.0 && true_r < 4.0 {
            assert_eq!(s.status[i], RayStatus::Hit);
            assert!((s.ranges_m[i] - true_r).abs() < 1e-9, "ray {i}");
        } else {
            assert_eq!(s.status[i], RayStatus::MaxRange);
            assert_eq!(s.ranges_m[i], 4.0);
        }
    }
}

#[test]
fn range_noise_has_the_preset_sigma() {
    let (mut laser, _, _) = sim(SensorPreset::Paper.default_noise(), MotionNoise::off(), 2).split();
    let g = *laser.geometry();
    let centre = g.nearest_index(0.0).unwrap();
    let errs: Vec<f64> = (0..2000)
        .map(|_| laser.next_scan().unwrap().ranges_m[centre] - 2.0)
        .collect();
    let sd = std_dev(&errs);
    assert!((sd - 0.01).abs() < 0.001, "sigma {sd}");
    // URG-04LX: 0.3 % of 3 m beyond 1 m.
    let mut s = Simulation::new(
        wall_world(),
        SensorPreset::Urg04lx,
        SensorPreset::Urg04lx.default_noise(),
        MotionNoise::off(),
        0.3,
        Pose2::new(-1.0, 0.0, 0.0),
        3,
    )
    .split()
    .0;
    let c = s.geometry().nearest_index(0.0).unwrap();
    let errs: Vec<f64> = (0..2000)
        .map(|_| s.next_scan().unwrap().ranges_m[c] - 3.0)
        .collect();
    let sd = std_dev(&errs);
    assert!((sd - 0.009).abs() < 0.0009, "sigma {sd}");
}

#[test]
fn dropouts_and_too_near() {
    let (mut laser, _, _) = sim(LaserNoise::off().with_dropout(0.2), MotionNoise::off(), 4).split();
    let mut dropped = 0usize;
    let mut total = 0usize;
    for _ in 0..20 {
        let s = laser.next_scan().unwrap();
        for (r, st) in s.ranges_m.iter().zip(&s.status) {
            total += 1;
            if let RayStatus::Error(_) = st {
                assert!(r.is_nan());
                dropped += 1;
            }
        }
    }
    let f = dropped as f64 / total as f64;
    assert!((f - 0.2).abs() < 0.02, "dropout fraction {f}");
    // URG-04LX minimum range 0.02 m: a wall 0.01 m ahead reads as an error.
    let (mut l, _, t) = Simulation::new(
        wall_world(),
        SensorPreset::Urg04lx,
        LaserNoise::off(),
        MotionNoise::off(),
        0.0,
        Pose2::new(1.99, 0.0, 0.0),
        1,
    )
    .split();
    let c = l.geometry().nearest_index(0.0).unwrap();
    let s = l.next_scan().unwrap();
    assert!(matches!(s.status[c], RayStatus::Error(_)));
    assert_eq!(t.scans_taken(), 1);
}

#[test]
fn same_seed_same_run_different_seed_different_run() {
    let run = |seed| {
        let (mut l, mut b, t) = Simulation::with_preset(
            Arc::new(World::paper()),
            SensorPreset::Paper,
            sim_laser::paper_start(),
            seed,
        )
        .split();
        let mut ranges = Vec::new();
        for _ in 0..3 {
            ranges.extend(l.next_scan().unwrap().ranges_m);
            b.rotate(0.2).unwrap();
            b.forward(0.3).unwrap();
        }
        (ranges, t.pose())
    };
    let (a, pa) = run(5);
    let (b, pb) = run(5);
    let (c, pc) = run(6);
    assert_eq!(a.len(), b.len());
    assert!(
        a.iter()
            .zip(&b)
            .all(|(x, y)| x == y || (x.is_nan() && y.is_nan()))
    );
    assert_eq!(pa, pb);
    assert_ne!(pa, pc);
    assert!(a.iter().zip(&c).any(|(x, y)| x != y));
}

#[test]
fn one_scale_factor_per_drive() {
    let motion = MotionNoise {
        rotation_sigma_rad: 0.0,
        drive_scale_sigma: 0.05,
    };
    let world = Arc::new(World::from_parts(WorldParts::default()).unwrap());
    let mk = || {
        Simulation::new(
            world.clone(),
            SensorPreset::Paper,
            LaserNoise::off(),
            motion,
            0.3,
            Pose2::default(),
            9,
        )
        .split()
    };
    let (_, mut b1, t1) = mk();
    for _ in 0..20 {
        b1.forward(0.05).unwrap();
    }
    let (_, mut b2, t2) = mk();
    b2.forward(1.0).unwrap();
    assert!((t1.pose().x_m - t2.pose().x_m).abs() < 1e-9);
    assert!((t1.pose().x_m - 1.0).abs() > 1e-6, "noise was applied");
    // A rotation in between starts a new drive with a new factor.
    let (_, mut b3, t3) = mk();
    b3.forward(0.5).unwrap();
    b3.rotate(0.0).unwrap();
    b3.forward(0.5).unwrap();
    assert!((t3.pose().x_m - t2.pose().x_m).abs() > 1e-9);
    // Factors over many drives have the configured sigma.
    let (_, mut b, t) = mk();
    let mut f = Vec::new();
    for _ in 0..2000 {
        let x0 = t.pose().x_m;
        b.forward(1.0).unwrap();
        f.push(t.pose().x_m - x0);
        b.rotate(0.0).unwrap();
    }
    let sd = std_dev(&f);
    assert!((sd - 0.05).abs() < 0.005, "scale sigma {sd}");
}

#[test]
fn rotation_noise_has_one_degree_sigma() {
    let world = Arc::new(World::from_parts(WorldParts::default()).unwrap());
    let (_, mut b, t) = Simulation::new(
        world,
        SensorPreset::Paper,
        LaserNoise::off(),
        MotionNoise::default(),
        0.3,
        Pose2::default(),
        10,
    )
    .split();
    let mut errs = Vec::new();
    for _ in 0..2000 {
        let before = t.pose().theta_rad;
        b.rotate(0.5).unwrap();
        errs.push(scan_types::angle_diff_rad(t.pose().theta_rad, before) - 0.5);
    }
    let sd = std_dev(&errs).to_degrees();
    assert!((sd - 1.0).abs() < 0.1, "rotation sigma {sd} deg");
    assert_eq!(t.rotations(), 2000);
}

#[test]
fn collision_stops_the_disc_at_contact() {
    let (_, mut b, t) = sim(LaserNoise::off(), MotionNoise::off(), 1).split();
    b.forward(5.0).unwrap();
    // Disc of 0.3 m against the wall at x = 2: stops at x = 1.7.
    assert!((t.pose().x_m - 1.7).abs() < 1e-3, "{:?}", t.pose());
    assert_eq!(t.collisions(), 1);
    let c = t.collision_log()[0];
    assert!((c.achieved_m - 1.7).abs() < 1e-3 && c.commanded_m == 5.0);
    // Further forward is refused and recorded; backing off works.
    b.forward(0.5).unwrap();
    assert_eq!(t.collisions(), 2);
    b.forward(-1.0).unwrap();
    assert!((t.pose().x_m - 0.7).abs() < 2e-3);
    assert_eq!(t.collisions(), 2);
    assert!(b.forward(f64::NAN).is_err());
    assert!(b.rotate(f64::INFINITY).is_err());
}

#[test]
fn scans_advance_the_clock_at_the_scan_rate() {
    let (mut l, mut b, t) = sim(LaserNoise::off(), MotionNoise::off(), 1).split();
    let s0 = l.next_scan().unwrap();
    let s1 = l.next_scan().unwrap();
    assert!((s1.host_time_s - s0.host_time_s - 0.1).abs() < 1e-12);
    b.forward(0.3).unwrap(); // 1 s at 0.3 m/s
    let s2 = l.next_scan().unwrap();
    assert!((s2.host_time_s - 1.1).abs() < 1e-9, "{}", s2.host_time_s);
    assert_eq!(t.scans_taken(), 3);
}
