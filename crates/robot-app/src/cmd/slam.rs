//! `robot-app slam`: a trajectory and a map from the laser alone, for any log goalseek reads.
//! The poses and odometry a log may carry are never given to the estimator; they are only
//! used, when present, to evaluate it.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use scan_log::{LogOptions, LogSource};
use scan_types::{LaserSource, Pose2, Scan, ScanGeometry};
use serde::Serialize;
use slam::eval::{RelativeError, Stats, absolute_error, relative_error};
use slam::{FrontEnd, FrontEndParams, Placement};

use crate::outputs::{tum, write_atomic};

/// Arguments of `robot-app slam`.
#[derive(Debug, Args)]
pub struct SlamArgs {
    /// The log: CARMEN (.log, .log.gz), BreezySLAM .dat or a goalseek .mcap recording.
    #[arg(long)]
    pub log: PathBuf,
    /// Output folder (created if missing).
    #[arg(long, default_value = "goalseek-slam")]
    pub out: PathBuf,
    /// TOML file overriding front-end parameters (see docs/slam.md).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Map cell side, metres.
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f64,
    /// Rays enter the map up to this range, metres.
    #[arg(long, default_value_t = 20.0)]
    pub max_range: f64,
}

/// One placed scan.
#[derive(Debug, Clone)]
pub struct Placed {
    /// Its time stamp, seconds (the log's, or the scan index).
    pub time_s: f64,
    /// The estimate.
    pub pose: Pose2,
    /// The log's reference pose, if it has one (never seen by the estimator).
    pub reference: Option<Pose2>,
    /// The scan.
    pub scan: Scan,
}

/// A scan that was not placed.
#[derive(Debug, Clone, Serialize)]
pub struct Skip {
    /// Its line (text logs) or sequence number (MCAP).
    pub line: usize,
    /// Why.
    pub reason: String,
}

/// `slam.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SlamReport {
    /// The log.
    pub log: String,
    /// Scans read.
    pub scans: usize,
    /// Scans placed.
    pub placed: usize,
    /// Scans that could not be placed.
    pub skipped: Vec<Skip>,
    /// Malformed records of the log that were skipped while reading.
    pub malformed_records: usize,
    /// Where the time stamps come from: `log` or `scan_index`.
    pub timestamps: String,
    /// Front-end time per scan, milliseconds: median and 99th percentile.
    pub time_per_scan_ms: [f64; 2],
    /// Front-end time for the whole log, seconds.
    pub total_time_s: f64,
    /// Straight-line distance between the first and the last placed pose, metres.
    pub start_to_end_m: f64,
    /// Length of the estimated path, metres.
    pub path_length_m: f64,
    /// Share of the map's hit endpoints within one cell of an occupied cell.
    pub map_consistency: f64,
    /// Against the log's reference poses, when every placed scan has one.
    pub evaluation: Option<Evaluation>,
    /// The front end's parameters.
    pub params: FrontEndParams,
}

/// Errors against the reference poses.
#[derive(Debug, Clone, Serialize)]
pub struct Evaluation {
    /// Relations k to k+1.
    pub relative_1: RelativeError,
    /// Relations k to k+10.
    pub relative_10: Option<RelativeError>,
    /// Position error after an SE(2) alignment, metres.
    pub absolute_m: Stats,
}

/// A finished run.
pub struct SlamRun {
    /// The log's geometry.
    pub geometry: ScanGeometry,
    /// Placed scans, in order.
    pub placed: Vec<Placed>,
    /// What `slam.json` holds.
    pub report: SlamReport,
}

/// Loads front-end parameters: the defaults overridden by a TOML file.
pub fn load_params(path: Option<&Path>) -> anyhow::Result<FrontEndParams> {
    let Some(p) = path else {
        return Ok(FrontEndParams::default());
    };
    let text = std::fs::read_to_string(p)
        .with_context(|| format!("cannot read config {}", p.display()))?;
    let params: FrontEndParams =
        toml::from_str(&text).with_context(|| format!("config {}", p.display()))?;
    params
        .validate()
        .with_context(|| format!("config {}", p.display()))?;
    Ok(params)
}

/// A progress bar on stderr that shows itself once the run has taken a second.
struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: bool,
}

impl Progress {
    fn new() -> Self {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{spinner} {pos} scans, {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        Self {
            bar,
            start: Instant::now(),
            shown: false,
        }
    }

    fn tick(&mut self) {
        if !self.shown && self.start.elapsed() > Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        self.bar.inc(1);
    }
}

/// Runs the front end over every scan of `path`.
pub fn run_log(path: &Path, params: &FrontEndParams) -> anyhow::Result<SlamRun> {
    let mut source = LogSource::open(path, &LogOptions::default())
        .with_context(|| format!("opening the log {}", path.display()))?;
    let geometry = *source.geometry();
    let mut fe = FrontEnd::new(params.clone())?;
    let (mut placed, mut skipped, mut times) = (Vec::new(), Vec::new(), Vec::new());
    let mut scans = 0usize;
    let mut progress = Progress::new();
    let started = Instant::now();
    loop {
        let rec = match source.next_record() {
            Ok(r) => r,
            Err(e) if e.is_end_of_log() => break,
            Err(e) => return Err(e).context("reading the log"),
        };
        scans += 1;
        progress.tick();
        let t = Instant::now();
        let placement = fe.add_scan(&rec.geometry, &rec.scan);
        times.push(t.elapsed().as_secs_f64() * 1e3);
        match placement {
            Placement::Placed { pose, .. } => placed.push(Placed {
                time_s: rec.scan.host_time_s,
                pose,
                reference: rec.pose,
                scan: rec.scan.clone(),
            }),
            Placement::Skipped { reason } => {
                tracing::warn!(
                    "{} line {}: scan not placed: {reason}",
                    path.display(),
                    rec.line
                );
                skipped.push(Skip {
                    line: rec.line,
                    reason: reason.to_string(),
                });
            }
        }
    }
    let total_time_s = started.elapsed().as_secs_f64();
    progress.bar.finish_and_clear();
    let timestamps = fix_timestamps(path, &mut placed);
    let report = SlamReport {
        log: path.display().to_string(),
        scans,
        placed: placed.len(),
        skipped,
        malformed_records: source.skipped(),
        timestamps,
        time_per_scan_ms: [percentile(&mut times, 0.5), percentile(&mut times, 0.99)],
        total_time_s,
        start_to_end_m: match (placed.first(), placed.last()) {
            (Some(a), Some(b)) => a.pose.position().distance_m(&b.pose.position()),
            _ => 0.0,
        },
        path_length_m: placed
            .windows(2)
            .map(|w| w[0].pose.position().distance_m(&w[1].pose.position()))
            .sum(),
        map_consistency: 0.0,
        evaluation: evaluate(&placed),
        params: params.clone(),
    };
    Ok(SlamRun {
        geometry,
        placed,
        report,
    })
}

/// Keeps the log's time stamps when they are finite and increase; else the scan index.
fn fix_timestamps(path: &Path, placed: &mut [Placed]) -> String {
    let increasing = placed.iter().all(|p| p.time_s.is_finite())
        && placed.windows(2).all(|w| w[1].time_s > w[0].time_s);
    if increasing {
        return "log".into();
    }
    tracing::warn!(
        "{}: the time stamps are missing or do not increase; trajectory.tum uses the scan index",
        path.display()
    );
    for (i, p) in placed.iter_mut().enumerate() {
        p.time_s = i as f64;
    }
    "scan_index".into()
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn evaluate(placed: &[Placed]) -> Option<Evaluation> {
    let reference: Vec<Pose2> = placed.iter().map(|p| p.reference).collect::<Option<_>>()?;
    let est: Vec<Pose2> = placed.iter().map(|p| p.pose).collect();
    Some(Evaluation {
        relative_1: relative_error(&est, &reference, 1).ok()?,
        relative_10: relative_error(&est, &reference, 10).ok(),
        absolute_m: absolute_error(&est, &reference).ok()?,
    })
}

/// Writes `trajectory.tum`, `reference.tum` (when the log has poses), the maps and
/// `slam.json` into `dir`; fills in the map consistency.
pub fn write_outputs(
    dir: &Path,
    run: &mut SlamRun,
    resolution_m: f64,
    max_range_m: f64,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_atomic(
        &dir.join("trajectory.tum"),
        tum(run.placed.iter().map(|p| (p.time_s, p.pose))).as_bytes(),
    )?;
    if run.report.evaluation.is_some() {
        let rows = run
            .placed
            .iter()
            .filter_map(|p| p.reference.map(|r| (p.time_s, r)));
        write_atomic(&dir.join("reference.tum"), tum(rows).as_bytes())?;
    }
    let scans: Vec<(Pose2, Scan)> = run
        .placed
        .iter()
        .map(|p| (p.pose, p.scan.clone()))
        .collect();
    let (grid, stats) =
        super::map::build_map(&run.geometry, &scans, resolution_m, max_range_m, false);
    run.report.map_consistency = stats.endpoint_fit();
    grid.write_map_server(dir, "map")?;
    grid.to_png(&dir.join("map.png"))?;
    let mut text = serde_json::to_string_pretty(&run.report)?;
    text.push('\n');
    write_atomic(&dir.join("slam.json"), text.as_bytes())
}

/// Runs `robot-app slam`.
pub fn run(args: SlamArgs) -> anyhow::Result<()> {
    for (name, v) in [
        ("--resolution", args.resolution),
        ("--max-range", args.max_range),
    ] {
        if !(v.is_finite() && v > 0.0) {
            anyhow::bail!("{name} {v}: must be a positive number of metres");
        }
    }
    let params = load_params(args.config.as_deref())?;
    let mut run = run_log(&args.log, &params)?;
    write_outputs(&args.out, &mut run, args.resolution, args.max_range)?;
    let r = &run.report;
    let eval = r.evaluation.as_ref().map_or(String::new(), |e| {
        format!(
            "; against the log's poses: k->k+1 {:.3} m {:.2} deg, ATE {:.3} m",
            e.relative_1.translation_m.mean, e.relative_1.rotation_deg.mean, e.absolute_m.rmse
        )
    });
    #[allow(clippy::print_stdout)]
    {
        println!(
            "{}: {} of {} scans placed, {} skipped; {:.2} ms per scan (median), map consistency {:.1} %, start to end {:.2} m{eval}; outputs in {}",
            args.log.display(),
            r.placed,
            r.scans,
            r.skipped.len(),
            r.time_per_scan_ms[0],
            100.0 * r.map_consistency,
            r.start_to_end_m,
            args.out.display()
        );
    }
    Ok(())
}
