//! The goal-seeking loop's cost per scan, and each of its steps alone.
//!
//! `navigator/paper_run` feeds the scans of a whole simulated paper run (seed 0, default
//! noise) to a fresh [`navigator::Navigator`] through its step API, answering every motion at
//! once: the navigator's real cycle (expand, plan, measure each rotation, detect and select
//! landmarks, triangle OBC, track, scan-match, map), with no simulator in the timing. Its
//! throughput is scans per second; the time per scan is the median divided by the scan count
//! printed at the start. Goal: at most 0.5 ms per scan.
//!
//! `navigator/paper_run_replan` is the same with `[planner] replan_step_m = 0.25` (the run
//! recorded with it).
//!
//! `cycle_step/*` times each step alone on 685-ray scans of the paper world, with the
//! parameters the navigator derives from the goalseek preset.
//!
//! Run: `cargo bench --bench cycle -- --quick`.
#![allow(clippy::print_stderr, clippy::print_stdout)] // benches and tests report to the terminal

use std::hint::black_box;
use std::sync::Arc;

use criterion::{BatchSize, Criterion, Throughput, criterion_group, criterion_main};
use expansion::Expander;
use landmarks::{Tracker, detect, select};
use localiser::OccupancyGrid;
use navigator::{Action, Monitor, Navigator, Params};
use planner::Planner;
use scan_types::{LaserSource, Pose2, Scan, ScanGeometry, WorldPoint};
use sim_laser::{MotionNoise, SensorPreset, Simulation, World, paper_start, paper_target};

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
    [paper_start(), Pose2::new(-2.09, -2.34, 50f64.to_radians())]
        .into_iter()
        .map(|pose| {
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

/// Keeps every scan the navigator accepted.
#[derive(Default)]
struct Scans(Vec<Scan>);

impl Monitor for Scans {
    fn scan(&mut self, scan: &Scan, _estimate: &Pose2) {
        self.0.push(scan.clone());
    }
}

/// goalseek's parameters with `[planner] replan_step_m` set.
fn with_replan(replan_step_m: f64) -> Params {
    let mut p = Params::goalseek();
    p.planner.replan_step_m = replan_step_m;
    p
}

/// The scans of the simulated paper run, seed 0, in the order the navigator took them.
fn paper_run_scans(params: Params) -> Vec<Scan> {
    let preset = SensorPreset::Paper;
    let sim = Simulation::new(
        Arc::new(World::paper()),
        preset,
        preset.default_noise(),
        MotionNoise::default(),
        params.robot.radius_m,
        paper_start(),
        0,
    );
    let (mut laser, mut base, _truth) = sim.split();
    let nav = Navigator::new(params, *laser.geometry(), paper_start(), paper_target()).unwrap();
    let mut scans = Scans::default();
    let outcome = navigator::run(nav, &mut laser, &mut base, &mut scans);
    assert_eq!(
        outcome.reason,
        navigator::Reason::Reached,
        "{}",
        outcome.note
    );
    scans.0
}

/// Feeds `scans` to `nav`, every motion done at once; returns the legs driven.
fn replay(mut nav: Navigator, scans: &[Scan]) -> usize {
    let mut next = scans.iter();
    let mut action = nav.pending();
    loop {
        action = match action {
            Action::Scan => match next.next() {
                Some(s) => nav.on_scan(s),
                None => break,
            },
            Action::Rotate { .. } | Action::Forward { .. } => nav.on_motion_done(),
            Action::Finish(_) => break,
        };
    }
    nav.into_outcome().legs_driven
}

fn bench_cycle(c: &mut Criterion) {
    let g = ScanGeometry::paper();
    assert_eq!(g.ray_count, 685);
    // goalseek as it is, and with the leg checked every 0.25 m while driving.
    let mut group = c.benchmark_group("navigator");
    for (name, step) in [
        ("paper_run", Params::goalseek().planner.replan_step_m),
        ("paper_run_replan", 0.25),
    ] {
        let scans = paper_run_scans(with_replan(step));
        let new = || Navigator::new(with_replan(step), g, paper_start(), paper_target()).unwrap();
        // The replay drives the same run: every recorded scan is used.
        let legs = replay(new(), &scans);
        println!("{name}: {} scans, {legs} legs", scans.len());
        group.throughput(Throughput::Elements(scans.len() as u64));
        group.bench_function(name, |b| {
            b.iter_batched(
                new,
                |nav| black_box(replay(nav, &scans)),
                BatchSize::SmallInput,
            )
        });
    }
    group.finish();

    let cfg = Params::goalseek();
    let (detect_p, select_p, track_p) = cfg.landmark_params();
    let stops = stops(&g);
    let target = WorldPoint::new(4.0, 4.0);
    let mut expander = Expander::new(&g);
    let mut clearances = vec![0.0; g.ray_count];
    let mut planner = Planner::new(cfg.planner_params());
    let mut grid = OccupancyGrid::new(cfg.localiser.map_resolution_m);
    for s in &stops {
        grid.integrate(&s.pose, &g, &s.stepped);
        planner.add_scan(&s.pose, &g, &s.stepped);
    }

    // Each step alone, to see where a cycle's time goes.
    let mut steps = c.benchmark_group("cycle_step");
    let s = &stops[0];
    let r = cfg.expansion_radius_m();
    steps.bench_function("expand", |b| {
        b.iter(|| expander.clearances(black_box(&s.before), r, &mut clearances))
    });
    steps.bench_function("plan", |b| {
        b.iter(|| black_box(planner.plan(&s.pose, &g, &s.before, &clearances, target)))
    });
    steps.bench_function("measure_rotation", |b| {
        b.iter(|| {
            black_box(localiser::measure_rotation(
                &g,
                &s.before,
                &s.after,
                TURN_RAD,
                cfg.localiser.rotation_search_deg.to_radians(),
            ))
        })
    });
    steps.bench_function("detect_select", |b| {
        b.iter(|| black_box(select(&detect(&g, &s.after, &detect_p), &select_p)))
    });
    let lm = select(&detect(&g, &s.after, &detect_p), &select_p).expect("a landmark");
    steps.bench_function("track_step", |b| {
        b.iter(|| black_box(Tracker::new(lm, track_p).update(&g, &s.stepped, 0.05)))
    });
    let mp = localiser::MatchParams::default();
    steps.bench_function("scan_match", |b| {
        b.iter(|| {
            let mut reference = localiser::MatchTarget::from_scan(&g, &s.after, &mp);
            black_box(reference.align(&g, &s.stepped, Pose2::new(0.05, 0.0, 0.0), &mp))
        })
    });
    // A revisit match: a target of three earlier scans (before and after the turn, and 5 cm on),
    // the last one aligned from a guess 3 cm and 0.6 deg off.
    steps.bench_function("revisit_match", |b| {
        b.iter(|| {
            let mut t = localiser::MatchTarget::new();
            t.add_scan(&Pose2::new(0.0, 0.0, -TURN_RAD), &g, &s.before, &mp);
            t.add_scan(&Pose2::default(), &g, &s.after, &mp);
            t.add_scan(&Pose2::new(0.05, 0.0, 0.0), &g, &s.stepped, &mp);
            black_box(t.align(&g, &s.stepped, Pose2::new(0.08, 0.01, 0.01), &mp))
        })
    });
    let axes = localiser::AxesParams::default();
    steps.bench_function("wall_axes", |b| {
        b.iter(|| black_box(localiser::wall_axes(&g, black_box(&s.after), &axes)))
    });
    steps.bench_function("grid_integrate", |b| {
        b.iter(|| black_box(grid.integrate(&s.pose, &g, &s.stepped)))
    });
    steps.bench_function("planner_add_scan", |b| {
        b.iter(|| planner.add_scan(&s.pose, &g, black_box(&s.stepped)))
    });
    steps.finish();
}

criterion_group!(benches, bench_cycle);
criterion_main!(benches);
