//! `robot-app scan`: prints scans from a Hokuyo (or the simulator) as CSV or JSON.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::Context;
use clap::{Args, ValueEnum};
use scan_types::{LaserSource, RayStatus, Scan, ScanGeometry};
use urg_driver::{AcquisitionMode, Urg, UrgConfig};

use crate::record::Recorder;

/// Output format of `robot-app scan`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ScanFormat {
    /// One scan CSV block per scan (columns index,bearing_rad,range_m,valid), see `scan_csv`.
    Csv,
    /// One JSON object per line per scan.
    Json,
}

/// Arguments of `robot-app scan`.
#[derive(Debug, Args)]
pub struct ScanArgs {
    /// Serial device of the sensor (/dev/ttyACM0, /dev/hokuyo, or the path `robot-app emulate` prints).
    #[arg(long, required_unless_present = "sim", conflicts_with = "sim")]
    pub port: Option<String>,
    /// Number of scans to print.
    #[arg(long, default_value_t = 1)]
    pub count: usize,
    /// Output format.
    #[arg(long, value_enum, default_value = "csv")]
    pub format: ScanFormat,
    /// Stream scans with MD (at the sensor's period) instead of one GD request per scan.
    #[arg(long)]
    pub stream: bool,
    /// Scan the simulator instead of a device.
    #[arg(long)]
    pub sim: bool,
    /// World file for --sim (.toml, .yaml, .png); default: the paper's world.
    #[arg(long, requires = "sim")]
    pub world: Option<PathBuf>,
    /// Robot pose for --sim: X,Y,THETA_DEG (default: the paper's start).
    #[arg(long, requires = "sim", allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Sensor preset for --sim: paper, urg-04lx, utm-30lx.
    #[arg(long, default_value = "paper", requires = "sim")]
    pub sensor: String,
    /// Seed of the simulated laser noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Simulated laser noise on or off.
    #[arg(long, default_value = "on", value_parser = ["on", "off"])]
    pub noise: String,
    /// Also record every scan to this file (MCAP).
    #[arg(long)]
    pub record: Option<PathBuf>,
}

/// Called with every scan after it is printed (the `--record` hook).
pub type ScanSink<'a> = Box<dyn FnMut(&ScanGeometry, &Scan) -> anyhow::Result<()> + 'a>;

/// Runs `robot-app scan`, printing to stdout.
pub fn run(args: ScanArgs) -> anyhow::Result<()> {
    let stdout = std::io::stdout();
    super::reader_gone_is_ok(run_to(&args, &mut stdout.lock()))
}

/// Runs `robot-app scan`, writing to `out`.
pub fn run_to<W: Write>(args: &ScanArgs, out: &mut W) -> anyhow::Result<()> {
    let mut sink = match &args.record {
        Some(path) => Some(record_sink(path)?),
        None => None,
    };
    if args.sim {
        let pose = match &args.pose {
            Some(p) => crate::simsetup::parse_pose(p)?,
            None => crate::simsetup::paper_start(),
        };
        // ---- `--sim` call site: the simulator source comes from `crate::simsetup`. ----
        let mut source = crate::simsetup::sim_scan_source(
            args.world.as_deref(),
            pose,
            &args.sensor,
            args.seed,
            args.noise == "on",
        )?;
        return print_scans(&mut source, args, out, sink.as_mut());
    }
    let port = args
        .port
        .as_deref()
        .context("--port PATH or --sim is required")?;
    let config = UrgConfig {
        mode: if args.stream {
            AcquisitionMode::Streaming
        } else {
            AcquisitionMode::Polled
        },
        ..UrgConfig::default()
    };
    let mut urg =
        Urg::open(port, config).with_context(|| format!("connecting to the sensor at {port}"))?;
    let r = print_scans(&mut urg, args, out, sink.as_mut());
    let stop = urg.stop();
    let stats = urg.stats();
    if stats.checksum_errors + stats.malformed_replies > 0 {
        tracing::warn!(
            "{} scans dropped for checksum errors, {} malformed replies",
            stats.checksum_errors,
            stats.malformed_replies
        );
    }
    r?;
    stop.context("stopping the stream (QT)")?;
    Ok(())
}

/// The recorder behind `--record FILE`: records every scan printed.
fn record_sink(path: &Path) -> anyhow::Result<ScanSink<'static>> {
    let mut rec: Option<Recorder> = None;
    let path = path.to_path_buf();
    Ok(Box::new(move |g: &ScanGeometry, s: &Scan| {
        let r = match &mut rec {
            Some(r) => r,
            None => rec.insert(Recorder::create(&path, g)?),
        };
        r.record_scan(g, s, None, None)
    }))
}

fn print_scans<S: LaserSource, W: Write>(
    source: &mut S,
    args: &ScanArgs,
    out: &mut W,
    mut sink: Option<&mut ScanSink<'_>>,
) -> anyhow::Result<()> {
    let geometry = *source.geometry();
    for k in 0..args.count {
        let scan = source
            .next_scan()
            .map_err(|e| anyhow::anyhow!(e))
            .with_context(|| format!("reading scan {} of {}", k + 1, args.count))?;
        match args.format {
            ScanFormat::Csv => {
                if k > 0 {
                    writeln!(out)?;
                }
                scan_log::write_scan_csv(&mut *out, &geometry, &scan)?;
            }
            ScanFormat::Json => {
                serde_json::to_writer(&mut *out, &scan_json(k, &geometry, &scan))?;
                writeln!(out)?;
            }
        }
        if let Some(s) = sink.as_mut() {
            s(&geometry, &scan)?;
        }
    }
    out.flush()?;
    Ok(())
}

/// One scan as JSON: geometry, time stamps, ranges (null for invalid rays) and statuses.
pub fn scan_json(index: usize, g: &ScanGeometry, scan: &Scan) -> serde_json::Value {
    let ranges: Vec<Option<f64>> = scan
        .ranges_m
        .iter()
        .map(|&r| r.is_finite().then_some(r))
        .collect();
    let status: Vec<String> = scan
        .status
        .iter()
        .map(|s| match s {
            RayStatus::Hit => "hit".to_string(),
            RayStatus::MaxRange => "max_range".to_string(),
            RayStatus::Error(c) => format!("error:{c}"),
        })
        .collect();
    serde_json::json!({
        "scan": index,
        "sensor_time_ms": scan.sensor_time_ms,
        "host_time_s": scan.host_time_s,
        "first_bearing_rad": g.first_bearing_rad,
        "increment_rad": g.increment_rad,
        "ray_count": g.ray_count,
        "min_range_m": g.min_range_m,
        "max_range_m": g.max_range_m,
        "ranges_m": ranges,
        "status": status,
        "intensities": scan.intensities,
    })
}
