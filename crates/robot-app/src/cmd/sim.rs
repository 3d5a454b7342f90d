//! `robot-app sim`: goal seeking in the simulator. With no arguments: the paper's scenario.

use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::Args;
use scan_types::{Pose2, WorldPoint};
use sim_laser::{GeodesicMap, SensorPreset, SimSetup, paper_start, paper_target};

use crate::config::Params;
use crate::outputs::{PointOut, PoseOut, Reason, Summary, spl, write_summary};
use crate::runloop::run_loop_legs;
use scan_log::write_trajectory;

/// A simulated run counts as a success when the true position ends this close to the target.
pub const SUCCESS_RADIUS_M: f64 = 0.3;

/// The simulated world, sensor, seed and noise: the options `sim` and `explore` share.
#[derive(Debug, Clone, Args)]
pub struct SimWorldArgs {
    /// World file: goalseek .toml (with its own start and target), map_server .yaml, or a
    /// Stage .png (0.02 m per pixel; give another size in a .yaml or .toml beside it). Default:
    /// the paper's world.
    #[arg(long, value_name = "PATH")]
    pub world: Option<PathBuf>,
    /// Sensor preset: paper, urg-04lx, utm-30lx or ust-10lx.
    #[arg(long, default_value = "paper")]
    pub sensor: String,
    /// Noise seed.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// `off` turns laser and motion noise off; `on` (or `default`) keeps the preset's noise.
    #[arg(long, value_enum, default_value = "on")]
    pub noise: super::Noise,
}

impl SimWorldArgs {
    /// The simulation these options give (its start still the world's default).
    pub fn setup(&self) -> anyhow::Result<SimSetup> {
        let mut setup = match &self.world {
            None => SimSetup::load(None)?,
            Some(p) => SimSetup::load(Some(p))
                .with_context(|| format!("cannot load world {}", p.display()))?,
        };
        setup.sensor = self
            .sensor
            .parse::<SensorPreset>()
            .map_err(|e| anyhow::anyhow!("--sensor {}: {e}", self.sensor))?;
        setup.seed = self.seed;
        setup.noise = self.noise.is_on();
        Ok(setup)
    }
}

/// Arguments of `robot-app sim`.
#[derive(Debug, Args)]
pub struct SimArgs {
    /// World, sensor, seed and noise.
    #[command(flatten)]
    pub sim: SimWorldArgs,
    /// Start pose X,Y,THETA_DEG (default: the paper's -3.92,-4.26,45).
    #[arg(long, value_name = "X,Y,THETA_DEG", allow_hyphen_values = true)]
    pub start: Option<String>,
    /// Target X,Y (default: the paper's 4,4).
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub goal: Option<String>,
    /// Configuration, output folder, recording.
    #[command(flatten)]
    pub options: super::LoopOptions,
    /// Live view, paced by the simulated clock.
    #[command(flatten)]
    pub live: crate::live::PacedLiveOptions,
}

/// Everything that defines one simulated run: the simulation, the target and the tuning.
#[derive(Debug, Clone)]
pub struct SimSpec {
    /// World, sensor, seed, noise, robot radius (the configuration's) and start pose (true and
    /// initial estimate).
    pub setup: SimSetup,
    /// Target.
    pub goal: WorldPoint,
    /// Tuning.
    pub config: Params,
}

impl SimSpec {
    /// A run of `setup` to `goal` tuned by `config`, the robot radius taken from `config`.
    pub fn new(mut setup: SimSetup, goal: WorldPoint, config: Params) -> Self {
        setup.robot_radius_m = config.robot.radius_m;
        Self {
            setup,
            goal,
            config,
        }
    }

    /// The paper's scenario with a seed and a configuration.
    pub fn paper(seed: u64, config: Params) -> Self {
        Self::new(SimSetup::paper(seed), paper_target(), config)
    }
}

/// One simulated run: its summary and the navigator's outcome.
pub struct SimRun {
    /// What `summary.json` holds.
    pub summary: Summary,
    /// The navigator's outcome.
    pub outcome: navigator::Outcome,
    /// Leg ends with the true pose beside the estimate.
    pub log: scan_log::RunLog,
}

/// CPU time of the calling thread, seconds.
pub fn thread_cpu_time_s() -> f64 {
    // Linux: the first field of schedstat is the time on CPU in nanoseconds.
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |ns| ns * 1e-9)
}

/// Called with every scan of a simulated run, its true pose and the navigator's estimate.
pub type ScanObserver<'a> = &'a mut dyn FnMut(&scan_types::Scan, Pose2, Pose2);

/// Runs one simulated run (no files written).
pub fn simulate(
    spec: &SimSpec,
    on_scan: Option<&mut dyn FnMut(&scan_types::Scan)>,
) -> anyhow::Result<SimRun> {
    match on_scan {
        None => simulate_observed(spec, None),
        Some(f) => simulate_observed(spec, Some(&mut |s, _, _| f(s))),
    }
}

/// Runs one simulated run (no files written), showing every scan with its true pose and the
/// navigator's estimate to `observer`.
pub fn simulate_observed(spec: &SimSpec, observer: Option<ScanObserver>) -> anyhow::Result<SimRun> {
    simulate_inner(spec, observer, None, geodesic_of(spec))
}

/// [`simulate_observed`] that also shows every leg end to `legs`.
pub fn simulate_watched(
    spec: &SimSpec,
    observer: Option<ScanObserver>,
    legs: Option<crate::runloop::LegHook>,
) -> anyhow::Result<SimRun> {
    simulate_inner(spec, observer, legs, geodesic_of(spec))
}

/// Runs one simulated run (no files written) whose geodesic is already known.
pub fn simulate_with_geodesic(spec: &SimSpec, geodesic_m: Option<f64>) -> anyhow::Result<SimRun> {
    simulate_inner(spec, None, None, geodesic_m)
}

/// The free space of `spec`'s world for its robot, for geodesics; `None` (logged) when the
/// world is too large.
pub fn geodesic_map(spec: &SimSpec) -> Option<GeodesicMap> {
    GeodesicMap::new(&spec.setup.world, spec.setup.robot_radius_m)
        .inspect_err(|e| tracing::warn!("no geodesic, SPL null: {e}"))
        .ok()
}

/// The geodesic of `spec` (its start to its target for its robot) in `map`; `None` (logged)
/// when no free path joins them.
pub fn geodesic_in(map: &GeodesicMap, spec: &SimSpec) -> Option<f64> {
    let l = map.length_m(spec.setup.start.position(), spec.goal);
    if l.is_none() {
        tracing::warn!(
            world = %spec.setup.world_name,
            seed = spec.setup.seed,
            "no free path from the start to the target for the robot: geodesic and SPL null"
        );
    }
    l
}

/// The geodesic of `spec`, computed for this run alone.
pub fn geodesic_of(spec: &SimSpec) -> Option<f64> {
    geodesic_map(spec).and_then(|m| geodesic_in(&m, spec))
}

fn simulate_inner(
    spec: &SimSpec,
    mut observer: Option<ScanObserver>,
    legs: Option<crate::runloop::LegHook>,
    geodesic_m: Option<f64>,
) -> anyhow::Result<SimRun> {
    let cpu0 = thread_cpu_time_s();
    let sim = spec.setup.build()?;
    let (mut laser, mut base, truth) = sim.split();
    let observed = observer.is_some();
    let mut pose_hook = |s: &scan_types::Scan, e: &Pose2| {
        if let Some(o) = observer.as_mut() {
            o(s, truth.pose(), *e);
        }
    };
    let hook: Option<crate::runloop::ScanPoseHook> =
        if observed { Some(&mut pose_hook) } else { None };
    let run = run_loop_legs(
        &mut laser,
        &mut base,
        &spec.config,
        (spec.setup.start, spec.goal),
        Some(&truth),
        hook,
        legs,
    )?;
    let outcome = &run.outcome;
    let cpu = thread_cpu_time_s() - cpu0;
    let t = truth.pose();
    let collisions = truth.collisions();
    let travelled = truth.travelled_m();
    let goal_distance = t.position().distance_m(&spec.goal);
    let reason = if collisions > 0 {
        Reason::Collision
    } else {
        outcome.reason
    };
    let reached = reason == Reason::Reached && collisions == 0 && goal_distance <= SUCCESS_RADIUS_M;
    let (fe, fh) = run
        .log
        .final_errors()
        .map_or((None, None), |(p, h)| (Some(p), Some(h)));
    let mut note = outcome.note.clone();
    let mut reason = reason;
    if reason == Reason::Reached && !reached {
        reason = Reason::FalseArrival;
        let beside = outcome.estimate.position().distance_m(&spec.goal)
            > spec.config.navigator.goal_tolerance_m;
        note = if beside {
            // Stopped beside a target inside a wall's clearance: the navigator's note says where.
            format!(
                "{}; the robot is {goal_distance:.2} m from it",
                outcome.note
            )
        } else {
            format!("the estimate reached the target but the robot is {goal_distance:.2} m from it")
        };
    }
    let (position_sigma_m, heading_sigma_deg) = crate::outputs::leg_sigmas(outcome);
    let summary = Summary {
        reached,
        reason,
        legs: outcome.legs_driven,
        scans: outcome.scans,
        collisions,
        commanded_path_length_m: outcome.path_length_m,
        true_path_length_m: Some(travelled),
        geodesic_m,
        spl: geodesic_m.map(|l| spl(reached, l, travelled)),
        final_position_error_m: fe,
        final_heading_error_deg: fh,
        ate_rmse_m: run.log.ate_rmse_m(),
        goal_distance_m: Some(goal_distance),
        cpu_time_s: cpu,
        method: spec.config.method.to_string(),
        seed: Some(spec.setup.seed),
        start: PoseOut::of(&spec.setup.start),
        goal: PointOut::of(spec.goal),
        final_estimate: PoseOut::of(&outcome.estimate),
        final_truth: Some(PoseOut::of(&t)),
        note,
        narrow_passages: crate::outputs::narrow_passages(outcome),
        position_sigma_m,
        heading_sigma_deg,
    };
    Ok(SimRun {
        summary,
        outcome: run.outcome,
        log: run.log,
    })
}

/// Writes every output of a run into `dir` (created if needed).
pub fn write_outputs(dir: &Path, run: &SimRun, title: &str) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_summary(dir, &run.summary)?;
    write_trajectory(dir, &run.log)?;
    crate::outputs::write_grid(dir, &run.outcome.grid)?;
    crate::plot::write_plots(dir, &run.log, title)
}

/// Runs `robot-app sim`.
pub fn run(args: SimArgs) -> anyhow::Result<()> {
    let config = args.options.load()?;
    let mut setup = args.sim.setup()?;
    // A world file's own scenario unless the command line gives one.
    let (file_start, file_goal) = match &args.sim.world {
        None => (paper_start(), paper_target()),
        Some(p) => sim_laser::file_scenario(Some(p))
            .with_context(|| format!("reading the scenario of {}", p.display()))?,
    };
    setup.start = match &args.start {
        Some(s) => scan_types::parse_pose_deg(s).context("--start")?,
        None => file_start,
    };
    let goal = match &args.goal {
        Some(s) => scan_types::parse_point(s).context("--goal")?,
        None => file_goal,
    };
    let spec = SimSpec::new(setup, goal, config);
    spec.setup.check_scenario(goal).map_err(|e| {
        anyhow::anyhow!("{e}; give a start and a goal in its free space with --start and --goal")
    })?;
    args.options.write_config(&spec.config)?;
    let mut live = args
        .live
        .start(spec.config.localiser.map_resolution_m)?
        .map(|v| v.with_goal(goal));
    let record_path = args.options.record_path();
    let record = record_path.as_deref().map(|p| (p, args.options.profile));
    let run = run_with(&spec, record, live.as_mut())?;
    if let Some(v) = live {
        v.finish(Some(&run.outcome.grid));
    }
    let title = format!(
        "method {} — {} world, seed {}: {}",
        spec.config.method, spec.setup.world_name, spec.setup.seed, run.summary.reason
    );
    write_outputs(&args.options.out, &run, &title)?;
    let s = &run.summary;
    tracing::info!(
        reached = s.reached,
        reason = %s.reason,
        legs = s.legs,
        final_error_m = s.final_position_error_m.unwrap_or(f64::NAN),
        goal_distance_m = s.goal_distance_m.unwrap_or(f64::NAN),
        "run finished; outputs in {}",
        args.options.out.display()
    );
    crate::say!(
        "{}: {} after {} legs, true distance to target {:.3} m, final localisation error {:.3} m, outputs in {}",
        if s.reached { "reached" } else { "failed" },
        s.reason,
        s.legs,
        s.goal_distance_m.unwrap_or(f64::NAN),
        s.final_position_error_m.unwrap_or(f64::NAN),
        args.options.out.display()
    );
    let mapped = args.options.write_slam_map().map(|_| ());
    if s.reason == Reason::Interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    if !s.reached {
        bail!(
            "the run did not reach the target: {} ({})",
            s.reason,
            s.note
        );
    }
    mapped
}

/// Runs `spec` recording every scan with its true pose and the navigator's estimate to
/// `path` (goalseek's MCAP recording), with the run's settings ([`scan_log::RUN_METADATA`])
/// and the legs it drove ([`scan_log::LEGS_METADATA`]), so `robot-app replay FILE --loop` can
/// repeat it.
pub fn record_run(spec: &SimSpec, path: &Path) -> anyhow::Result<SimRun> {
    record_run_as(spec, path, crate::record::RecordProfile::Foxglove)
}

/// Runs `spec` recording it as [`record_run`] does in `profile` (ROS 2: with the map at the
/// end).
pub fn record_run_as(
    spec: &SimSpec,
    path: &Path,
    profile: crate::record::RecordProfile,
) -> anyhow::Result<SimRun> {
    run_with(spec, Some((path, profile)), None)
}

/// Runs `spec`, recording it as [`record_run_as`] does when `record` names a file and a
/// profile, and showing it on `live`.
pub fn run_with(
    spec: &SimSpec,
    record: Option<(&Path, crate::record::RecordProfile)>,
    live: Option<&mut crate::live::LiveView>,
) -> anyhow::Result<SimRun> {
    let Some((path, profile)) = record else {
        let Some(live) = live else {
            return simulate(spec, None);
        };
        let geometry = spec.setup.sensor.geometry();
        let live = std::cell::RefCell::new(live);
        let mut hook = |scan: &scan_types::Scan, truth: Pose2, estimate: Pose2| {
            live.borrow_mut()
                .scan(&geometry, scan, Some(estimate), Some(truth));
        };
        let mut legs = |leg: &navigator::Leg| live.borrow_mut().leg(leg);
        return simulate_watched(spec, Some(&mut hook), Some(&mut legs));
    };
    let setup = &spec.setup;
    let geometry = setup.sensor.geometry();
    let mut recorder = crate::record::Recorder::create_profile(path, &geometry, profile)
        .with_context(|| format!("cannot record to {}", path.display()))?
        .with_scan_period(Some(setup.sensor.scan_period_s()));
    let settings = crate::record::RunSettings {
        start: setup.start,
        goal: spec.goal,
        config: spec.config.clone(),
        world: setup.world_name.clone(),
        sensor: setup.sensor.name().to_string(),
        seed: setup.seed,
        noise: setup.noise,
    };
    recorder.write_metadata(scan_log::RUN_METADATA, &settings.to_metadata())?;
    let mut err: Option<anyhow::Error> = None;
    let live = live.map(std::cell::RefCell::new);
    let mut hook = |scan: &scan_types::Scan, truth: Pose2, estimate: Pose2| {
        if err.is_none()
            && let Err(e) = recorder.record_scan(&geometry, scan, Some(truth), Some(estimate))
        {
            err = Some(anyhow::anyhow!("recording to {}: {e}", path.display()));
        }
        if let Some(v) = &live {
            v.borrow_mut()
                .scan(&geometry, scan, Some(estimate), Some(truth));
        }
    };
    let mut legs = |leg: &navigator::Leg| {
        if let Some(v) = &live {
            v.borrow_mut().leg(leg);
        }
    };
    let run = simulate_watched(spec, Some(&mut hook), Some(&mut legs))?;
    if let Some(e) = err {
        return Err(e);
    }
    recorder.write_legs(&run.log, &run.outcome.reason.to_string())?;
    recorder.write_map(&run.outcome.grid)?;
    recorder
        .finish()
        .with_context(|| format!("finishing {}", path.display()))?;
    Ok(run)
}
