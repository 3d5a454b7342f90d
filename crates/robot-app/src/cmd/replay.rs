//! `robot-app replay`: streams a recorded log (CARMEN, BreezySLAM, goalseek MCAP) through the
//! live-sensor code path (`LaserSource`), printing each scan like `robot-app scan`.

use std::io::Write;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use scan_types::LaserSource;

use crate::cmd::scan::ScanFormat;

/// Arguments of `robot-app replay`.
#[derive(Debug, Args)]
pub struct ReplayArgs {
    /// The log: CARMEN .log/.log.gz, BreezySLAM .dat, an MCAP file (goalseek, ROS 2,
    /// Foxglove) or a rosbag2 bag (.db3 file or bag folder).
    pub file: PathBuf,
    /// Playback speed relative to the log's time stamps (2 = twice as fast, 0 = no waiting);
    /// a number >= 0.
    #[arg(long, default_value_t = 1.0, value_parser = super::non_negative)]
    pub rate: f64,
    /// Sensor preset whose geometry replaces the log's: paper, urg-04lx, utm-30lx or ust-10lx.
    #[arg(long)]
    pub sensor: Option<String>,
    /// The laser topic to read when a bag or MCAP file holds several (e.g. /scan).
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// Print at most this many scans, at least 1 (default: the whole log).
    #[arg(long, value_parser = super::positive_count)]
    pub count: Option<usize>,
    /// Output format (as `robot-app scan`).
    #[arg(long, value_enum, default_value = "csv")]
    pub format: ScanFormat,
    /// Also write the scans (with the log's poses) to this goalseek MCAP file.
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// What --record writes: foxglove (goalseek's recording) or ros2 (ROS 2 messages).
    #[arg(long, value_enum, default_value = "foxglove", requires = "record")]
    pub profile: crate::record::RecordProfile,
    /// Feed the scans of a `robot-app sim --record` recording to the goal-seeking loop (with
    /// the recorded settings and a base that executes nothing) and compare its legs with the
    /// recorded ones.
    #[arg(long = "loop")]
    pub through_loop: bool,
    /// With `--loop`: write `trajectory.csv` and `map.pgm`/`map.yaml`/`map.png` here.
    #[arg(long, value_name = "DIR", requires = "through_loop")]
    pub out: Option<PathBuf>,
    /// Live view (the scans with the log's poses; with `--loop` the loop's estimates and legs,
    /// paced by --rate).
    #[command(flatten)]
    pub live: crate::live::LiveOptions,
}

/// Cell size of the map the live view builds from a log's poses, metres.
const LIVE_MAP_RESOLUTION_M: f64 = 0.05;

/// A log's clock that jumps back, or ahead by more than this between two scans, seconds,
/// restarts the pacing of `--rate` (a log cut and joined, a clock reset).
const MAX_CLOCK_GAP_S: f64 = 10.0;

/// Runs `robot-app replay`, printing to stdout.
pub fn run(args: ReplayArgs) -> anyhow::Result<()> {
    let stdout = std::io::stdout();
    run_to(&args, &mut std::io::BufWriter::new(stdout.lock()))
}

/// Runs `robot-app replay`, writing to `out`.
pub fn run_to<W: Write>(args: &ReplayArgs, out: &mut W) -> anyhow::Result<()> {
    if args.through_loop {
        return run_loop(args, out);
    }
    let mut source =
        crate::record::open_log_topic(&args.file, args.sensor.as_deref(), args.topic.as_deref())?;
    let geometry = *source.geometry();
    let mut recorder = match &args.record {
        Some(p) => Some(crate::record::Recorder::create_profile(
            p,
            &geometry,
            args.profile,
        )?),
        None => None,
    };
    let mut live = args.live.start(LIVE_MAP_RESOLUTION_M)?;
    let started = Instant::now();
    // (log stamp, wall time since the start) pacing counts from, and the last scan's stamp.
    let mut first_stamp: Option<(f64, f64)> = None;
    let mut last_stamp: Option<f64> = None;
    let mut k = 0usize;
    let mut interrupted = false;
    let mut stopped: Option<anyhow::Error> = None;
    while args.count.is_none_or(|c| k < c) {
        if crate::interrupt::requested() {
            interrupted = true;
            break;
        }
        let rec = match source.next_record() {
            Ok(r) => r.clone(),
            Err(e) if e.is_end_of_log() => break,
            Err(e) => return Err(e).context("replaying"),
        };
        let scan = &rec.scan;
        // Pace by the log's own clock; where it jumps back or ahead by more than
        // MAX_CLOCK_GAP_S, pacing starts over from this scan.
        if args.rate > 0.0 && scan.host_time_s.is_finite() {
            let now = started.elapsed().as_secs_f64();
            let (t0, w0) = *first_stamp.get_or_insert((scan.host_time_s, now));
            let gap = scan.host_time_s - last_stamp.unwrap_or(scan.host_time_s);
            if !(0.0..=MAX_CLOCK_GAP_S).contains(&gap) {
                tracing::warn!(
                    scan = k,
                    gap_s = gap,
                    "the log's clock jumps here; paced from this scan on"
                );
                first_stamp = Some((scan.host_time_s, now));
            } else {
                let due = w0 + (scan.host_time_s - t0) / args.rate;
                if due > now && !crate::interrupt::sleep(Duration::from_secs_f64(due - now)) {
                    interrupted = true;
                    break;
                }
            }
            last_stamp = Some(scan.host_time_s);
        }
        // A reader that has gone away ends the replay; the recording is still finished.
        if let Err(e) = super::scan::print_scan(out, args.format, k, &geometry, scan, || {
            scan_log::record_json(k, &geometry, &rec)
        }) {
            stopped = Some(e);
            break;
        }
        if let Some(r) = recorder.as_mut() {
            r.record_scan(&geometry, scan, rec.true_pose, rec.pose)?;
        }
        if let Some(v) = live.as_mut() {
            v.scan(&rec.geometry, scan, rec.pose, rec.true_pose);
        }
        k += 1;
    }
    if let Some(v) = live {
        v.finish(None);
    }
    let flushed = out.flush();
    if let Some(r) = recorder {
        r.finish()?;
    }
    if let Some(e) = stopped {
        return Err(e);
    }
    flushed?;
    tracing::info!(
        "{}: {k} scans replayed, {} records skipped",
        args.file.display(),
        source.skipped()
    );
    if interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    Ok(())
}

/// `robot-app replay FILE --loop`: the recorded scans through the loop; fails if the legs
/// differ from the recorded ones or if the replayed run does not reach the target (as `sim`
/// fails then; a cut recording ends in `sensor_failure`).
fn run_loop<W: Write>(args: &ReplayArgs, out: &mut W) -> anyhow::Result<()> {
    use crate::record::{read_settings, replay_loop_live};
    let settings = read_settings(&args.file)?;
    let mut live = args
        .live
        .start(settings.config.localiser.map_resolution_m)?
        .map(|v| v.with_rate(args.rate).with_goal(settings.goal));
    let replay = replay_loop_live(
        &args.file,
        &settings.config,
        (settings.start, settings.goal),
        live.as_mut(),
    )?;
    if let Some(v) = live {
        v.finish(Some(&replay.run.outcome.grid));
    }
    let o = &replay.run.outcome;
    let log = &replay.run.log;
    writeln!(
        out,
        "replayed {} through the loop: {} after {} legs, {} scans read, {} left, {} commands",
        args.file.display(),
        o.reason,
        o.legs_driven,
        replay.scans_read,
        replay.scans_left,
        replay.commands.len()
    )?;
    if let Some(dir) = &args.out {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        scan_log::write_trajectory(dir, log)?;
        crate::outputs::write_grid(dir, &o.grid)?;
    }
    let compared = compare_legs(&args.file, &log.leg_summaries(), o.legs_driven, out);
    out.flush()?;
    compared?;
    if o.reason == crate::outputs::Reason::Interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    if o.reason != crate::outputs::Reason::Reached {
        anyhow::bail!(
            "the replayed run did not reach the target: {} ({})",
            o.reason,
            o.note
        );
    }
    Ok(())
}

/// Compares the legs of the replay with those recorded in `file` (if any), saying so to `out`;
/// an error names the first row that differs.
fn compare_legs<W: Write>(
    file: &std::path::Path,
    replayed: &[scan_log::LegSummary],
    legs_driven: usize,
    out: &mut W,
) -> anyhow::Result<()> {
    let Some((reason, recorded)) = scan_log::read_recorded_legs(file)? else {
        writeln!(out, "the recording holds no legs to compare with")?;
        return Ok(());
    };
    let Some(difference) = scan_log::leg_difference(&recorded, replayed) else {
        writeln!(
            out,
            "same legs as recorded: {} rows (start + {legs_driven} legs), every estimate, landmark and point B bit for bit; recorded end: {reason}",
            recorded.len(),
        )?;
        return Ok(());
    };
    anyhow::bail!("the replayed legs differ from the recorded ones at {difference}")
}
