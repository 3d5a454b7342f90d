//! `robot-app run`: the goal-seeking loop on a real Hokuyo and a robot base.

use std::time::Instant;

use anyhow::{Context, bail};
use clap::Args;
use scan_types::{LaserSource, Pose2, Scan, WorldPoint};

use super::sim::thread_cpu_time_s;
use crate::outputs::{PointOut, PoseOut, Reason, Summary};
use crate::runloop::run_loop_legs;
use robot_base::StopOnDrop;

/// Arguments of `robot-app run`.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// Serial device of the Hokuyo (e.g. /dev/ttyACM0), or tcp:HOST:PORT for an Ethernet model.
    #[arg(long, value_name = "PATH|tcp:HOST:PORT")]
    pub port: String,
    /// Target X,Y in the frame of the start pose.
    #[arg(long, value_name = "X,Y", allow_hyphen_values = true)]
    pub goal: String,
    /// Motion base: stdio (line protocol on stdin/stdout), `serial:PATH[@BAUD]` or manual.
    #[arg(long, default_value = "manual", value_name = "BASE")]
    pub base: String,
    /// Start pose X,Y,THETA_DEG: where the map's frame puts the robot (default 0,0,0).
    #[arg(long, value_name = "X,Y,THETA_DEG", allow_hyphen_values = true)]
    pub start: Option<String>,
    /// Do not map the run with SLAM when it ends (by default `run` records every scan to
    /// OUT/run.mcap, or --record's file, and maps it into OUT/slam/, as --slam-map does).
    #[arg(long, conflicts_with = "slam_map")]
    pub no_slam_map: bool,
    /// Configuration, output folder, recording.
    #[command(flatten)]
    pub options: super::LoopOptions,
    /// Live view.
    #[command(flatten)]
    pub live: crate::live::LiveOptions,
}

/// Opens the base named by `--base SPEC` ([`robot_base::open_base`]): a move's answer is no
/// longer waited for once Ctrl-C or SIGTERM came, and the base is sent `stop` when dropped
/// unless `stop` was its last command (an early error still stops the robot).
pub fn open_base(spec: &str) -> anyhow::Result<StopOnDrop<robot_base::DynBase>> {
    if spec == "stdio" {
        crate::outputs::stdout_is_base();
    }
    robot_base::open_base(spec, Some(crate::interrupt::requested))
        .map(StopOnDrop::new)
        .map_err(|e| {
            let e = anyhow::Error::new(e);
            match e.downcast_ref::<robot_base::BaseError>() {
                Some(b) if b.is_spec_error() => anyhow::anyhow!("--base {e:#}"),
                _ => e,
            }
        })
}

/// Runs `robot-app run`.
pub fn run(mut args: RunArgs) -> anyhow::Result<()> {
    // On a real robot the building's map is the point of the run: mapped unless refused. A
    // failure of the map asked for by default is logged, not the run's exit status.
    let asked_for_map = args.options.slam_map;
    args.options.slam_map = !args.no_slam_map;
    let config = args.options.prepare()?;
    let goal = scan_types::parse_point(&args.goal).context("--goal")?;
    let start = match &args.start {
        Some(s) => scan_types::parse_pose_deg(s).context("--start")?,
        None => Pose2::new(0.0, 0.0, 0.0),
    };
    let mut base = open_base(&args.base)?;
    let mut laser = super::open_sensor(&args.port, urg_driver::UrgConfig::default())?;
    tracing::info!(port = %args.port, rays = laser.geometry().ray_count, "sensor connected");
    let geometry = *laser.geometry();
    let scan_period_s = laser
        .urg_mut()
        .map(|u| u.params().scan_period().as_secs_f64());
    let mut recorder = args
        .options
        .record_path()
        .map(|p| {
            crate::record::Recorder::create_profile(&p, &geometry, args.options.profile)
                .map(|r| r.with_scan_period(scan_period_s))
                .with_context(|| format!("cannot record to {}", p.display()))
        })
        .transpose()?;
    let live = args
        .live
        .start(config.localiser.map_resolution_m)?
        .map(|v| v.with_goal(goal));
    let live = std::cell::RefCell::new(live);
    let mut record_error: Option<String> = None;
    let mut hook = |scan: &Scan, estimate: &Pose2| {
        if let Some(r) = recorder.as_mut()
            && record_error.is_none()
            && let Err(e) = r.record_scan(&geometry, scan, None, Some(*estimate))
        {
            record_error = Some(e.to_string());
        }
        if let Some(v) = live.borrow_mut().as_mut() {
            v.scan(&geometry, scan, Some(*estimate), None);
        }
    };
    let mut legs = |leg: &navigator::Leg| {
        if let Some(v) = live.borrow_mut().as_mut() {
            v.leg(leg);
        }
    };
    let wall = Instant::now();
    let cpu0 = thread_cpu_time_s();
    let run = run_loop_legs(
        &mut laser,
        &mut base,
        &config,
        (start, goal),
        None,
        Some(&mut hook),
        Some(&mut legs),
    )?;
    let outcome = run.outcome;
    if let Some(v) = live.into_inner() {
        v.finish(Some(&outcome.grid));
    }
    let cpu = thread_cpu_time_s() - cpu0;
    if let Some(urg) = laser.urg_mut() {
        let _ = urg.stop();
    }
    if let Some(mut r) = recorder {
        if record_error.is_none()
            && let Err(e) = r.write_map(&outcome.grid)
        {
            record_error = Some(e.to_string());
        }
        r.finish().context("finishing the recording")?;
    }
    let summary = summary_of(&outcome, &config, (start, goal), cpu);
    let run = super::sim::SimRun {
        summary,
        outcome,
        log: run.log,
    };
    super::sim::write_outputs(&args.options.out, &run, "goalseek on a real Hokuyo")?;
    tracing::info!(
        wall_s = wall.elapsed().as_secs_f64(),
        "run finished; outputs in {}",
        args.options.out.display()
    );
    // What was recorded is mapped even when the recording broke off.
    let mapped = match args.options.write_slam_map() {
        Err(e) if !asked_for_map => {
            tracing::warn!("the run's SLAM map was not written: {e:#}");
            Ok(())
        }
        other => other.map(|_| ()),
    };
    if let Some(e) = record_error {
        bail!("recording failed: {e}");
    }
    if run.summary.reason == Reason::Interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    if !run.summary.reached {
        bail!(
            "the run did not reach the target: {} ({})",
            run.summary.reason,
            run.summary.note
        );
    }
    mapped
}

/// The `summary.json` of a run on a real robot (no truth: no errors, no collisions).
fn summary_of(
    outcome: &navigator::Outcome,
    config: &crate::config::Params,
    (start, goal): (Pose2, WorldPoint),
    cpu_time_s: f64,
) -> Summary {
    let (position_sigma_m, heading_sigma_deg) = crate::outputs::leg_sigmas(outcome);
    Summary {
        reached: outcome.reason == Reason::Reached,
        reason: outcome.reason,
        legs: outcome.legs_driven,
        scans: outcome.scans,
        collisions: 0,
        commanded_path_length_m: outcome.path_length_m,
        true_path_length_m: None,
        geodesic_m: None,
        spl: None,
        final_position_error_m: None,
        final_heading_error_deg: None,
        ate_rmse_m: None,
        goal_distance_m: None,
        cpu_time_s,
        method: config.method.to_string(),
        seed: None,
        start: PoseOut::of(&start),
        goal: PointOut::of(goal),
        final_estimate: PoseOut::of(&outcome.estimate),
        final_truth: None,
        note: outcome.note.clone(),
        narrow_passages: crate::outputs::narrow_passages(outcome),
        position_sigma_m,
        heading_sigma_deg,
    }
}
