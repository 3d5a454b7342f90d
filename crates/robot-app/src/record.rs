//! MCAP recording for `robot-app scan --record FILE` and `robot-app sim --record FILE`, and
//! opening recordings and other logs for replay.
//!
//! The file is written as `FILE.partial` and renamed to `FILE` when the recording finishes
//! (or when the [`Recorder`] is dropped); see `docs/logs.md`.

use std::path::{Path, PathBuf};

use anyhow::Context;
use scan_log::{LogOptions, LogSource, McapRecorder};
use scan_types::{LaserSource, Pose2, Scan, ScanGeometry};

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

/// The `--record FILE` sink of `robot-app scan`: records every scan printed.
pub fn scan_sink(path: &Path) -> anyhow::Result<crate::cmd::scan::ScanSink<'static>> {
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

/// Opens a log (CARMEN, BreezySLAM, goalseek MCAP) as a `LaserSource`, with an optional
/// sensor preset name (`paper`, `urg-04lx`, `utm-30lx`) overriding its geometry.
///
/// The preset gives the first bearing, the increment and the range limits; when the log's
/// scans have another ray count (BreezySLAM's URG-04LX logs have 683 rays, the preset's
/// steps 44..725 are 682), the log's count is kept and a warning says so.
pub fn open_log(path: &Path, sensor: Option<&str>) -> anyhow::Result<LogSource> {
    let opened = LogSource::open(path, &LogOptions::default())
        .with_context(|| format!("opening the log {}", path.display()))?;
    let Some(name) = sensor else {
        return Ok(opened);
    };
    let p = name
        .parse::<sim_laser::SensorPreset>()
        .map_err(|e| anyhow::anyhow!("--sensor {name}: {e}"))?
        .geometry();
    let n = opened.geometry().ray_count;
    if n != p.ray_count {
        tracing::warn!(
            "--sensor {name} has {} rays, the scans of {} have {n}: keeping {n} rays at the preset's spacing",
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
    let options = LogOptions {
        geometry,
        ..LogOptions::default()
    };
    LogSource::open(path, &options).with_context(|| format!("opening the log {}", path.display()))
}

/// A log source that starts again from the first scan at the end of the log (for the
/// emulator, whose clients expect a sensor that never runs out).
pub struct LoopingLog {
    path: PathBuf,
    sensor: Option<String>,
    source: LogSource,
    laps: usize,
}

impl LoopingLog {
    /// Opens `path` (see [`open_log`]).
    pub fn open(path: &Path, sensor: Option<&str>) -> anyhow::Result<LoopingLog> {
        Ok(LoopingLog {
            path: path.to_path_buf(),
            sensor: sensor.map(str::to_string),
            source: open_log(path, sensor)?,
            laps: 0,
        })
    }

    /// Times the log has been started again.
    pub fn laps(&self) -> usize {
        self.laps
    }
}

impl scan_types::LaserSource for LoopingLog {
    type Error = scan_log::LogError;

    fn geometry(&self) -> &ScanGeometry {
        self.source.geometry()
    }

    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        match self.source.next_scan() {
            Err(e) if e.is_end_of_log() && self.source.scans_read() > 0 => {
                let options = LogOptions {
                    geometry: Some(*self.source.geometry()),
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
