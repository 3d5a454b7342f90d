//! One whole cycle of the goal-seeking loop (docs/method.md, "One cycle") on 685-ray scans of
//! the paper's world, with the crates' public APIs called as `robot_app::navigator` calls them:
//! expand, plan, measure the rotation, detect and select a landmark, triangle OBC, one tracking
//! step, one scan match (the goalseek travel rule), map update (occupancy grid and planner
//! memory). Goal: at most 0.5 ms per cycle. `cycle_step/*` times each step alone.
//!
//! `cycle` alternates between two poses of the first leg (start and near B), so every cycle
//! updates the maps; `cycle_new_field` also alternates the target, which forces the planner to
//! recompute its path-length field every cycle (the worst case: on a real run the map grows
//! every leg).
//!
//! Run: `cargo bench --bench cycle -- --quick`.
#![allow(clippy::print_stderr, clippy::print_stdout)] // benches and tests report to the terminal

use std::hint::black_box;
use std::sync::Arc;

use criterion::{Criterion, criterion_group, criterion_main};
use expansion::Expander;
use landmarks::{DetectParams, SelectParams, TrackParams, Tracker, detect, select};
use localiser::OccupancyGrid;
use planner::{Plan, Planner};
use robot_app::config::{Config, Method, TravelRuleCfg};
use scan_types::{LaserSource, Pose2, Scan, ScanGeometry, WorldPoint};
use sim_laser::{MotionNoise, SensorPreset, Simulation, World};

/// Scans before and after a rotation, and after one 5 cm tracking step, at one pose.
struct Stop {
    pose: Pose2,
    before: Scan,
    after: Scan,
    stepped: Scan,
}

const TURN_RAD: f64 = 0.2;

fn stops(g: &ScanGeometry) -> Vec<Stop> {
    let preset = SensorPreset::Paper;
    let sim = Simulation::new(
        Arc::new(World::paper()),
        preset,
        preset.default_noise(),
        MotionNoise::off(),
        0.3,
        Pose2::new(0.0, 0.0, 0.0),
        1,
    );
    let (mut laser, _base, truth) = sim.split();
    assert_eq!(laser.geometry(), g);
    // The paper's start and a pose near its first point B.
    [(-3.92, -4.26, 45f64), (-2.09, -2.34, 50.0)]
        .iter()
        .map(|&(x, y, deg)| {
            let pose = Pose2::new(x, y, deg.to_radians());
            truth.teleport(pose);
            let before = laser.next_scan().unwrap();
            let turned = pose.rotated(TURN_RAD);
            truth.teleport(turned);
            let after = laser.next_scan().unwrap();
            truth.teleport(turned.advanced(0.05));
            let stepped = laser.next_scan().unwrap();
            Stop {
                pose: turned,
                before,
                after,
                stepped,
            }
        })
        .collect()
}

/// The loop's per-run state, set up as `Navigator::new` does for the goalseek preset.
struct Cycle {
    cfg: Config,
    g: ScanGeometry,
    expander: Expander,
    clearances: Vec<f64>,
    planner: Planner,
    grid: OccupancyGrid,
    detect: DetectParams,
    select: SelectParams,
    track: TrackParams,
}

impl Cycle {
    fn new(g: ScanGeometry) -> Self {
        let cfg = Config::preset(Method::Goalseek);
        let (detect, select, track) = robot_app::navigator::landmark_params(&cfg);
        Self {
            expander: Expander::new(&g),
            clearances: vec![0.0; g.ray_count],
            planner: Planner::new(robot_app::navigator::planner_params(&cfg)),
            grid: OccupancyGrid::new(cfg.localiser.map_resolution_m),
            cfg,
            g,
            detect,
            select,
            track,
        }
    }

    /// One cycle at `s` toward `target`; returns something derived from every step.
    fn run(&mut self, s: &Stop, target: WorldPoint) -> f64 {
        let g = &self.g;
        // Expand and plan.
        let r = self.cfg.robot.radius_m + self.cfg.robot.expansion_margin_m;
        self.expander.clearances(&s.before, r, &mut self.clearances);
        let plan = self
            .planner
            .plan(&s.pose, g, &s.before, &self.clearances, target);
        let alpha = match plan {
            Plan::Go { alpha_rad, .. } => alpha_rad,
            _ => 0.0,
        };
        // Rotate: measure the rotation on the scans, clearance ahead after it.
        let turned = localiser::measure_rotation(
            g,
            &s.before,
            &s.after,
            TURN_RAD,
            self.cfg.localiser.rotation_search_deg.to_radians(),
        )
        .unwrap_or(TURN_RAD);
        self.expander.clearances(&s.after, r, &mut self.clearances);
        // Landmarks in front, the nearest usable one, triangle OBC.
        let found = detect(g, &s.after, &self.detect);
        let mut out = alpha + turned + found.len() as f64;
        if let Some(lm) = select(&found, &self.select) {
            let tri = localiser::triangle(&s.pose, lm.range_m, lm.bearing_rad);
            out += tri.point_b.x_m();
            // One tracking step while driving to B.
            let mut tracker = Tracker::new(lm, self.track);
            out += match tracker.update(g, &s.stepped, 0.05) {
                landmarks::TrackUpdate::Tracked(l) => l.range_m,
                _ => 0.0,
            };
        }
        // Scan-matched travel (goalseek's default travel rule): the reference scan and one
        // alignment, as each keyframe of a drive does.
        if self.cfg.localiser.travel_rule == TravelRuleCfg::ScanMatched {
            let params = localiser::MatchParams::default();
            let mut reference = localiser::MatchTarget::from_scan(g, &s.after, &params);
            let guess = Pose2::new(0.05, 0.0, 0.0);
            if let Some(m) = reference.align(g, &s.stepped, guess, &params) {
                out += m.pose.x_m;
            }
        }
        // Map with the localised scan.
        self.grid.integrate(&s.pose, g, &s.stepped);
        self.planner.add_scan(&s.pose, g, &s.stepped);
        out
    }
}

fn bench_cycle(c: &mut Criterion) {
    let g = ScanGeometry::paper();
    assert_eq!(g.ray_count, 685);
    let stops = stops(&g);
    let target = WorldPoint::new(4.0, 4.0);
    let other = WorldPoint::new(3.0, 4.0);
    let mut group = c.benchmark_group("cycle");

    let mut cycle = Cycle::new(g);
    // Sanity: the first stop selects a landmark and the planner finds a way.
    assert!(!detect(&g, &stops[0].after, &cycle.detect).is_empty());
    let mut k = 0usize;
    group.bench_function("cycle", |b| {
        b.iter(|| {
            k += 1;
            black_box(cycle.run(&stops[k % 2], target))
        })
    });

    let mut cycle = Cycle::new(g);
    let mut k = 0usize;
    group.bench_function("cycle_new_field", |b| {
        b.iter(|| {
            k += 1;
            let t = if (k / 2).is_multiple_of(2) {
                target
            } else {
                other
            };
            black_box(cycle.run(&stops[k % 2], t))
        })
    });
    group.finish();

    // Each step alone, to see where a cycle's time goes.
    let mut steps = c.benchmark_group("cycle_step");
    let mut cy = Cycle::new(g);
    for _ in 0..4 {
        cy.run(&stops[0], target);
        cy.run(&stops[1], target);
    }
    let s = &stops[0];
    let r = cy.cfg.robot.radius_m + cy.cfg.robot.expansion_margin_m;
    steps.bench_function("expand", |b| {
        b.iter(|| {
            cy.expander
                .clearances(black_box(&s.before), r, &mut cy.clearances)
        })
    });
    steps.bench_function("plan", |b| {
        b.iter(|| {
            black_box(
                cy.planner
                    .plan(&s.pose, &g, &s.before, &cy.clearances, target),
            )
        })
    });
    steps.bench_function("measure_rotation", |b| {
        b.iter(|| {
            black_box(localiser::measure_rotation(
                &g,
                &s.before,
                &s.after,
                TURN_RAD,
                cy.cfg.localiser.rotation_search_deg.to_radians(),
            ))
        })
    });
    steps.bench_function("detect_select", |b| {
        b.iter(|| black_box(select(&detect(&g, &s.after, &cy.detect), &cy.select)))
    });
    let lm = select(&detect(&g, &s.after, &cy.detect), &cy.select).expect("a landmark");
    steps.bench_function("track_step", |b| {
        b.iter(|| black_box(Tracker::new(lm, cy.track).update(&g, &s.stepped, 0.05)))
    });
    let mp = localiser::MatchParams::default();
    steps.bench_function("scan_match", |b| {
        b.iter(|| {
            let mut reference = localiser::MatchTarget::from_scan(&g, &s.after, &mp);
            black_box(reference.align(&g, &s.stepped, Pose2::new(0.05, 0.0, 0.0), &mp))
        })
    });
    steps.bench_function("grid_integrate", |b| {
        b.iter(|| black_box(cy.grid.integrate(&s.pose, &g, &s.stepped)))
    });
    steps.bench_function("planner_add_scan", |b| {
        b.iter(|| cy.planner.add_scan(&s.pose, &g, black_box(&s.stepped)))
    });
    steps.finish();
}

criterion_group!(benches, bench_cycle);
criterion_main!(benches);
