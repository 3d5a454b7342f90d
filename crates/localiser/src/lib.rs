//! Localisation without odometry: the triangles OBC and OAB give point B, the scan measures
//! the rotation, and localised scans build a point map and an occupancy grid.
//!
//! One leg of the method (see `docs/localiser.md`): at pose O the robot selects a landmark at
//! range rho and bearing phi; [`triangle`] gives OB = rho cos(phi), CB = rho sin(phi) and B in
//! the world frame; while driving, [`check_arrival`] decides from the tracked landmark when
//! the robot has reached B (side ray, or the Fig. 6 fallback [`travelled_from_fallback`]).
//! After each rotation in place the heading comes from [`measure_rotation`]
//! ([`HeadingRule::ScanMeasured`], default) or the command ([`HeadingRule::Commanded`], the
//! paper). [`PointMap`] and [`OccupancyGrid`] map the scans taken at localised poses.
//!
//! ```
//! use localiser::{triangle, Side};
//! use scan_types::Pose2;
//! // The paper's first leg: from O = (-3.92, -4.26) facing the target (4, 4), the landmark
//! // at (-2.38, -2.06) gives B = (-2.09, -2.34) on the left.
//! let theta = (4.0f64 + 4.26).atan2(4.0 + 3.92);
//! let o = Pose2::new(-3.92, -4.26, theta);
//! let (dx, dy) = (-2.38f64 + 3.92, -2.06f64 + 4.26);
//! let t = triangle(&o, dx.hypot(dy), dy.atan2(dx) - theta);
//! assert_eq!(t.side, Side::Left);
//! assert!((t.point_b.x_m() + 2.09).abs() < 0.02 && (t.point_b.y_m() + 2.34).abs() < 0.02);
//! ```

mod error;
mod grid;
mod io;
mod mapping;
mod pointmap;
mod rectilinear;
mod rotation;
mod scanmatch;
mod triangle;

pub use error::LocaliserError;
pub use grid::{CellState, GridParams, MapServerFiles, OccupancyGrid, pixel};
pub use io::write_atomic;
pub use mapping::{MapStats, build_map};
pub use pointmap::{MapScan, PointMap};
pub use rectilinear::{AxesParams, WallAxes, wall_axes, wrap_quarter_rad};
pub use rotation::{
    HeadingRule, RotationEstimate, RotationParams, heading_after_rotation, measure_rotation,
    measure_rotation_with,
};
pub use scanmatch::{MatchParams, MatchTarget, ScanMatch};
pub use triangle::{
    Arrival, ArrivalHow, ArrivalParams, ArrivalRule, Side, Triangle, check_arrival,
    travelled_from_fallback, triangle,
};
