//! MCAP recording for `robot-app scan --record FILE` and `robot-app sim --record FILE`, and
//! opening recordings and other logs for replay.
//!
//! The file is written as `FILE.partial` and renamed to `FILE` when the recording finishes
//! (or when the [`Recorder`] is dropped); see `docs/logs.md`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use robot_base::{Command, LoggingBase, NoMotion};
use scan_log::{
    GeometryOverride, LEGS_METADATA, LegSummary, LogSource, McapRecorder, RecordedLaser,
    RecordedTruth, legs_metadata,
};
use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

use crate::config::Params;
use crate::outputs::RunLog;
use crate::runloop::{Evaluation, LoopRun, run_loop};

/// Records scans (and poses) to a goalseek MCAP file that Foxglove opens as it is.
pub struct Recorder {
    inner: Option<McapRecorder>,
    geometry: ScanGeometry,
    path: PathBuf,
}

impl Recorder {
    /// Starts recording to `path`; `geometry` is used by [`Recorder::write`].
    pub fn create(path: &Path, geometry: &ScanGeometry) -> anyhow::Result<Recorder> {
        let inner = McapRecorder::create(path)?;
        tracing::info!("recording to {}", path.display());
        Ok(Recorder {
            inner: Some(inner),
            geometry: *geometry,
            path: path.to_path_buf(),
        })
    }

    /// The final path of the recording.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Scans recorded so far.
    pub fn scans(&self) -> u64 {
        self.inner.as_ref().map_or(0, McapRecorder::scans)
    }

    /// Records a scan of the geometry given to [`Recorder::create`], without poses.
    pub fn write(&mut self, scan: &Scan) -> anyhow::Result<()> {
        let g = self.geometry;
        self.record_scan(&g, scan, None, None)
    }

    /// Records a scan with its geometry and, where known, the true and estimated poses.
    pub fn record_scan(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        true_pose: Option<Pose2>,
        est_pose: Option<Pose2>,
    ) -> anyhow::Result<()> {
        let inner = self
            .inner
            .as_mut()
            .with_context(|| format!("{}: recording already finished", self.path.display()))?;
        inner.record_scan(geometry, scan, true_pose, est_pose)?;
        Ok(())
    }

    /// Closes the file and moves it to its final name; returns the number of scans.
    pub fn finish(mut self) -> anyhow::Result<u64> {
        self.close()
    }

    fn close(&mut self) -> anyhow::Result<u64> {
        match self.inner.take() {
            Some(r) => {
                let n = r.finish()?;
                tracing::info!("recorded {n} scans to {}", self.path.display());
                Ok(n)
            }
            None => Ok(0),
        }
    }
}

impl Drop for Recorder {
    fn drop(&mut self) {
        if let Err(e) = self.close() {
            tracing::error!("closing the recording {}: {e:#}", self.path.display());
        }
    }
}

/// Opens a log (CARMEN, BreezySLAM, goalseek MCAP), with an optional sensor preset name
/// (`paper`, `urg-04lx`, `utm-30lx`) overriding its geometry (see [`scan_log::open_log`]).
pub fn open_log(path: &Path, sensor: Option<&str>) -> anyhow::Result<LogSource> {
    let preset = sensor.map(sensor_override).transpose()?;
    scan_log::open_log(path, preset.as_ref())
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

/// The legs of a run's log.
pub fn leg_summaries(log: &RunLog) -> Vec<LegSummary> {
    let xy = |p: WorldPoint| [p.x_m(), p.y_m()];
    log.legs
        .iter()
        .map(|l| LegSummary {
            leg: l.leg,
            estimate: [l.estimate.x_m, l.estimate.y_m, l.estimate.theta_rad],
            landmark: l.landmark.map(xy),
            point_b: l.point_b.map(xy),
        })
        .collect()
}

impl Recorder {
    /// Writes an MCAP metadata record (name and string pairs).
    pub fn write_metadata(
        &mut self,
        name: &str,
        values: &BTreeMap<String, String>,
    ) -> anyhow::Result<()> {
        let inner = self
            .inner
            .as_mut()
            .with_context(|| format!("{}: recording already finished", self.path.display()))?;
        inner.write_metadata(name, values)?;
        Ok(())
    }

    /// Writes the legs of a finished run ([`LEGS_METADATA`]).
    pub fn write_legs(&mut self, log: &RunLog, reason: &str) -> anyhow::Result<()> {
        let m = legs_metadata(&leg_summaries(log), reason);
        self.write_metadata(LEGS_METADATA, &m)
    }
}

// The recorded true poses as the loop's evaluation; a recording knows no collisions.
impl Evaluation for RecordedTruth {
    fn true_pose(&self) -> Pose2 {
        self.pose().unwrap_or_default()
    }
    fn collisions(&self) -> usize {
        0
    }
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
