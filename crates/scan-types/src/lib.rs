//! The language every goalseek crate speaks: scan geometry, scans, poses, frames,
//! the two traits that let the real Hokuyo and the simulator be swapped, and the simulator's
//! truth as a third ([`GroundTruth`]), for evaluation.
//!
//! Conventions (see `docs/architecture.md`): metres and radians, units in names,
//! world frame x right / y up, angles counter-clockwise positive and normalised to
//! (-pi, pi]. A scan's ray `i` has bearing `first_bearing_rad + i * increment_rad`
//! relative to the robot's heading; the laser sits at the robot centre.
//!
//! ```
//! use scan_types::{Pose2, ScanGeometry};
//! let geometry = ScanGeometry::paper();
//! assert_eq!(geometry.ray_count, 685);
//! // The central ray of the paper's sensor points straight ahead.
//! assert!(geometry.bearing_rad(342).abs() < 1e-12);
//! // Ray 342 at 2 m, seen from a robot at (1, 1) heading +90 deg, lands at (1, 3).
//! let robot = Pose2::new(1.0, 1.0, std::f64::consts::FRAC_PI_2);
//! let p = robot.transform_point(geometry.robot_point(342, 2.0));
//! assert!((p.x_m() - 1.0).abs() < 1e-12 && (p.y_m() - 3.0).abs() < 1e-12);
//! ```

mod angle;
mod error;
mod fs;
mod geometry;
mod mapfile;
mod motion;
mod num;
mod parse;
mod pose;
mod scan;
mod source;
#[cfg(feature = "testkit")]
pub mod testkit;
mod truth;
mod wait;

pub use angle::{angle_diff_rad, normalize_angle_rad};
pub use error::ScanTypesError;
pub use fs::write_atomic;
pub use geometry::ScanGeometry;
pub use mapfile::{MAP_FREE_THRESH, MAP_OCCUPIED_THRESH, format_decimal};
pub use motion::MotionBase;
pub use num::{floor_i32, floor_i64};
pub use parse::{parse_point, parse_pose_deg, parse_size};
pub use pose::{Pose2, RobotPoint, WorldPoint};
pub use scan::{RayStatus, Scan};
pub use source::LaserSource;
pub use truth::GroundTruth;
pub use wait::sleep_unless;

/// Re-export of the nalgebra version the types are built on.
pub use nalgebra;
