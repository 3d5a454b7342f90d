//! Playing a log back as a laser: a geometry override, a log that loops at its end, and a
//! recording whose true poses stand in for a simulator's.

use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::rc::Rc;

use scan_types::{LaserSource, Pose2, Scan, ScanGeometry};

use crate::{LogError, LogOptions, LogSource};

/// A geometry (e.g. a sensor preset's) that replaces a log's own, and its name for messages.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometryOverride {
    /// How messages name the override (e.g. `--sensor urg-04lx`).
    pub name: String,
    /// The bearings and range limits to use; the log's ray count wins over `ray_count`.
    pub geometry: ScanGeometry,
}

/// Opens a log of any format as a [`LogSource`], optionally with another geometry.
pub fn open_log(path: &Path, geometry: Option<&GeometryOverride>) -> Result<LogSource, LogError> {
    open_log_topic(path, geometry, None)
}

/// Opens a log as [`open_log`] does, reading the laser topic `topic` of a bag or MCAP file
/// (`None`: its only one).
pub fn open_log_topic(
    path: &Path,
    geometry: Option<&GeometryOverride>,
    topic: Option<&str>,
) -> Result<LogSource, LogError> {
    let base = LogOptions {
        topic: topic.map(str::to_string),
        ..LogOptions::default()
    };
    let opened = LogSource::open(path, &base)?;
    let Some(o) = geometry else {
        return Ok(opened);
    };
    // The override gives the first bearing, the increment and the range limits; when the
    // log's scans have another ray count (BreezySLAM's URG-04LX logs have 683 rays, the
    // preset's steps 44..725 are 682), the log's count is kept and a warning says so.
    let p = &o.geometry;
    let n = opened.geometry().ray_count;
    if n != p.ray_count {
        tracing::warn!(
            "{} has {} rays, the scans of {} have {n}: keeping {n} rays at the preset's spacing",
            o.name,
            p.ray_count,
            path.display()
        );
    }
    let geometry = Some(ScanGeometry::new(
        p.first_bearing_rad,
        p.increment_rad,
        n,
        p.min_range_m,
        p.max_range_m,
    )?);
    let options = LogOptions { geometry, ..base };
    LogSource::open(path, &options)
}

// For the emulator, whose clients expect a sensor that never runs out.
/// A log source that starts again from the first scan at the end of the log.
pub struct LoopingLog {
    path: PathBuf,
    sensor: Option<String>,
    topic: Option<String>,
    source: LogSource,
    laps: usize,
}

impl LoopingLog {
    /// Opens `path` (see [`open_log`]).
    pub fn open(path: &Path, geometry: Option<&GeometryOverride>) -> Result<LoopingLog, LogError> {
        Self::open_topic(path, geometry, None)
    }

    /// Opens the laser topic `topic` of `path` (see [`open_log_topic`]).
    pub fn open_topic(
        path: &Path,
        geometry: Option<&GeometryOverride>,
        topic: Option<&str>,
    ) -> Result<LoopingLog, LogError> {
        Ok(LoopingLog {
            path: path.to_path_buf(),
            sensor: geometry.map(|o| o.name.clone()),
            topic: topic.map(str::to_string),
            source: open_log_topic(path, geometry, topic)?,
            laps: 0,
        })
    }

    /// Times the log has been started again.
    pub fn laps(&self) -> usize {
        self.laps
    }
}

impl LaserSource for LoopingLog {
    type Error = LogError;

    fn geometry(&self) -> &ScanGeometry {
        self.source.geometry()
    }

    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        match self.source.next_scan() {
            Err(e) if e.is_end_of_log() && self.source.scans_read() > 0 => {
                let options = LogOptions {
                    geometry: Some(*self.source.geometry()),
                    topic: self.topic.clone(),
                    ..LogOptions::default()
                };
                self.source = LogSource::open(&self.path, &options)?;
                self.laps += 1;
                tracing::info!(
                    "{}: end of log, starting again (lap {}, sensor {:?})",
                    self.path.display(),
                    self.laps + 1,
                    self.sensor
                );
                self.source.next_scan()
            }
            r => r,
        }
    }
}

/// A recording as a laser that shares the true pose of its last scan with a [`RecordedTruth`].
pub struct RecordedLaser {
    source: LogSource,
    truth: Rc<Cell<Option<Pose2>>>,
}

/// The recorded true pose of the last scan a [`RecordedLaser`] gave.
pub struct RecordedTruth(Rc<Cell<Option<Pose2>>>);

impl RecordedLaser {
    /// Wraps a log source.
    pub fn new(source: LogSource) -> (Self, RecordedTruth) {
        let truth = Rc::new(Cell::new(None));
        (
            Self {
                source,
                truth: truth.clone(),
            },
            RecordedTruth(truth),
        )
    }

    /// The log source.
    pub fn source(&self) -> &LogSource {
        &self.source
    }

    /// The log source, to read on past the laser.
    pub fn into_source(self) -> LogSource {
        self.source
    }
}

impl LaserSource for RecordedLaser {
    type Error = LogError;
    fn geometry(&self) -> &ScanGeometry {
        self.source.geometry()
    }
    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        let rec = self.source.next_record()?;
        self.truth.set(rec.true_pose);
        Ok(rec.scan.clone())
    }
}

impl RecordedTruth {
    /// The recorded true pose of the last scan, if it has one.
    pub fn pose(&self) -> Option<Pose2> {
        self.0.get()
    }
}

// The recorded true poses as a simulator's truth (the origin before any); a recording knows
// no collisions.
impl scan_types::GroundTruth for RecordedTruth {
    fn true_pose(&self) -> Pose2 {
        self.pose().unwrap_or_default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::McapRecorder;

    const TWO_SCANS: &str =
        "FLASER 3 1.0 2.0 3.0 0 0 0 0 0 0 1.0 h 1.0\nFLASER 3 1.5 2.5 3.5 0 0 0 0 0 0 2.0 h 2.0\n";

    #[test]
    fn the_override_keeps_the_log_ray_count() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.log");
        std::fs::write(&path, TWO_SCANS).unwrap();
        let o = GeometryOverride {
            name: "test".into(),
            geometry: ScanGeometry::new(-1.0, 0.5, 5, 0.1, 4.0).unwrap(),
        };
        let src = open_log(&path, Some(&o)).unwrap();
        let g = src.geometry();
        assert_eq!(
            (g.ray_count, g.first_bearing_rad, g.max_range_m),
            (3, -1.0, 4.0)
        );
    }

    #[test]
    fn a_looping_log_starts_again() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("two.log");
        std::fs::write(&path, TWO_SCANS).unwrap();
        let mut src = LoopingLog::open(&path, None).unwrap();
        let first: Vec<f64> = (0..5)
            .map(|_| src.next_scan().unwrap().ranges_m[0])
            .collect();
        assert_eq!(first, [1.0, 1.5, 1.0, 1.5, 1.0]);
        assert_eq!(src.laps(), 2);
    }

    #[test]
    fn the_truth_follows_the_recorded_laser() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rec.mcap");
        let g = ScanGeometry::centred(3, 1.0, 0.0, 4.0).unwrap();
        let mut rec = McapRecorder::create(&path).unwrap();
        for k in 0..2 {
            let s = Scan::from_ranges(&g, &[1.0, 2.0, 3.0], f64::from(k));
            let p = Pose2::new(f64::from(k), 0.0, 0.0);
            rec.record_scan(&g, &s, Some(p), None).unwrap();
        }
        rec.finish().unwrap();
        let (mut laser, truth) = RecordedLaser::new(open_log(&path, None).unwrap());
        assert_eq!(truth.pose(), None);
        laser.next_scan().unwrap();
        assert_eq!(truth.pose(), Some(Pose2::new(0.0, 0.0, 0.0)));
        let mut rest = laser.into_source();
        assert_eq!(rest.scans_read(), 1);
        assert!(rest.next_record().is_ok());
        assert!(rest.next_record().unwrap_err().is_end_of_log());
    }
}
