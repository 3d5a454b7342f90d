//! `robot-app explore`: map an unknown world with no target, driving to the frontiers of the
//! robot's own map until none is left; in the simulator, with coverage and map accuracy.

use anyhow::{Context, bail};
use clap::Args;
use localiser::{CellState, OccupancyGrid};
use navigator::{ExploreEnd, ExploreParams, Reason};
use scan_types::{Pose2, WorldPoint};
use serde::Serialize;
use sim_laser::{FreeSpace, PAIR_CELL_M, World, paper_start};

use crate::cmd::sim::thread_cpu_time_s;
use crate::outputs::write_atomic;
use crate::runloop::explore_loop;

/// Arguments of `robot-app explore`.
#[derive(Debug, Clone, Args)]
pub struct ExploreArgs {
    /// World, sensor, seed and noise (as `sim`).
    #[command(flatten)]
    pub sim: super::sim::SimWorldArgs,
    /// Start pose X,Y,THETA_DEG (default: the world file's start, the paper's in its world,
    /// else a seeded random pose in the largest free region).
    #[arg(long, value_name = "X,Y,THETA_DEG", allow_hyphen_values = true)]
    pub start: Option<String>,
    /// Explore on a real robot: the Hokuyo's serial device, or tcp:HOST:PORT for an Ethernet
    /// model (no simulator: no coverage, accuracy or errors).
    #[arg(long, value_name = "PATH|tcp:HOST:PORT", conflicts_with_all = ["world", "seed", "noise"])]
    pub port: Option<String>,
    /// With --port: the motion base, stdio (line protocol on stdin/stdout),
    /// `serial:PATH[@BAUD]` or manual (the default).
    #[arg(long, value_name = "BASE", requires = "port")]
    pub base: Option<String>,
    /// Explore once per seed A..B (B excluded), each into OUT/seed-N/, and write
    /// OUT/explore-batch.json with every run and their minimum and median figures.
    #[arg(long, value_name = "A..B", conflicts_with_all = ["seed", "port", "record", "live"])]
    pub seeds: Option<String>,
    /// Most frontiers to try.
    #[arg(long, default_value_t = ExploreParams::default().max_goals)]
    pub max_goals: usize,
    /// Most legs toward one frontier before it is given up.
    #[arg(long, default_value_t = ExploreParams::default().legs_per_goal)]
    pub legs_per_goal: usize,
    /// Configuration, output folder and recording (`--record`: every scan with its estimated
    /// and, in the simulator, true pose; the map at the end in the ros2 profile).
    #[command(flatten)]
    pub options: super::LoopOptions,
    /// Live view, paced by the simulated clock (`--live-rate` applies in the simulator).
    #[command(flatten)]
    pub live: crate::live::PacedLiveOptions,
}

/// One frontier tried, as `explore.json` lists it.
#[derive(Debug, Clone, Serialize)]
pub struct GoalRecord {
    /// The frontier's target.
    pub target: crate::outputs::PointOut,
    /// How the run to it ended.
    pub reason: Reason,
    /// Legs driven toward it.
    pub legs: usize,
}

/// `explore.json`: what an exploration did and, in the simulator, how good its map is.
#[derive(Debug, Clone, Serialize)]
pub struct ExploreSummary {
    /// How it ended: explored (no untried frontier left), goal_limit or failed.
    pub end: ExploreEnd,
    /// The last run's reason (the failure, when `end` is failed).
    pub reason: Reason,
    /// A one-line note on the last run.
    pub note: String,
    /// Frontiers tried.
    pub goals_tried: usize,
    /// Frontiers reached.
    pub goals_reached: usize,
    /// Every frontier tried, in order.
    pub goals: Vec<GoalRecord>,
    /// Legs driven.
    pub legs: usize,
    /// Scans taken.
    pub scans: usize,
    /// Collisions the simulator recorded (0 on a real robot).
    pub collisions: usize,
    /// Distance commanded, metres: the sum of the forward moves sent.
    pub commanded_path_length_m: f64,
    /// Distance truly driven, metres (simulator).
    pub true_path_length_m: Option<f64>,
    /// Share of the reachable free space (eroded by the robot radius) the map marks free.
    pub coverage_share: Option<f64>,
    /// Share of the map's occupied cells within 1.5 cells of a true obstacle.
    pub map_accuracy_share: Option<f64>,
    /// Distance between the final estimate and the true position, metres (simulator).
    pub final_position_error_m: Option<f64>,
    /// RMS of the position error at every leg end, metres (simulator).
    pub ate_rmse_m: Option<f64>,
    /// With `--slam-map` (simulator): `coverage_share` of the SLAM map, placed at the true
    /// start.
    pub slam_map_coverage_share: Option<f64>,
    /// With `--slam-map` (simulator): `map_accuracy_share` of the SLAM map.
    pub slam_map_accuracy_share: Option<f64>,
    /// CPU time, seconds (the loop's own thread).
    pub cpu_time_s: f64,
    /// Method preset used.
    pub method: String,
    /// Noise seed (simulator).
    pub seed: Option<u64>,
    /// Start pose.
    pub start: crate::outputs::PoseOut,
}

/// Coverage and map accuracy of `grid` (in the world's frame) against the true `world`.
///
/// Coverage: the share of the cells (0.05 m) at least `radius_m` from every obstacle and
/// connected to `start` that the map marks free. Accuracy: the share of the map's occupied
/// cells whose centre lies within 1.5 cells of a true obstacle (or inside one).
pub fn map_quality(
    world: &World,
    radius_m: f64,
    start: WorldPoint,
    grid: &OccupancyGrid,
) -> (Option<f64>, Option<f64>) {
    let space = FreeSpace::new(world, radius_m, 0.05);
    let region = space.region_of(start);
    let (mut reachable, mut seen) = (0usize, 0usize);
    if let Some(region) = region {
        for p in space.free_cells() {
            if space.region_of(p) == Some(region) {
                reachable += 1;
                if grid.state(p) == CellState::Free {
                    seen += 1;
                }
            }
        }
    }
    let coverage = (reachable > 0).then(|| seen as f64 / reachable as f64);
    let near = 1.5 * grid.resolution_m();
    let (mut occupied, mut right) = (0usize, 0usize);
    for row in 0..grid.height() {
        for col in 0..grid.width() {
            if grid.cell_state(col, row) != CellState::Occupied {
                continue;
            }
            occupied += 1;
            let c = grid.cell_centre(col, row);
            if world.is_occupied(c) || world.clearance(c, near + 0.01) <= near {
                right += 1;
            }
        }
    }
    let accuracy = (occupied > 0).then(|| right as f64 / occupied as f64);
    (coverage, accuracy)
}

/// What one exploration gave: its summary, its run, and in the simulator the true world.
struct Explored {
    summary: ExploreSummary,
    run: crate::runloop::ExploreRun,
    world: Option<(std::sync::Arc<World>, String)>,
    /// The robot radius and start that map quality is measured with (simulator).
    quality_at: Option<(f64, WorldPoint)>,
    /// How `--record` ended (reported once the other outputs are written).
    recorded: anyhow::Result<()>,
}

/// Exploring's own defaults over the method's preset: the planner's line of sight, the
/// travel on a round landmark's centre and the tracker's range-limit rule off (measured no
/// better for exploring, `docs/explore.md`), no arrival beside a target inside a wall's
/// clearance (a frontier goal ends when its frontier is mapped) and no final approach (a
/// frontier goal needs no exact arrival). A `--config` file may still turn them on.
pub fn explore_defaults(p: &mut crate::config::Params) {
    p.planner.line_of_sight = false;
    p.tracking.round_centre = false;
    p.tracking.reject_near_range_limit = false;
    p.navigator.blocked_target_plans = 0;
    p.navigator.final_approach_m = 0.0;
}

/// Runs `robot-app explore`: in the simulator, or with `--port` on a real Hokuyo and base.
pub fn run(args: ExploreArgs) -> anyhow::Result<()> {
    if let Some(seeds) = args.seeds.clone() {
        return super::explore_batch::run(args, &seeds);
    }
    let params = ExploreParams {
        max_goals: args.max_goals,
        legs_per_goal: args.legs_per_goal,
        ..ExploreParams::default()
    };
    if params.max_goals == 0 {
        bail!("--max-goals 0: must be at least 1");
    }
    if params.legs_per_goal == 0 {
        bail!("--legs-per-goal 0: must be at least 1");
    }
    let config = args.options.load_over(explore_defaults)?;
    let explored = match &args.port {
        Some(port) => explore_robot(&args, port, &config, &params)?,
        None => explore_sim(&args, &config, &params)?,
    };
    let mut explored = explored;
    let summary = &explored.summary;
    let name = explored.world.as_ref().map_or("robot", |(_, n)| n.as_str());
    write_outputs(&args.options.out, &explored.run, summary, name)?;
    if let Some((world, _)) = &explored.world {
        let path = args.options.out.join("truth.png");
        world
            .write_png(&path, config.localiser.map_resolution_m)
            .with_context(|| format!("writing {}", path.display()))?;
    }
    let pct = |v: Option<f64>| v.map_or("-".to_string(), |v| format!("{:.1} %", 100.0 * v));
    crate::say!(
        "{}: {} frontiers tried ({} reached), {} legs, coverage {}, map accuracy {}, collisions {}, final localisation error {}, outputs in {}",
        match summary.end {
            ExploreEnd::Explored => "explored",
            ExploreEnd::GoalLimit => "goal limit",
            ExploreEnd::Failed => "failed",
        },
        summary.goals_tried,
        summary.goals_reached,
        summary.legs,
        pct(summary.coverage_share),
        pct(summary.map_accuracy_share),
        summary.collisions,
        summary
            .final_position_error_m
            .map_or("-".to_string(), |e| format!("{e:.3} m")),
        args.options.out.display()
    );
    // What was recorded is mapped even when the recording broke off.
    let mapped = args.options.write_slam_map();
    if let (Ok(Some(slam_run)), Some((world, _)), Some((radius_m, start))) =
        (&mapped, &explored.world, explored.quality_at)
        && let Some(grid) = super::slam::map_at_reference_start(
            &slam_run.geometry,
            &slam_run.placed,
            super::slam::MAP_RESOLUTION_M,
            super::slam::MAP_MAX_RANGE_M,
        )
    {
        let (coverage, accuracy) = map_quality(world, radius_m, start, &grid);
        let summary = &mut explored.summary;
        summary.slam_map_coverage_share = coverage;
        summary.slam_map_accuracy_share = accuracy;
        write_summary(&args.options.out, summary)?;
        crate::say!(
            "--slam-map: the SLAM map placed at the true start: coverage {}, map accuracy {}",
            pct(coverage),
            pct(accuracy)
        );
    }
    explored.recorded?;
    let summary = &explored.summary;
    if summary.reason == Reason::Interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    if summary.end == ExploreEnd::Failed || summary.collisions > 0 {
        bail!(
            "the exploration failed: {} ({})",
            summary.reason,
            summary.note
        );
    }
    mapped.map(|_| ())
}

/// What the simulator knows beside an exploration: collisions, distance driven, true pose.
struct Truth {
    collisions: usize,
    travelled_m: f64,
    pose: Pose2,
}

/// The `explore.json` of `run`.
fn summary_of(
    run: &crate::runloop::ExploreRun,
    config: &crate::config::Params,
    (start, seed): (Pose2, Option<u64>),
    truth: Option<&Truth>,
    (coverage, map_accuracy): (Option<f64>, Option<f64>),
    cpu_time_s: f64,
) -> ExploreSummary {
    let ex = &run.exploration;
    let collisions = truth.map_or(0, |t| t.collisions);
    ExploreSummary {
        end: ex.end,
        reason: if collisions > 0 {
            Reason::Collision
        } else {
            ex.outcome.reason
        },
        note: ex.outcome.note.clone(),
        goals_tried: ex.goals.len(),
        goals_reached: ex
            .goals
            .iter()
            .filter(|g| g.reason == Reason::Reached)
            .count(),
        goals: ex
            .goals
            .iter()
            .map(|g| GoalRecord {
                target: crate::outputs::PointOut::of(g.target),
                reason: g.reason,
                legs: g.legs,
            })
            .collect(),
        legs: ex.outcome.legs_driven,
        scans: ex.outcome.scans,
        collisions,
        commanded_path_length_m: ex.outcome.path_length_m,
        true_path_length_m: truth.map(|t| t.travelled_m),
        coverage_share: coverage,
        map_accuracy_share: map_accuracy,
        final_position_error_m: truth.map(|t| {
            ex.outcome
                .estimate
                .position()
                .distance_m(&t.pose.position())
        }),
        ate_rmse_m: run.log.ate_rmse_m(),
        slam_map_coverage_share: None,
        slam_map_accuracy_share: None,
        cpu_time_s,
        method: config.method.to_string(),
        seed,
        start: crate::outputs::PoseOut::of(&start),
    }
}

/// The recording of `--record`, if asked for, and the first error writing it.
struct Recording {
    recorder: Option<(crate::record::Recorder, std::path::PathBuf)>,
    error: Option<String>,
}

impl Recording {
    /// Opens `--record`'s file in its profile, if given; `scan_period_s` is the sensor's scan
    /// period when known.
    fn open(
        options: &super::LoopOptions,
        geometry: &scan_types::ScanGeometry,
        scan_period_s: Option<f64>,
    ) -> anyhow::Result<Self> {
        let recorder = options
            .record_path()
            .map(|p| {
                crate::record::Recorder::create_profile(&p, geometry, options.profile)
                    .map(|r| (r.with_scan_period(scan_period_s), p.clone()))
                    .with_context(|| format!("cannot record to {}", p.display()))
            })
            .transpose()?;
        Ok(Recording {
            recorder,
            error: None,
        })
    }

    /// Records one scan; after the first error, records nothing more.
    fn scan(
        &mut self,
        geometry: &scan_types::ScanGeometry,
        scan: &scan_types::Scan,
        truth: Option<Pose2>,
        estimate: Pose2,
    ) {
        if let Some((r, path)) = self.recorder.as_mut()
            && self.error.is_none()
            && let Err(e) = r.record_scan(geometry, scan, truth, Some(estimate))
        {
            self.error = Some(format!("recording to {}: {e}", path.display()));
        }
    }

    /// Adds the legs and the map, and closes the file; the first error, if any.
    fn finish(self, run: &crate::runloop::ExploreRun) -> anyhow::Result<()> {
        let Some((mut r, path)) = self.recorder else {
            return Ok(());
        };
        if let Some(e) = self.error {
            // Close what was written; the error is what the user needs to see.
            let _ = r.finish();
            bail!(e);
        }
        let outcome = &run.exploration.outcome;
        r.write_legs(&run.log, &outcome.reason.to_string())
            .and_then(|()| r.write_map(&outcome.grid))
            .and_then(|()| r.finish().map(|_| ()))
            .with_context(|| format!("finishing the recording {}", path.display()))
    }
}

/// The live view, when `--live` is given, shared by the scan and leg hooks.
type LiveCell = Option<std::cell::RefCell<crate::live::LiveView>>;

/// The scan hook that shows every scan, its estimate and `truth()`'s pose on `live`.
fn live_scan<'a>(
    live: &'a LiveCell,
    geometry: &'a scan_types::ScanGeometry,
    truth: impl Fn() -> Option<Pose2> + 'a,
) -> impl FnMut(&scan_types::Scan, &Pose2) + 'a {
    move |scan, estimate| {
        if let Some(v) = live {
            v.borrow_mut()
                .scan(geometry, scan, Some(*estimate), truth());
        }
    }
}

/// The leg hook that shows every leg end on `live`.
fn live_leg(live: &LiveCell) -> impl FnMut(&navigator::Leg) + '_ {
    move |leg| {
        if let Some(v) = live {
            v.borrow_mut().leg(leg);
        }
    }
}

/// Explores in the simulator.
fn explore_sim(
    args: &ExploreArgs,
    config: &crate::config::Params,
    params: &ExploreParams,
) -> anyhow::Result<Explored> {
    let mut setup = args.sim.setup()?;
    // The world file's start, else (a map without one) a seeded random start in the largest
    // free region.
    let file_start = match &args.sim.world {
        None => Some(paper_start()),
        Some(p) if p.extension().is_some_and(|e| e == "toml") => sim_laser::read_description(p)
            .with_context(|| format!("reading the scenario of {}", p.display()))?
            .start
            .map(|[x, y, t]| Pose2::new(x, y, t)),
        Some(_) => None,
    };
    setup.start = match (&args.start, file_start) {
        (Some(s), _) => scan_types::parse_pose_deg(s).context("--start")?,
        (None, Some(s)) => s,
        (None, None) => FreeSpace::new(&setup.world, config.robot.radius_m + 0.1, PAIR_CELL_M)
            .random_start(args.sim.seed)
            .context("no free space for the robot in the world: give --start")?,
    };
    setup.robot_radius_m = config.robot.radius_m;
    setup
        .check_scenario(setup.start.position())
        .map_err(|e| anyhow::anyhow!("{e}; give a start in its free space with --start"))?;
    args.options.write_config(config)?;
    let live: LiveCell = args
        .live
        .start(config.localiser.map_resolution_m)?
        .map(std::cell::RefCell::new);
    let geometry = setup.sensor.geometry();
    let (mut laser, mut base, truth) = setup.build()?.split();
    let mut recording =
        Recording::open(&args.options, &geometry, Some(setup.sensor.scan_period_s()))?;
    let cpu0 = thread_cpu_time_s();
    let run = {
        let mut show = live_scan(&live, &geometry, || Some(truth.pose()));
        let mut on_scan = |scan: &scan_types::Scan, estimate: &Pose2| {
            recording.scan(&geometry, scan, Some(truth.pose()), *estimate);
            show(scan, estimate);
        };
        let mut on_leg = live_leg(&live);
        explore_loop(
            &mut laser,
            &mut base,
            config,
            params,
            setup.start,
            Some(&truth),
            Some(&mut on_scan),
            Some(&mut on_leg),
        )?
    };
    let cpu = thread_cpu_time_s() - cpu0;
    if let Some(v) = live {
        v.into_inner().finish(Some(&run.exploration.outcome.grid));
    }
    let recorded = recording.finish(&run);
    let quality = map_quality(
        &setup.world,
        setup.robot_radius_m,
        setup.start.position(),
        &run.exploration.outcome.grid,
    );
    let t = Truth {
        collisions: truth.collisions(),
        travelled_m: truth.travelled_m(),
        pose: truth.pose(),
    };
    let summary = summary_of(
        &run,
        config,
        (setup.start, Some(setup.seed)),
        Some(&t),
        quality,
        cpu,
    );
    Ok(Explored {
        summary,
        run,
        world: Some((setup.world.clone(), setup.world_name.clone())),
        quality_at: Some((setup.robot_radius_m, setup.start.position())),
        recorded,
    })
}

/// Explores with a real Hokuyo at `port` and the base of `--base`: no truth, so no coverage,
/// accuracy or errors.
fn explore_robot(
    args: &ExploreArgs,
    port: &str,
    config: &crate::config::Params,
    params: &ExploreParams,
) -> anyhow::Result<Explored> {
    let start = match &args.start {
        Some(s) => scan_types::parse_pose_deg(s).context("--start")?,
        None => Pose2::new(0.0, 0.0, 0.0),
    };
    args.options.write_config(config)?;
    let mut base = super::run::open_base(args.base.as_deref().unwrap_or("manual"))?;
    let mut laser = super::open_sensor(port, urg_driver::UrgConfig::default())?;
    let geometry = *scan_types::LaserSource::geometry(&laser);
    tracing::info!(port, rays = geometry.ray_count, "sensor connected");
    let live: LiveCell = args
        .live
        .live
        .start(config.localiser.map_resolution_m)?
        .map(std::cell::RefCell::new);
    let scan_period_s = laser
        .urg_mut()
        .map(|u| u.params().scan_period().as_secs_f64());
    let mut recording = Recording::open(&args.options, &geometry, scan_period_s)?;
    let cpu0 = thread_cpu_time_s();
    let run = {
        let mut show = live_scan(&live, &geometry, || None);
        let mut on_scan = |scan: &scan_types::Scan, estimate: &Pose2| {
            recording.scan(&geometry, scan, None, *estimate);
            show(scan, estimate);
        };
        let mut on_leg = live_leg(&live);
        explore_loop(
            &mut laser,
            &mut base,
            config,
            params,
            start,
            None,
            Some(&mut on_scan),
            Some(&mut on_leg),
        )?
    };
    let cpu = thread_cpu_time_s() - cpu0;
    if let Some(v) = live {
        v.into_inner().finish(Some(&run.exploration.outcome.grid));
    }
    if let Some(urg) = laser.urg_mut() {
        let _ = urg.stop();
    }
    let recorded = recording.finish(&run);
    let summary = summary_of(&run, config, (start, None), None, (None, None), cpu);
    Ok(Explored {
        summary,
        run,
        world: None,
        quality_at: None,
        recorded,
    })
}

/// Writes `summary` as `explore.json` into `dir`.
fn write_summary(dir: &std::path::Path, summary: &ExploreSummary) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(summary)?;
    text.push('\n');
    write_atomic(&dir.join("explore.json"), text.as_bytes())
}

/// Writes `explore.json`, `trajectory.csv`, the TUM files, the maps and the run's figure.
fn write_outputs(
    dir: &std::path::Path,
    run: &crate::runloop::ExploreRun,
    summary: &ExploreSummary,
    world: &str,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_summary(dir, summary)?;
    scan_log::write_trajectory(dir, &run.log)?;
    crate::outputs::write_grid(dir, &run.exploration.outcome.grid)?;
    let seed = summary
        .seed
        .map_or(String::new(), |s| format!(", seed {s}"));
    let coverage = summary
        .coverage_share
        .map_or(String::new(), |c| format!(", coverage {:.0} %", 100.0 * c));
    let title = format!(
        "explore — {world}{seed}: {} frontiers{coverage}",
        summary.goals_tried
    );
    crate::plot::write_plots(dir, &run.log, &title)
}
