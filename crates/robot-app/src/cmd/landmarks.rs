//! `robot-app landmarks`: landmark detection and re-identification over every scan of a log.
//!
//! For each scan: the landmarks found, how many of them are re-identified in the next scan,
//! and how many are range-limit artefacts (a hit within the margin of the maximum range) or
//! dropout artefacts (the no-return gap beside an edge is at most `--dropout-rays` rays wide).
//! The counting is [`landmarks::count_log`]'s.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use landmarks::{DetectParams, LandmarkCounts, TrackParams, count_log};
use scan_types::LaserSource;

/// Arguments of `robot-app landmarks`.
#[derive(Debug, Args)]
pub struct LandmarksArgs {
    /// The log: CARMEN .log/.log.gz, BreezySLAM .dat, an MCAP file (goalseek, ROS 2,
    /// Foxglove) or a rosbag2 bag (.db3 file or bag folder).
    #[arg(long)]
    pub log: PathBuf,
    /// Detection rules: paper (max-range jumps, n = 1, nothing rejected) or goalseek.
    #[arg(long, default_value = "paper", value_parser = ["paper", "goalseek"])]
    pub params: String,
    /// Tracking gate, metres (default: the tracker's for the chosen rules).
    #[arg(long)]
    pub gate: Option<f64>,
    /// A no-return gap of at most this many rays beside an edge is counted as a dropout.
    #[arg(long, default_value_t = 3)]
    pub dropout_rays: usize,
    /// Sensor preset whose geometry replaces the log's: paper, urg-04lx, utm-30lx or ust-10lx.
    #[arg(long)]
    pub sensor: Option<String>,
    /// The laser topic to read when a bag or MCAP file holds several (e.g. /scan).
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// Print one CSV row per scan before the totals.
    #[arg(long)]
    pub per_scan: bool,
}

/// Runs `robot-app landmarks`.
pub fn run(args: LandmarksArgs) -> anyhow::Result<()> {
    let mut source =
        crate::record::open_log_topic(&args.log, args.sensor.as_deref(), args.topic.as_deref())?;
    let geometry = *source.geometry();
    let (detect_params, mut track) = if args.params == "paper" {
        (DetectParams::paper(), TrackParams::paper())
    } else {
        (DetectParams::default(), TrackParams::default())
    };
    track.detect = detect_params;
    if let Some(g) = args.gate {
        if !(g.is_finite() && g > 0.0) {
            anyhow::bail!("--gate {g}: must be a positive number of metres");
        }
        track.gate_m = g;
    }
    let mut records = Vec::new();
    loop {
        crate::interrupt::check()?;
        match source.next_record() {
            Ok(r) => records.push((r.scan.clone(), r.pose.or(r.true_pose))),
            Err(e) if e.is_end_of_log() => break,
            Err(e) => return Err(e).context("reading the log"),
        }
    }
    // In chunks (each with the next chunk's first scan, its pair), so that Ctrl-C is heard.
    let mut counts = Vec::with_capacity(records.len());
    for start in (0..records.len()).step_by(256) {
        crate::interrupt::check()?;
        let end = (start + 256).min(records.len());
        let window = &records[start..(end + 1).min(records.len())];
        let chunk = count_log(&geometry, window, &detect_params, &track, args.dropout_rays);
        counts.extend(chunk.into_iter().take(end - start));
    }
    let mut out = std::io::stdout().lock();
    if args.per_scan {
        writeln!(
            out,
            "scan,found,max_range_jumps,reidentified_next,range_limit,dropout"
        )?;
    }
    let mut total = LandmarkCounts::default();
    for (k, c) in counts.iter().enumerate() {
        if args.per_scan {
            writeln!(
                out,
                "{k},{},{},{},{},{}",
                c.found, c.max_range_jumps, c.reidentified, c.range_limit, c.dropout
            )?;
        }
        total.add(c);
    }
    let with_poses = records.iter().filter(|r| r.1.is_some()).count();
    writeln!(
        out,
        "{}: {} scans ({} with poses), rules {}, gate {} m: {} landmarks ({:.2} a scan), {} of them max-range jumps ({:.2} a scan); re-identified in the next scan {} of {} ({:.1} %); range-limit artefacts {} ({:.1} %); dropout edges (gap <= {} rays) {} ({:.1} %), of which re-identified {:.1} %, others re-identified {:.1} %",
        args.log.display(),
        total.scans,
        with_poses,
        args.params,
        track.gate_m,
        total.found,
        total.found as f64 / total.scans.max(1) as f64,
        total.max_range_jumps,
        total.max_range_jumps as f64 / total.scans.max(1) as f64,
        total.reidentified,
        total.followed,
        100.0 * total.reid_rate(),
        total.range_limit,
        100.0 * total.range_limit as f64 / total.found.max(1) as f64,
        args.dropout_rays,
        total.dropout,
        100.0 * total.dropout as f64 / total.found.max(1) as f64,
        100.0 * total.dropout_reidentified as f64 / total.dropout_followed.max(1) as f64,
        100.0 * (total.reidentified - total.dropout_reidentified) as f64
            / (total.followed - total.dropout_followed).max(1) as f64,
    )?;
    Ok(())
}
