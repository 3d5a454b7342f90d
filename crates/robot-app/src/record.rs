//! MCAP recording for `robot-app scan --record FILE` and `robot-app sim --record FILE`, and
//! opening recordings and other logs for replay.
//!
//! The file is written as `FILE.partial` and renamed to `FILE` when the recording finishes
//! (or when the [`Recorder`] is dropped); see `docs/logs.md`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::Context;
use robot_base::{Command, LoggingBase, NoMotion};
use scan_log::{GeometryOverride, LogSource, McapRecorder, RecordedLaser, RecordedTruth};
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

/// Name of the MCAP metadata record with the settings of a recorded simulated run.
pub const RUN_METADATA: &str = "goalseek.run";
/// Name of the MCAP metadata record with the legs a recorded run drove.
pub const LEGS_METADATA: &str = "goalseek.legs";

/// The settings of a recorded run: what a replay through the loop needs to repeat it.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSettings {
    /// Start pose (the estimate's origin).
    pub start: Pose2,
    /// Target.
    pub goal: WorldPoint,
    /// Tuning of the loop.
    pub config: Params,
    /// World name (information only).
    pub world: String,
    /// Sensor preset name (information only).
    pub sensor: String,
    /// Noise seed (information only).
    pub seed: u64,
    /// Noise on (information only).
    pub noise: bool,
}

fn json_of<T: serde::Serialize>(v: &T) -> String {
    serde_json::to_string(v).expect("plain data serialises")
}

fn json_field<T: serde::de::DeserializeOwned>(
    m: &BTreeMap<String, String>,
    key: &str,
) -> anyhow::Result<T> {
    let text = m
        .get(key)
        .with_context(|| format!("metadata '{RUN_METADATA}' has no '{key}'"))?;
    serde_json::from_str(text)
        .with_context(|| format!("metadata '{RUN_METADATA}': '{key}' = {text:?}"))
}

impl RunSettings {
    /// The settings as MCAP metadata (JSON values; floats round-trip exactly).
    pub fn to_metadata(&self) -> BTreeMap<String, String> {
        let p = self.start;
        BTreeMap::from([
            ("start".into(), json_of(&[p.x_m, p.y_m, p.theta_rad])),
            ("goal".into(), json_of(&[self.goal.x_m(), self.goal.y_m()])),
            ("config".into(), json_of(&self.config)),
            ("world".into(), json_of(&self.world)),
            ("sensor".into(), json_of(&self.sensor)),
            ("seed".into(), json_of(&self.seed)),
            ("noise".into(), json_of(&self.noise)),
        ])
    }

    /// Reads the settings back from [`RunSettings::to_metadata`].
    pub fn from_metadata(m: &BTreeMap<String, String>) -> anyhow::Result<Self> {
        let [x_m, y_m, theta_rad]: [f64; 3] = json_field(m, "start")?;
        let [gx, gy]: [f64; 2] = json_field(m, "goal")?;
        let config: Params = json_field(m, "config")?;
        config.validate()?;
        Ok(Self {
            start: Pose2 {
                x_m,
                y_m,
                theta_rad,
            },
            goal: WorldPoint::new(gx, gy),
            config,
            world: json_field(m, "world")?,
            sensor: json_field(m, "sensor")?,
            seed: json_field(m, "seed")?,
            noise: json_field(m, "noise")?,
        })
    }

    /// The settings of a recording made by `robot-app sim --record`.
    pub fn read(path: &Path) -> anyhow::Result<Self> {
        let meta = scan_log::read_mcap_metadata(path)?;
        let (_, m) = meta
            .iter()
            .find(|(n, _)| n == RUN_METADATA)
            .with_context(|| {
                format!(
                    "{}: no '{RUN_METADATA}' metadata (not a recording of `robot-app sim --record`)",
                    path.display()
                )
            })?;
        Self::from_metadata(m).with_context(|| path.display().to_string())
    }
}

/// One leg as a run recorded it: where it ended by the estimate, its landmark and point B.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LegSummary {
    /// Leg number (0 = start).
    pub leg: usize,
    /// Estimate at the end of the leg: x, y, theta (rad).
    pub estimate: [f64; 3],
    /// The landmark the leg localised on (world frame by the estimate).
    pub landmark: Option<[f64; 2]>,
    /// Point B of the leg.
    pub point_b: Option<[f64; 2]>,
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

/// The legs a recorded run drove (metadata written by `robot-app sim --record`), if stored.
pub fn read_recorded_legs(path: &Path) -> anyhow::Result<Option<(String, Vec<LegSummary>)>> {
    let meta = scan_log::read_mcap_metadata(path)?;
    let Some((_, m)) = meta.iter().find(|(n, _)| n == LEGS_METADATA) else {
        return Ok(None);
    };
    let legs = m
        .get("legs")
        .with_context(|| format!("{}: '{LEGS_METADATA}' without 'legs'", path.display()))?;
    let legs = serde_json::from_str(legs)
        .with_context(|| format!("{}: '{LEGS_METADATA}' legs", path.display()))?;
    Ok(Some((m.get("reason").cloned().unwrap_or_default(), legs)))
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
        let m = BTreeMap::from([
            ("legs".to_string(), json_of(&leg_summaries(log))),
            ("reason".to_string(), reason.to_string()),
        ]);
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
