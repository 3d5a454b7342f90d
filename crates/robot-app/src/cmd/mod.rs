//! One module per `robot-app` command: its arguments and its `run`.

pub mod batch;
pub mod emulate;
pub mod expand;
pub mod explore;
pub mod explore_batch;
pub mod info;
pub mod landmarks;
pub mod map;
pub mod replay;
pub mod run;
pub mod scan;
pub mod sim;
pub mod slam;
pub mod world;

use std::path::PathBuf;

use anyhow::Context;
use clap::Args;

use crate::config::{Method, Params};

/// Options shared by the commands that run the goal-seeking loop (`sim`, `run`, `explore`).
#[derive(Debug, Clone, Args)]
pub struct LoopOptions {
    /// TOML file overriding tuning parameters (see docs/robot-app.md).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Method preset: paper (as written) or goalseek (default).
    #[arg(long)]
    pub method: Option<Method>,
    /// Output folder.
    #[arg(long, default_value = "goalseek-out")]
    pub out: PathBuf,
    /// Record every scan to this MCAP file (Foxglove opens it); in the simulator with the
    /// true and estimated poses, and `robot-app replay FILE --loop` repeats the run from it.
    #[arg(long, value_name = "FILE")]
    pub record: Option<PathBuf>,
    /// What --record writes: foxglove (goalseek's replayable recording) or ros2 (ROS 2
    /// messages: /scan, poses, /tf and /map, for ros2 bag, rosbags, Foxglove).
    #[arg(long, value_enum, default_value = "foxglove", requires = "record")]
    pub profile: crate::record::RecordProfile,
    /// After the run, map it with SLAM (as `robot-app slam --motion-prior`: loop closure on,
    /// each scan's search centred on the robot's own estimate) from every scan it read, into
    /// OUT/slam/; records to OUT/run.mcap unless --record is given (`run` does this by
    /// default).
    #[arg(long)]
    pub slam_map: bool,
}

impl LoopOptions {
    /// Loads the configuration, creates the output folder and writes the configuration used
    /// into it as `config.toml`.
    pub fn prepare(&self) -> anyhow::Result<Params> {
        let config = self.load()?;
        self.write_config(&config)?;
        Ok(config)
    }

    /// Loads the configuration (`--config` over the `--method` preset).
    pub fn load(&self) -> anyhow::Result<Params> {
        crate::config::load(self.config.as_deref(), self.method)
    }

    /// [`LoopOptions::load`] over the preset changed by a command's own defaults.
    pub fn load_over(&self, adjust: impl Fn(&mut Params)) -> anyhow::Result<Params> {
        crate::config::load_over(self.config.as_deref(), self.method, adjust)
    }

    /// The file to record to: `--record`'s, or `OUT/run.mcap` with `--slam-map`.
    pub fn record_path(&self) -> Option<PathBuf> {
        self.record
            .clone()
            .or_else(|| self.slam_map.then(|| self.out.join("run.mcap")))
    }

    /// With `--slam-map`: maps the run's recording as `robot-app slam --motion-prior` does
    /// (default parameters and map settings) into `OUT/slam/`. A recording without a scan is reported
    /// and skipped; an error is logged as well as returned, so that a caller that ends on the
    /// run's own outcome first still shows it. The SLAM run, when there was one.
    pub fn write_slam_map(&self) -> anyhow::Result<Option<::slam::SlamRun>> {
        let (true, Some(path)) = (self.slam_map, self.record_path()) else {
            return Ok(None);
        };
        let map = || -> anyhow::Result<Option<::slam::SlamRun>> {
            let (front, loops) = slam::load_params(None)?;
            let mut run = match slam::run_log_with_motion(&path, &front, Some(&loops)) {
                Ok(run) => run,
                Err(e)
                    if e.chain().any(|c| {
                        matches!(
                            c.downcast_ref::<scan_log::LogError>(),
                            Some(scan_log::LogError::NoScans { .. })
                        )
                    }) =>
                {
                    return Ok(None);
                }
                Err(e) => return Err(e.context(format!("mapping {}", path.display()))),
            };
            let dir = self.out.join("slam");
            slam::write_outputs(
                &dir,
                &mut run,
                slam::MAP_RESOLUTION_M,
                slam::MAP_MAX_RANGE_M,
            )
            .with_context(|| format!("writing {}", dir.display()))?;
            Ok(Some(run))
        };
        match map() {
            Ok(Some(run)) => {
                tracing::info!(
                    placed = run.report.placed,
                    scans = run.report.scans,
                    "SLAM map and trajectory in {}",
                    self.out.join("slam").display()
                );
                Ok(Some(run))
            }
            Ok(None) => {
                tracing::warn!("SLAM map: {} holds no scan to map", path.display());
                Ok(None)
            }
            Err(e) => {
                tracing::error!("SLAM map: {e:#}");
                Err(e.context("SLAM map"))
            }
        }
    }

    /// Creates the output folder and writes `config` into it as `config.toml`.
    pub fn write_config(&self, config: &Params) -> anyhow::Result<()> {
        std::fs::create_dir_all(&self.out)
            .with_context(|| format!("--out: cannot create {}", self.out.display()))?;
        crate::outputs::write_atomic(
            &self.out.join("config.toml"),
            crate::config::to_toml_string(config).as_bytes(),
        )
    }
}

/// Reconnection of a Hokuyo that disappears mid-run: 0.1 s doubling to 2 s, for about 30 s,
/// given up at once on Ctrl-C or SIGTERM.
pub const RECONNECT: urg_driver::Backoff = urg_driver::Backoff {
    initial: std::time::Duration::from_millis(100),
    max: std::time::Duration::from_secs(2),
    factor: 2.0,
    max_attempts: Some(20),
    cancel: Some(crate::interrupt::requested),
};

/// Opens the Hokuyo at `port` (a serial device or `tcp:HOST:PORT`) so that it survives being
/// unplugged or its connection dropping ([`RECONNECT`]).
pub fn open_sensor(
    port: &str,
    config: urg_driver::UrgConfig,
) -> anyhow::Result<urg_driver::PortUrg> {
    use anyhow::Context;
    urg_driver::PortUrg::open_port(port, config, RECONNECT)
        .with_context(|| format!("cannot connect to the Hokuyo on {port}"))
}

/// Checks `--resolution` (0.01 to 1 m) and `--max-range` (above 0, at most 100 m) of the
/// map-writing commands.
pub fn check_map_options(resolution_m: f64, max_range_m: f64) -> anyhow::Result<()> {
    if !(resolution_m.is_finite() && (0.01..=1.0).contains(&resolution_m)) {
        anyhow::bail!("--resolution {resolution_m}: must be from 0.01 to 1 m");
    }
    if !(max_range_m.is_finite() && max_range_m > 0.0 && max_range_m <= 100.0) {
        anyhow::bail!("--max-range {max_range_m}: must be above 0 and at most 100 m");
    }
    Ok(())
}

/// `--noise` of `sim`, `scan` and `emulate`: the simulated sensor's noise on or off.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Noise {
    /// The sensor preset's noise (`default` is the same).
    #[value(alias = "default")]
    On,
    /// No noise.
    Off,
}

impl Noise {
    /// True for [`Noise::On`].
    pub fn is_on(self) -> bool {
        self == Noise::On
    }
}

/// A whole number of at least 1 (`--count`), for clap's `value_parser`.
pub fn positive_count(text: &str) -> Result<usize, String> {
    match text.parse::<usize>() {
        Ok(n) if n >= 1 => Ok(n),
        Ok(_) => Err("must be at least 1".into()),
        Err(e) => Err(format!("not a whole number ({e})")),
    }
}

/// A finite number of at least 0 (rates, intervals), for clap's `value_parser`.
pub fn non_negative(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() && x >= 0.0 => Ok(x),
        Ok(_) => Err("must be a finite number >= 0".into()),
        Err(e) => Err(format!("not a number ({e})")),
    }
}
