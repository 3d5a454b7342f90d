//! One scan of a log with what the log says about where it was taken.

use scan_types::{Pose2, Scan, ScanGeometry};

/// One scan read from a log, with the poses the log records for it.
#[derive(Debug, Clone, PartialEq)]
pub struct LogRecord {
    /// Where the record is: line number (text logs, 1-based) or scan sequence number (MCAP).
    pub line: usize,
    /// The scan.
    pub scan: Scan,
    /// The geometry of this scan (from the log itself or from the preset in use).
    pub geometry: ScanGeometry,
    /// The log's best pose of the laser: CARMEN's (corrected) pose, or the estimated pose of a
    /// goalseek recording.
    pub pose: Option<Pose2>,
    /// The simulator's true pose (goalseek recordings of simulated runs).
    pub true_pose: Option<Pose2>,
    /// Raw odometry pose (CARMEN `FLASER`).
    pub odom_pose: Option<Pose2>,
    /// Left and right wheel encoder ticks (BreezySLAM logs).
    pub wheel_ticks: Option<[i64; 2]>,
}

impl LogRecord {
    /// A record of a bare scan without poses.
    pub fn new(line: usize, geometry: ScanGeometry, scan: Scan) -> Self {
        Self {
            line,
            scan,
            geometry,
            pose: None,
            true_pose: None,
            odom_pose: None,
            wheel_ticks: None,
        }
    }
}
