//! MCAP recording for `robot-app scan --record FILE` and `robot-app sim --record FILE`, and
//! opening recordings and other logs for replay.
//!
//! The file is written as `FILE.partial` and renamed to `FILE` when the recording finishes
//! (or when the [`Recorder`] is dropped); see `docs/logs.md`.

use std::path::Path;

use anyhow::Context;
use robot_base::{Command, LoggingBase, NoMotion};
use scan_log::{GeometryOverride, LogError, LogSource, McapRecorder, RecordedLaser, RunLog};
use scan_types::{Pose2, ScanGeometry, WorldPoint};

use crate::config::Params;
use crate::runloop::{LoopRun, run_loop};

/// A goalseek MCAP recording ([`McapRecorder`], whose methods it has) that also takes the legs
/// of a run.
pub struct Recorder(McapRecorder);

impl Recorder {
    /// Starts recording to `path`; `geometry` is the one of [`McapRecorder::write`].
    pub fn create(path: &Path, geometry: &ScanGeometry) -> Result<Recorder, LogError> {
        Ok(Recorder(
            McapRecorder::create(path)?.with_geometry(geometry),
        ))
    }

    /// Writes the legs of a finished run ([`scan_log::LEGS_METADATA`]).
    pub fn write_legs(&mut self, log: &RunLog, reason: &str) -> Result<(), LogError> {
        self.0.write_legs(&log.leg_summaries(), reason)
    }

    /// Closes the file and moves it to its final name; returns the number of scans.
    pub fn finish(self) -> Result<u64, LogError> {
        self.0.finish()
    }
}

impl std::ops::Deref for Recorder {
    type Target = McapRecorder;
    fn deref(&self) -> &McapRecorder {
        &self.0
    }
}

impl std::ops::DerefMut for Recorder {
    fn deref_mut(&mut self) -> &mut McapRecorder {
        &mut self.0
    }
}

/// Opens a log (CARMEN, BreezySLAM, goalseek MCAP), with an optional sensor preset name
/// (`paper`, `urg-04lx`, `utm-30lx`) overriding its geometry (see [`scan_log::open_log`]).
pub fn open_log(path: &Path, sensor: Option<&str>) -> anyhow::Result<LogSource> {
    open_log_topic(path, sensor, None)
}

/// Opens a log as [`open_log`] does, reading the laser topic `topic` of a bag or MCAP file
/// (`None`: its only one; see [`scan_log::open_log_topic`]).
pub fn open_log_topic(
    path: &Path,
    sensor: Option<&str>,
    topic: Option<&str>,
) -> anyhow::Result<LogSource> {
    let preset = sensor.map(sensor_override).transpose()?;
    scan_log::open_log_topic(path, preset.as_ref(), topic)
        .with_context(|| format!("opening the log {}", path.display()))
}

/// The geometry of the sensor preset `name`, as `--sensor NAME` overrides a log's.
fn sensor_override(name: &str) -> anyhow::Result<GeometryOverride> {
    let geometry = name
        .parse::<sim_laser::SensorPreset>()
        .map_err(|e| anyhow::anyhow!("--sensor {name}: {e}"))?
        .geometry();
    Ok(GeometryOverride {
        name: format!("--sensor {name}"),
        geometry,
    })
}

/// The settings of a recorded run with the loop's tuning ([`scan_log::RunSettings`]).
pub type RunSettings = scan_log::RunSettings<Params>;

/// The settings of a recording made by `robot-app sim --record`, the tuning validated.
pub fn read_settings(path: &Path) -> anyhow::Result<RunSettings> {
    let settings = RunSettings::read(path)?;
    settings
        .config
        .validate()
        .with_context(|| path.display().to_string())?;
    Ok(settings)
}

/// A recording replayed through the loop.
pub struct LoopReplay {
    /// The loop's outcome and leg rows.
    pub run: LoopRun,
    /// The commands the loop gave (executed by nothing).
    pub commands: Vec<Command>,
    /// Scans of the recording the loop read.
    pub scans_read: usize,
    /// Scans of the recording left unread.
    pub scans_left: usize,
}

/// Feeds the scans of a recording to the goal-seeking loop (`config`, `start`, `goal`) with a
/// base that executes nothing, the recorded true poses standing in for the simulator's truth.
pub fn replay_loop(
    path: &Path,
    config: &Params,
    start: Pose2,
    goal: WorldPoint,
) -> anyhow::Result<LoopReplay> {
    let source = open_log(path, None)?;
    let (mut laser, truth) = RecordedLaser::new(source);
    let mut base = LoggingBase::new(NoMotion);
    let run = run_loop(
        &mut laser,
        &mut base,
        config,
        (start, goal),
        Some(&truth),
        None,
    )?;
    let scans_read = laser.source().scans_read();
    let mut scans_left = 0;
    let mut rest = laser.into_source();
    while rest.next_record().is_ok() {
        scans_left += 1;
    }
    Ok(LoopReplay {
        run,
        commands: base.commands,
        scans_read,
        scans_left,
    })
}
