//! End to end through the sensor protocol: simulator -> SCIP 2.0 emulator -> urg-driver ->
//! the goal-seeking loop gives the same legs as the simulator connected directly, same seed,
//! with the emulator in memory and behind a pseudo-terminal.
//!
//! SCIP carries ranges as integer millimetres, clamped to the sensor's [DMIN, DMAX - 1], and
//! "no return" as code 0. So the direct run reads its scans through [`Millimetres`], which
//! applies exactly that quantisation; with it the two runs must agree bit for bit (same
//! commands, same landmarks, same points B, same estimates). Without it they may differ from
//! the first landmark fix on, since sub-millimetre range differences move the estimates.
#![allow(clippy::print_stderr, clippy::print_stdout)] // tests report to the terminal

use std::sync::Arc;

use navigator::{Method, Params};
use robot_app::runloop::{LoopRun, run_loop};
use scan_types::{LaserSource, MotionBase, RayStatus, Scan, ScanGeometry};
use sim_laser::{
    MotionNoise, SensorPreset, Simulation, TruthHandle, World, paper_start, paper_target,
};
use urg_driver::{Emulator, Model, Profile, Urg, UrgConfig};

/// The URG-04LX's distance limits (PP: DMIN 20 mm, DMAX 5600 mm).
const DMIN_MM: f64 = 20.0;
const DMAX_MM: f64 = 5600.0;

/// A laser seen through SCIP's integer millimetres, as the URG-04LX reports it.
struct Millimetres<L>(L);

impl<L: LaserSource> LaserSource for Millimetres<L> {
    type Error = L::Error;
    fn geometry(&self) -> &ScanGeometry {
        self.0.geometry()
    }
    fn next_scan(&mut self) -> Result<Scan, L::Error> {
        let mut s = self.0.next_scan()?;
        let max_m = DMAX_MM / 1000.0;
        for (r, st) in s.ranges_m.iter_mut().zip(s.status.iter_mut()) {
            match *st {
                RayStatus::Hit if r.is_finite() => {
                    let mm = (*r * 1000.0).round().clamp(DMIN_MM, DMAX_MM - 1.0);
                    *r = mm / 1000.0;
                }
                // Error codes below DMIN survive; code 0 means "no return".
                RayStatus::Error(c) if c != 0 => {
                    *st = RayStatus::Error(c.min(DMIN_MM as u16 - 1));
                    *r = f64::NAN;
                }
                _ => {
                    *st = RayStatus::MaxRange;
                    *r = max_m;
                }
            }
        }
        s.intensities = None;
        Ok(s)
    }
}

/// A motion base that records every command it passes on.
struct Recording<M> {
    inner: M,
    commands: Vec<(char, f64)>,
}

impl<M: MotionBase> MotionBase for Recording<M> {
    type Error = M::Error;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), M::Error> {
        self.commands.push(('r', angle_rad));
        self.inner.rotate(angle_rad)
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), M::Error> {
        self.commands.push(('f', distance_m));
        self.inner.forward(distance_m)
    }
    fn stop(&mut self) -> Result<(), M::Error> {
        self.inner.stop()
    }
}

fn config() -> Params {
    let mut c = Params::preset(Method::Goalseek);
    // Enough legs to cover several landmark fixes; keeps the test short.
    c.navigator.max_legs = 8;
    c
}

fn simulation(world: &Arc<World>, seed: u64) -> Simulation {
    let preset = SensorPreset::Urg04lx;
    Simulation::new(
        world.clone(),
        preset,
        preset.default_noise(),
        MotionNoise::default(),
        config().robot.radius_m,
        paper_start(),
        seed,
    )
}

struct Run {
    run: LoopRun,
    commands: Vec<(char, f64)>,
    scans_cast: u64,
    geometry: ScanGeometry,
}

fn drive<L: LaserSource>(laser: &mut L, base: sim_laser::SimBase, truth: &TruthHandle) -> Run {
    let geometry = *laser.geometry();
    let mut base = Recording {
        inner: base,
        commands: Vec::new(),
    };
    let cfg = config();
    let run = run_loop(
        laser,
        &mut base,
        &cfg,
        (paper_start(), paper_target()),
        Some(truth),
        None,
    )
    .unwrap();
    Run {
        run,
        commands: base.commands,
        scans_cast: truth.scans_taken(),
        geometry,
    }
}

fn direct(world: &Arc<World>, seed: u64, quantise: bool) -> Run {
    let (laser, base, truth) = simulation(world, seed).split();
    if quantise {
        drive(&mut Millimetres(laser), base, &truth)
    } else {
        let mut laser = laser;
        drive(&mut laser, base, &truth)
    }
}

fn through_emulator(world: &Arc<World>, seed: u64) -> Run {
    let (laser, base, truth) = simulation(world, seed).split();
    let emulator = Emulator::new(Profile::of(Model::Urg04lx), laser);
    let mut urg = Urg::connect(
        emulator,
        UrgConfig {
            time_sync_rounds: 0,
            ..UrgConfig::default()
        },
    )
    .expect("the driver connects to the emulator");
    drive(&mut urg, base, &truth)
}

/// The same, with the emulator behind a pseudo-terminal that the driver opens like a serial port.
fn through_pty(world: &Arc<World>, seed: u64) -> Run {
    let (laser, base, truth) = simulation(world, seed).split();
    let server = urg_driver::serve_pty(Profile::of(Model::Urg04lx), laser).expect("a pty");
    let mut urg = Urg::open(
        server.path(),
        UrgConfig {
            time_sync_rounds: 0,
            ..UrgConfig::default()
        },
    )
    .expect("the driver opens the pty");
    let run = drive(&mut urg, base, &truth);
    drop(urg);
    server.stop();
    run
}

fn assert_same_legs(a: &Run, b: &Run, what: &str) {
    assert_eq!(a.geometry, b.geometry, "{what}: scan geometry");
    assert_eq!(
        a.run.outcome.reason, b.run.outcome.reason,
        "{what}: end reason"
    );
    assert_eq!(
        a.run.outcome.legs_driven, b.run.outcome.legs_driven,
        "{what}: legs"
    );
    assert_eq!(a.run.outcome.scans, b.run.outcome.scans, "{what}: scans");
    // The emulator asked the simulator for exactly one scan per GD.
    assert_eq!(a.scans_cast, b.scans_cast, "{what}: scans cast");
    assert_eq!(a.commands.len(), b.commands.len(), "{what}: commands");
    for (i, (x, y)) in a.commands.iter().zip(&b.commands).enumerate() {
        assert_eq!(x, y, "{what}: command {i}");
    }
    let (la, lb) = (&a.run.log.legs, &b.run.log.legs);
    assert_eq!(la.len(), lb.len(), "{what}: leg records");
    for (x, y) in la.iter().zip(lb) {
        let leg = x.leg;
        assert_eq!(x.leg, y.leg);
        assert_eq!(x.landmark, y.landmark, "{what}: landmark of leg {leg}");
        assert_eq!(x.point_b, y.point_b, "{what}: point B of leg {leg}");
        assert_eq!(x.estimate, y.estimate, "{what}: estimate after leg {leg}");
        assert_eq!(x.truth, y.truth, "{what}: true pose after leg {leg}");
        assert_eq!(x.scan_points, y.scan_points, "{what}: scan of leg {leg}");
    }
}

#[test]
fn emulated_hokuyo_gives_the_same_legs_as_the_direct_simulator() {
    let world = Arc::new(World::paper());
    for seed in [0u64, 7] {
        let direct_run = direct(&world, seed, true);
        let emulated = through_emulator(&world, seed);
        // The driver reports the URG-04LX geometry of PP, the preset the simulator casts.
        assert_eq!(emulated.geometry, SensorPreset::Urg04lx.geometry());
        assert_eq!(emulated.geometry.ray_count, 725 - 44 + 1);
        let fixes = direct_run
            .run
            .log
            .legs
            .iter()
            .filter(|l| l.point_b.is_some())
            .count();
        println!(
            "seed {seed}: {} legs ({fixes} landmark fixes), {} scans, {} commands, {}",
            direct_run.run.outcome.legs_driven,
            direct_run.run.outcome.scans,
            direct_run.commands.len(),
            direct_run.run.outcome.reason
        );
        // Something to compare: the runs drove and fixed landmarks.
        assert!(direct_run.run.outcome.legs_driven >= 2 && fixes >= 1);
        assert_same_legs(&direct_run, &emulated, &format!("seed {seed}"));

        if seed == 0 {
            assert_same_legs(&direct_run, &through_pty(&world, seed), "pty, seed 0");
        }

        // For the record: whether quantisation alone changes the run.
        let raw = direct(&world, seed, false);
        let same = raw.commands == direct_run.commands;
        println!("seed {seed}: unquantised direct run gives the same commands: {same}");
    }
}
