//! The goal-seeking loop of goalseek (`docs/method.md`) as a library: a state machine that is
//! fed scans and motion results and answers with the next action.
//!
//! [`Navigator`] never touches a sensor or a base, so any front end can drive it: the
//! blocking [`run`] over a [`scan_types::LaserSource`] and a [`scan_types::MotionBase`], a
//! ROS node, an async task, a replayed log. Its [`Params`] hold every number the loop uses,
//! with the `goalseek` and `paper` presets.
//!
//! ```
//! use navigator::{Action, Navigator, Params};
//! use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};
//!
//! let geometry = ScanGeometry::paper();
//! let start = Pose2::new(0.0, 0.0, 0.0);
//! let goal = WorldPoint::new(0.04, 0.0); // within the final approach's 0.05 m of the start
//! let mut nav = Navigator::new(Params::goalseek(), geometry, start, goal).unwrap();
//! assert_eq!(nav.pending(), Action::Scan);
//! // Nothing in range: every ray is a max-range reading.
//! let scan = Scan::from_ranges(&geometry, &vec![f64::INFINITY; geometry.ray_count], 0.0);
//! assert_eq!(nav.on_scan(&scan), Action::Finish(navigator::Reason::Reached));
//! assert_eq!(nav.into_outcome().legs.len(), 1);
//! ```
#![warn(missing_docs)]

mod clearance;
mod drive;
mod error;
mod explore;
mod machine;
mod outcome;
mod params;
mod revisit;
mod run;

pub use error::NavigatorError;
pub use explore::{Exploration, ExploreEnd, ExploreParams, Frontier, GoalTry, explore, frontiers};
pub use machine::{Action, Navigator, Phase};
pub use outcome::{Leg, NarrowPassage, Outcome, Reason};
pub use params::{
    HeadingRule, LandmarkParams, LocaliserParams, LoopParams, Method, Params, PlanRule,
    PlanningParams, RobotParams, TrackingParams, TravelRule,
};
pub use run::{Monitor, NoMonitor, ScanHook, TruthMonitor, run};

/// Largest start or goal coordinate the navigator accepts, metres (1000 km).
pub const MAX_COORD_M: f64 = 1e6;
