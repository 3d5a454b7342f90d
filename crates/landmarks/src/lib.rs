//! Landmarks in raw scans: the paper's max-range jumps, occlusion edges and corners;
//! stability rules, selection (eq. 6) and tracking while the robot drives.
//!
//! A **landmark** is a point the laser can find again from another position. The paper
//! defines it on the max-range set A: ray `x` is in A and ray `x + n` or `x - n` is not (it
//! hits). The landmark point is the hit of the edge ray next to the open space. goalseek adds
//! occlusion edges (a range jump between two hits; the nearer, occluding edge is the landmark)
//! and corners (two straight arms meeting at an angle), and flags what moves with the robot:
//! hits within a few centimetres of the maximum range, and surfaces that simply continue past
//! the edge (a wall running out of range or seen at a grazing angle). An edge on a post or
//! pillar can be fitted to its round object's centre ([`round_object`], [`round_centre`]),
//! which stays put while the edge hit slides round it.
//!
//! Every rule is a field of [`DetectParams`]; [`DetectParams::paper`] is the paper as
//! written, [`DetectParams::default`] is goalseek's choice. See `docs/landmarks.md`.
//!
//! ```
//! use landmarks::{detect, select_nearest, DetectParams, LandmarkKind};
//! use scan_types::{Scan, ScanGeometry};
//!
//! // Five rays at -2..2 deg: a wall 2 m ahead on the right, open space on the left.
//! let g = ScanGeometry::centred(5, 4f64.to_radians(), 0.0, 4.0).unwrap();
//! let scan = Scan::from_ranges(&g, &[2.0, 2.0, 2.0, 4.0, 4.0], 0.0);
//! let found = detect(&g, &scan, &DetectParams::paper());
//! assert_eq!(found.len(), 1);
//! assert_eq!(found[0].index, 2); // the last hit before the open space
//! assert_eq!(found[0].kind, LandmarkKind::MaxRangeJump);
//! let chosen = select_nearest(&found, std::f64::consts::FRAC_PI_2).unwrap();
//! assert!((chosen.robot_point().x_m() - 2.0).abs() < 1e-12);
//! ```

mod detect;
mod error;
mod round;
mod select;
mod stats;
mod track;

pub use detect::{DetectParams, Landmark, LandmarkKind, OpenSide, detect, detect_near};
pub use error::LandmarksError;
pub use round::{Circle, RoundParams, round_centre, round_object};
pub use select::{SelectParams, select, select_nearest};
pub use stats::{LandmarkCounts, count_log, count_scan};
pub use track::{TrackParams, TrackUpdate, Tracker};
