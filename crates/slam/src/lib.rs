//! Laser-only pose tracking and trajectory evaluation.
//!
//! [`FrontEnd`] places each scan against a local submap of recent keyframes: a narrow, then a
//! wide correlative search (branch and bound over a max-pooled likelihood field) around a
//! constant-velocity prediction, refined by the point-to-line ICP of `localiser`. It never
//! reads odometry: the laser alone decides where the robot is. A scan that cannot be placed is
//! reported as [`Placement::Skipped`], never placed silently. [`eval`] measures a trajectory
//! against reference poses; [`LogRun`] runs the front end over a log's scans and reports on
//! the run ([`SlamReport`]).
#![warn(missing_docs)]

mod check;
mod correlative;
mod error;
pub mod eval;
mod frontend;
pub mod graph;
mod grid;
mod log_run;
mod loops;

pub use error::SlamError;
pub use frontend::{FrontEnd, FrontEndParams, Placement, SkipReason};
pub use log_run::{Evaluation, LogRun, Placed, Skip, SlamReport, SlamRun};
pub use loops::{Closure, LoopParams, LoopReport, close_loops};
