//! `robot-app scan`: prints scans from a Hokuyo (or the simulator) as CSV or JSON.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::{Args, ValueEnum};
use scan_types::{LaserSource, Scan, ScanGeometry};
use urg_driver::{AcquisitionMode, UrgConfig};

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
    /// Serial device of the sensor (/dev/ttyACM0, /dev/hokuyo, or the path `robot-app emulate` prints), or tcp:HOST:PORT for an Ethernet model (tcp:192.168.0.10:10940).
    #[arg(long, required_unless_present = "sim", conflicts_with = "sim")]
    pub port: Option<String>,
    /// Number of scans to print (at least 1).
    #[arg(long, default_value_t = 1, value_parser = super::positive_count)]
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
    /// Sensor preset for --sim: paper, urg-04lx, utm-30lx or ust-10lx.
    #[arg(long, default_value = "paper", requires = "sim")]
    pub sensor: String,
    /// Seed of the simulated laser noise.
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Simulated laser noise: on (or default) or off.
    #[arg(long, value_enum, default_value = "on")]
    pub noise: super::Noise,
    /// Also record every scan to this file (MCAP).
    #[arg(long)]
    pub record: Option<PathBuf>,
    /// What --record writes: foxglove (goalseek's recording) or ros2 (sensor_msgs/LaserScan
    /// on /scan).
    #[arg(long, value_enum, default_value = "foxglove", requires = "record")]
    pub profile: crate::record::RecordProfile,
}

/// Runs `robot-app scan`, printing to stdout.
pub fn run(args: ScanArgs) -> anyhow::Result<()> {
    let stdout = std::io::stdout();
    run_to(&args, &mut stdout.lock())
}

/// Runs `robot-app scan`, writing to `out`. A Hokuyo that is unplugged is waited for
/// ([`super::RECONNECT`]); a stop asked for by a signal ends the scans, finishes the
/// recording and returns [`crate::interrupt::Interrupted`].
pub fn run_to<W: Write>(args: &ScanArgs, out: &mut W) -> anyhow::Result<()> {
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
            args.noise.is_on(),
        )?;
        let period_s = args
            .sensor
            .parse::<sim_laser::SensorPreset>()
            .ok()
            .map(|s| s.scan_period_s());
        return print_scans(&mut source, period_s, args, out);
    }
    let port = args
        .port
        .as_deref()
        .context("--port PATH (or tcp:HOST:PORT) or --sim is required")?;
    let config = UrgConfig {
        mode: if args.stream {
            AcquisitionMode::Streaming
        } else {
            AcquisitionMode::Polled
        },
        ..UrgConfig::default()
    };
    let mut urg = super::open_sensor(port, config)?;
    let period_s = urg
        .urg_mut()
        .map(|u| u.params().scan_period().as_secs_f64());
    let printed = print_scans(&mut urg, period_s, args, out);
    let stopped = match urg.urg_mut() {
        Some(u) => {
            let stats = u.stats();
            if stats.checksum_errors + stats.malformed_replies > 0 {
                tracing::warn!(
                    "{} scans dropped for checksum errors, {} malformed replies",
                    stats.checksum_errors,
                    stats.malformed_replies
                );
            }
            u.stop()
        }
        None => Ok(()),
    };
    printed?;
    stopped.context("stopping the stream (QT)")?;
    Ok(())
}

/// Prints `args.count` scans of `source` (fewer when a stop is asked for), recording them to
/// `args.record` (ROS 2 scan times from `scan_period_s`); the recording is finished whatever
/// happens.
fn print_scans<S: LaserSource, W: Write>(
    source: &mut S,
    scan_period_s: Option<f64>,
    args: &ScanArgs,
    out: &mut W,
) -> anyhow::Result<()> {
    let geometry = *source.geometry();
    let mut recorder: Option<Recorder> = None;
    let mut printed = || -> anyhow::Result<()> {
        for k in 0..args.count {
            if crate::interrupt::requested() {
                return Err(anyhow::Error::new(crate::interrupt::Interrupted));
            }
            let scan = source
                .next_scan()
                .map_err(|e| anyhow::anyhow!(e))
                .with_context(|| format!("reading scan {} of {}", k + 1, args.count))?;
            print_scan(out, args.format, k, &geometry, &scan, || {
                scan_log::scan_json(k, &geometry, &scan)
            })?;
            if let Some(path) = &args.record {
                let r = match &mut recorder {
                    Some(r) => r,
                    None => {
                        let r = Recorder::create_profile(path, &geometry, args.profile)?;
                        recorder.insert(r.with_scan_period(scan_period_s))
                    }
                };
                r.write(&scan)?;
            }
        }
        Ok(())
    };
    let printed = printed();
    let finished = recorder.map(Recorder::finish).transpose();
    out.flush()?;
    printed?;
    finished?;
    Ok(())
}

/// Prints scan number `k` in `format`: a CSV block (after a blank line but for the first) or
/// one line of JSON, `json` giving the object.
pub fn print_scan<W: Write>(
    out: &mut W,
    format: ScanFormat,
    k: usize,
    geometry: &ScanGeometry,
    scan: &Scan,
    json: impl FnOnce() -> serde_json::Value,
) -> anyhow::Result<()> {
    match format {
        ScanFormat::Csv => {
            if k > 0 {
                writeln!(out)?;
            }
            scan_log::write_scan_csv(&mut *out, geometry, scan)?;
        }
        ScanFormat::Json => {
            serde_json::to_writer(&mut *out, &json())?;
            writeln!(out)?;
        }
    }
    Ok(())
}
