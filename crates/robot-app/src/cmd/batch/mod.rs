//! `robot-app batch`: many simulated runs in parallel, a summary table and `batch.json`.
//!
//! [`jobs`] turns the arguments into simulated runs, [`mod@table`] turns their summaries into rows,
//! aggregates and the table.

pub mod jobs;
pub mod table;

use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;

use self::jobs::Job;
use self::table::{Aggregate, BatchRow, aggregate, table};
use super::sim::{SimRun, geodesic_in, geodesic_map, simulate_with_geodesic};
use crate::config::Method;
use crate::outputs::write_atomic;
use sim_laser::GeodesicMap;

/// Arguments of `robot-app batch`.
#[derive(Debug, Args)]
pub struct BatchArgs {
    /// Worlds to run in: `paper` or world files (default: paper).
    #[arg(long, num_args = 1.., value_name = "W")]
    pub worlds: Vec<String>,
    /// Seeds A..B (B excluded): each seed gives one run per scenario and world.
    #[arg(long, default_value = "0..50", value_name = "A..B")]
    pub seeds: String,
    /// Also run in K seeded random worlds: rooms on both sides of a 1.6 m corridor, doors,
    /// clutter (sim-laser's generator, seeds 0..K).
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub random_worlds: usize,
    /// Also run in K seeded wide-corridor worlds (a 4 m wide, 24 m long empty corridor between
    /// rooms; pairs lie in the corridor), reported apart as `corridor`.
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub corridor_worlds: usize,
    /// Also run in K seeded clutter-only worlds (a 20 m x 12 m open walled area with 5 boxes
    /// and 5 discs, start and target 17 m apart; `world generate --clutter-only`), reported
    /// apart as `clutter`. `--clutter-worlds 50 --seeds 0..1 --scenarios paper` is one run in
    /// each of 50 worlds.
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub clutter_worlds: usize,
    /// Random start/target pairs per world (default: one per seed). Pair i uses noise seed
    /// A+i, so pairs are the same for every method.
    #[arg(long, value_name = "N")]
    pub random_pairs: Option<usize>,
    /// Scenarios: `paper` (the paper's start and target in the paper world, or a generated
    /// world's own start and target, once per seed), `pairs` (random start/target pairs at least
    /// --min-distance apart in free space), or both.
    #[arg(long, default_value = "both", value_parser = ["paper", "pairs", "both"])]
    pub scenarios: String,
    /// Smallest start-target distance of a random pair, metres.
    #[arg(long, default_value_t = 6.0)]
    pub min_distance: f64,
    /// Methods to run, comma-separated (e.g. goalseek,paper for a side-by-side table).
    #[arg(long, default_value = "goalseek", value_delimiter = ',')]
    pub method: Vec<Method>,
    /// TOML file overriding tuning parameters (applied to every method's preset).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Sensor preset.
    #[arg(long, default_value = "paper")]
    pub sensor: String,
    /// Output folder for batch.json.
    #[arg(long, default_value = "goalseek-batch")]
    pub out: PathBuf,
    /// Also write each run's outputs under OUT/runs/.
    #[arg(long)]
    pub keep_runs: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// Most runs one batch (or `explore --seeds`) may hold.
pub const MAX_RUNS: u64 = 100_000;
/// Most generated worlds, of all kinds together, in one batch.
pub const MAX_GENERATED_WORLDS: u64 = 1_000;

/// Parses `A..B` (B excluded) or a single seed.
pub fn parse_seeds(s: &str) -> anyhow::Result<std::ops::Range<u64>> {
    let bad = || format!("--seeds '{s}': expected A..B (B excluded) or N");
    if let Some((a, b)) = s.split_once("..") {
        let a: u64 = a.trim().parse().with_context(bad)?;
        let b: u64 = b.trim().parse().with_context(bad)?;
        if b <= a {
            bail!("--seeds '{s}': the range is empty");
        }
        Ok(a..b)
    } else {
        let a: u64 = s.trim().parse().with_context(bad)?;
        let b = a
            .checked_add(1)
            .with_context(|| format!("--seeds '{s}': the seed must be below {}", u64::MAX))?;
        Ok(a..b)
    }
}

#[derive(Serialize)]
struct BatchFile<'a> {
    command: String,
    aggregates: &'a [Aggregate],
    rows: &'a [BatchRow],
}

/// Runs `robot-app batch`.
pub fn run(args: BatchArgs) -> anyhow::Result<()> {
    if args.random_pairs == Some(0) {
        bail!("--random-pairs 0: must be at least 1");
    }
    let jobs = jobs::build(&args)?;
    if jobs.is_empty() {
        bail!("nothing to run: no worlds, seeds or scenarios");
    }
    // The output folder is checked before the first run, not after the last.
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("--out: cannot create {}", args.out.display()))?;
    let probe = args.out.join(".goalseek-write-test");
    write_atomic(&probe, b"")
        .with_context(|| format!("--out: cannot write into {}", args.out.display()))?;
    let _ = std::fs::remove_file(&probe);
    let (rows, failed) = run_jobs(&jobs, &args)?;
    let aggs = aggregate(&rows);
    // The table is printed whatever happens next.
    crate::outputs::say(format_args!("{}", table(&aggs)));
    let file = BatchFile {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        aggregates: &aggs,
        rows: &rows,
    };
    let mut text = serde_json::to_string_pretty(&file)?;
    text.push('\n');
    write_atomic(&args.out.join("batch.json"), text.as_bytes())?;
    crate::say!("batch.json: {}", args.out.join("batch.json").display());
    if let Some((n, first)) = failed {
        return Err(first.context(format!("{n} of {} runs failed; the first", jobs.len())));
    }
    if crate::interrupt::requested() {
        return Err(crate::interrupt::Interrupted.into());
    }
    Ok(())
}

/// Rows of the runs that finished, and how many failed with the first failure.
type JobResults = (Vec<BatchRow>, Option<(usize, anyhow::Error)>);

/// Runs every job on `--jobs` worker threads with a progress bar, rows in job order.
fn run_jobs(jobs: &[Job], args: &BatchArgs) -> anyhow::Result<JobResults> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let bar = ProgressBar::new(jobs.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let keep = args.keep_runs.then(|| args.out.join("runs"));
    // One free-space grid per world and robot radius, shared by the geodesics of its runs.
    let key = |job: &Job| {
        (
            std::sync::Arc::as_ptr(&job.spec.setup.world) as usize,
            job.spec.setup.robot_radius_m.to_bits(),
        )
    };
    let mut firsts: Vec<usize> = Vec::new();
    for (i, job) in jobs.iter().enumerate() {
        if !firsts.iter().any(|&f| key(&jobs[f]) == key(job)) {
            firsts.push(i);
        }
    }
    let maps: Vec<Option<GeodesicMap>> = pool.install(|| {
        firsts
            .par_iter()
            .map(|&f| geodesic_map(&jobs[f].spec))
            .collect()
    });
    let map_of = |job: &Job| {
        firsts
            .iter()
            .position(|&f| key(&jobs[f]) == key(job))
            .and_then(|i| maps[i].as_ref())
    };
    let rows: Vec<anyhow::Result<BatchRow>> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let geodesic = map_of(job).and_then(|m| geodesic_in(m, &job.spec));
                let run = simulate_with_geodesic(&job.spec, geodesic)?;
                if let Some(dir) = &keep {
                    let sub = dir.join(format!(
                        "{}-{}-{}-{}",
                        job.group,
                        job.spec.setup.world_name,
                        job.spec.config.method,
                        job.spec.setup.seed
                    ));
                    super::sim::write_outputs(&sub, &run, &sub.display().to_string())?;
                }
                bar.inc(1);
                Ok(row_of(job, run))
            })
            .collect()
    });
    bar.finish_and_clear();
    let mut ok = Vec::with_capacity(rows.len());
    let mut failed: Option<(usize, anyhow::Error)> = None;
    for r in rows {
        match r {
            Ok(row) => ok.push(row),
            Err(e) => match &mut failed {
                Some((n, _)) => *n += 1,
                None => failed = Some((1, e)),
            },
        }
    }
    Ok((ok, failed))
}

/// The batch.json row of a finished job.
fn row_of(job: &Job, run: SimRun) -> BatchRow {
    let s = run.summary;
    BatchRow {
        group: job.group.clone(),
        kind: job.kind,
        world: job.spec.setup.world_name.clone(),
        pair: job.pair,
        method: s.method,
        seed: job.spec.setup.seed,
        start: s.start,
        goal: s.goal,
        reached: s.reached,
        reason: s.reason,
        legs: s.legs,
        scans: s.scans,
        collisions: s.collisions,
        final_position_error_m: s.final_position_error_m,
        final_heading_error_deg: s.final_heading_error_deg,
        ate_rmse_m: s.ate_rmse_m,
        goal_distance_m: s.goal_distance_m,
        commanded_path_length_m: s.commanded_path_length_m,
        true_path_length_m: s.true_path_length_m,
        geodesic_m: s.geodesic_m,
        spl: s.spl,
        cpu_time_s: s.cpu_time_s,
        final_position_sigma_m: s.position_sigma_m.last().copied(),
        note: s.note,
    }
}
