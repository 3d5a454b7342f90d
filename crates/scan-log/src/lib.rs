//! Recorded laser data: CARMEN, BreezySLAM and goalseek MCAP logs, ROS 2 bags (MCAP or
//! SQLite, `sensor_msgs/msg/LaserScan`) and Foxglove MCAP files (`foxglove.LaserScan`,
//! protobuf or JSON) read as a [`LaserSource`](scan_types::LaserSource), and MCAP recording
//! with the Foxglove `LaserScan` and `PoseInFrame` schemas.
//!
//! - [`LogReader`]: every record of a log as `Result<LogRecord, LogError>`, so a malformed
//!   line is reported (file, line, byte offset) and the rest of the log still reads.
//! - [`LogSource`]: the same log as a `LaserSource` that skips and counts bad records and
//!   exposes the recorded pose of the last scan ([`LogSource::pose`]).
//! - [`McapRecorder`]: writes scans and poses to an MCAP file that Foxglove opens as it is,
//!   atomically (temp file + rename); [`read_mcap`] reads it back bit for bit.
//! - [`Ros2Recorder`]: writes scans, poses, transforms and the map as ROS 2 messages (CDR,
//!   MCAP profile `ros2`) that ROS 2 tools open, atomically too.
//! - [`open_log`], [`LoopingLog`], [`RecordedLaser`]: a log played back as a laser, with a
//!   geometry override, looping at its end, or with its recorded true poses.
//! - [`write_scan_csv`], [`read_scan_csv`], [`scan_json`], [`record_json`]: one scan as the CSV
//!   or JSON of `robot-app scan` and `robot-app replay`.
//! - [`RunSettings`], [`LegSummary`]: the metadata of a recorded simulated run, its settings
//!   and the legs it drove, for a replay through the loop.
//! - [`RunLog`], [`LegRecord`], [`write_trajectory`], [`trajectory_csv`], [`tum`]: the leg ends
//!   of a run as `trajectory.csv` and TUM trajectories, with their errors against truth.
//!
//! ```
//! use scan_log::{LogOptions, LogSource};
//! use scan_types::LaserSource;
//! let dir = tempfile::tempdir().unwrap();
//! let path = dir.path().join("tiny.log");
//! std::fs::write(&path, "ODOM 0 0 0 0 0 0 0.1 h 0.1\nFLASER 3 1.0 2.0 99 0.5 0.0 0.0 0 0 0 7.5 h 7.5\n").unwrap();
//! let mut src = LogSource::open(&path, &LogOptions::default()).unwrap();
//! assert_eq!(src.geometry().ray_count, 3);
//! let scan = src.next_scan().unwrap();
//! assert_eq!(scan.ranges_m[..2], [1.0, 2.0]);
//! assert!(scan.is_max_range(2));
//! assert_eq!(src.pose().unwrap().x_m, 0.5);
//! assert!(src.next_scan().unwrap_err().is_end_of_log());
//! ```

mod bag;
mod breezy;
mod carmen;
mod csv;
mod error;
mod foreign;
mod mcap_io;
mod playback;
mod record;
mod ros2_writer;
mod run_log;
mod run_meta;
mod source;
mod text;
mod topics;

pub use bag::{BAG_METADATA, SQLITE_MAGIC, read_bag};
pub use breezy::{
    BREEZY_HEADER_FIELDS, BREEZY_RAY_COUNT, URG_DMIN_MM, breezy_geometry, classify_mm,
};
pub use carmen::{CARMEN_DEFAULT_MAX_RANGE_M, flaser_geometry};
pub use csv::{read_scan_csv, record_json, scan_json, write_scan_csv};
pub use error::LogError;
pub use foreign::{
    FOXGLOVE_LASER_SCAN, INVALID_ABOVE_MAX, INVALID_BELOW_MIN, INVALID_NAN, ROS2_LASER_SCAN,
};
pub use mcap_io::{
    EST_POSE_TOPIC, LASER_FRAME, MAP_FRAME, MAX_MCAP_RECORD_BYTES, McapRecorder, MetadataRecord,
    SCAN_TOPIC, STATUS_HIT, STATUS_MAX_RANGE, TRUE_POSE_TOPIC, parse_mcap, partial_path, read_mcap,
    read_mcap_metadata, read_mcap_topic, recording_schemas,
};
pub use playback::{
    GeometryOverride, LoopingLog, RecordedLaser, RecordedTruth, open_log, open_log_topic,
};
pub use record::LogRecord;
pub use ros2_writer::{
    ROS2_BASE_FRAME, ROS2_LASER_FRAME, ROS2_MAP_FRAME, ROS2_MAP_TOPIC, ROS2_OCCUPANCY_GRID,
    ROS2_POSE_ESTIMATE_TOPIC, ROS2_POSE_STAMPED, ROS2_POSE_TRUTH_TOPIC, ROS2_TF_MESSAGE,
    ROS2_TF_STATIC_TOPIC, ROS2_TF_TOPIC, Ros2Map, Ros2Recorder, ros2_schema,
};
pub use run_log::{LegRecord, RunLog, trajectory_csv, tum, write_trajectory};
pub use run_meta::{
    LEGS_METADATA, LegSummary, RUN_METADATA, RunSettings, leg_difference, legs_metadata,
    read_recorded_legs,
};
pub use source::{LogFormat, LogOptions, LogReader, LogSource, open_text};
pub use text::{TextFormat, TextLog};
pub use topics::SUPPORTED_TOPICS;
