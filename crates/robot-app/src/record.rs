//! MCAP recording for `--record FILE` (`sim`, `run`, `scan`, `replay`) in goalseek's Foxglove
//! profile or as ROS 2 messages (`--profile ros2`), and opening recordings and other logs for
//! replay.
//!
//! The file is written as `FILE.partial` and renamed to `FILE` when the recording finishes
//! (or when the [`Recorder`] is dropped); see `docs/logs.md`.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::Context;
use localiser::{CellState, OccupancyGrid};
use robot_base::{Command, LoggingBase, NoMotion};
use scan_log::{
    GeometryOverride, LogError, LogSource, McapRecorder, RecordedLaser, Ros2Map, Ros2Recorder,
    RunLog,
};
use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

use crate::config::Params;
use crate::runloop::{LoopRun, run_loop_legs};

/// What a `--record` file holds.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum RecordProfile {
    /// goalseek's recording: Foxglove JSON messages with the exact scans, replayable.
    #[default]
    Foxglove,
    /// ROS 2 messages (CDR) that `ros2 bag`, rosbags and Foxglove open: scans, poses, `/tf`
    /// and the map at the end.
    Ros2,
}

/// An MCAP recording of scans, poses, the settings and legs of a run, and its map, in one of
/// the [`RecordProfile`]s.
pub enum Recorder {
    /// [`RecordProfile::Foxglove`].
    Foxglove(McapRecorder),
    /// [`RecordProfile::Ros2`].
    Ros2(Ros2Recorder),
}

impl Recorder {
    /// Starts a goalseek (Foxglove) recording to `path`; `geometry` is the one of
    /// [`Recorder::write`].
    pub fn create(path: &Path, geometry: &ScanGeometry) -> Result<Recorder, LogError> {
        Self::create_profile(path, geometry, RecordProfile::Foxglove)
    }

    /// Starts a recording to `path` in `profile`; `geometry` is the one of [`Recorder::write`].
    pub fn create_profile(
        path: &Path,
        geometry: &ScanGeometry,
        profile: RecordProfile,
    ) -> Result<Recorder, LogError> {
        Ok(match profile {
            RecordProfile::Foxglove => {
                Recorder::Foxglove(McapRecorder::create(path)?.with_geometry(geometry))
            }
            RecordProfile::Ros2 => {
                Recorder::Ros2(Ros2Recorder::create(path)?.with_geometry(geometry))
            }
        })
    }

    /// Sets the sensor's scan period, seconds, for the ROS 2 scans' `scan_time` and
    /// `time_increment` (goalseek's recording keeps the stamps only).
    pub fn with_scan_period(self, scan_period_s: Option<f64>) -> Self {
        match (self, scan_period_s) {
            (Recorder::Ros2(r), Some(t)) => Recorder::Ros2(r.with_scan_period(t)),
            (r, _) => r,
        }
    }

    /// Records a scan without poses.
    pub fn write(&mut self, scan: &Scan) -> Result<(), LogError> {
        match self {
            Recorder::Foxglove(r) => r.write(scan),
            Recorder::Ros2(r) => r.write(scan),
        }
    }

    /// Records one scan with its geometry and, where known, the true and estimated poses.
    pub fn record_scan(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        true_pose: Option<Pose2>,
        est_pose: Option<Pose2>,
    ) -> Result<(), LogError> {
        match self {
            Recorder::Foxglove(r) => r.record_scan(geometry, scan, true_pose, est_pose),
            Recorder::Ros2(r) => r.record_scan(geometry, scan, true_pose, est_pose),
        }
    }

    /// Writes an MCAP metadata record (e.g. [`scan_log::RUN_METADATA`]).
    pub fn write_metadata(
        &mut self,
        name: &str,
        values: &BTreeMap<String, String>,
    ) -> Result<(), LogError> {
        match self {
            Recorder::Foxglove(r) => r.write_metadata(name, values),
            Recorder::Ros2(r) => r.write_metadata(name, values),
        }
    }

    /// Writes the legs of a finished run ([`scan_log::LEGS_METADATA`]).
    pub fn write_legs(&mut self, log: &RunLog, reason: &str) -> Result<(), LogError> {
        let values = scan_log::legs_metadata(&log.leg_summaries(), reason);
        self.write_metadata(scan_log::LEGS_METADATA, &values)
    }

    /// Records the run's map on `/map` (ROS 2 profile; goalseek's recording has no map). An
    /// empty map is left out.
    pub fn write_map(&mut self, grid: &OccupancyGrid) -> Result<(), LogError> {
        match self {
            Recorder::Foxglove(_) => Ok(()),
            Recorder::Ros2(r) => match ros2_map(grid) {
                Some(map) => r.write_map(&map),
                None => Ok(()),
            },
        }
    }

    /// Closes the file and moves it to its final name; returns the number of scans.
    pub fn finish(self) -> Result<u64, LogError> {
        match self {
            Recorder::Foxglove(r) => r.finish(),
            Recorder::Ros2(r) => r.finish(),
        }
    }
}

/// The grid as ROS map_server publishes its `map.yaml` (`mode: trinary`): occupied 100, free 0,
/// unknown -1, rows from the lowest y; `None` for an empty grid.
pub fn ros2_map(grid: &OccupancyGrid) -> Option<Ros2Map> {
    if grid.width() == 0 || grid.height() == 0 {
        return None;
    }
    let mut cells = Vec::with_capacity(grid.width() * grid.height());
    for row in 0..grid.height() {
        for col in 0..grid.width() {
            cells.push(match grid.cell_state(col, row) {
                CellState::Occupied => 100,
                CellState::Free => 0,
                CellState::Unknown => -1,
            });
        }
    }
    let origin = grid.origin();
    Some(Ros2Map {
        resolution_m: grid.resolution_m(),
        width: u32::try_from(grid.width()).ok()?,
        height: u32::try_from(grid.height()).ok()?,
        origin_m: (origin.x_m(), origin.y_m()),
        cells,
    })
}

/// Opens a log (CARMEN, BreezySLAM, goalseek MCAP), with an optional sensor preset name
/// (`paper`, `urg-04lx`, `utm-30lx`, `ust-10lx`) overriding its geometry (see [`scan_log::open_log`]).
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
    replay_loop_live(path, config, (start, goal), None)
}

/// [`replay_loop`] showing the scans, the loop's estimates, the recorded true poses and the
/// legs on `live`.
pub fn replay_loop_live(
    path: &Path,
    config: &Params,
    (start, goal): (Pose2, WorldPoint),
    live: Option<&mut crate::live::LiveView>,
) -> anyhow::Result<LoopReplay> {
    let source = open_log(path, None)?;
    let (mut laser, truth) = RecordedLaser::new(source);
    let geometry = *scan_types::LaserSource::geometry(&laser);
    let mut base = LoggingBase::new(NoMotion);
    let live = live.map(std::cell::RefCell::new);
    let mut hook = |scan: &Scan, estimate: &Pose2| {
        if let Some(v) = &live {
            v.borrow_mut()
                .scan(&geometry, scan, Some(*estimate), truth.pose());
        }
    };
    let mut legs = |leg: &navigator::Leg| {
        if let Some(v) = &live {
            v.borrow_mut().leg(leg);
        }
    };
    let observed = live.is_some();
    let run = run_loop_legs(
        &mut laser,
        &mut base,
        config,
        (start, goal),
        Some(&truth),
        observed.then_some(&mut hook as crate::runloop::ScanPoseHook),
        observed.then_some(&mut legs as crate::runloop::LegHook),
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
