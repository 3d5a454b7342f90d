//! What a run records: one [`Leg`] per leg end, and the [`Outcome`] when it finishes.

use localiser::OccupancyGrid;
use scan_types::{Pose2, WorldPoint};
use serde::{Deserialize, Serialize};

/// Why a run ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Reason {
    /// The estimate reached the target within tolerance.
    Reached,
    /// No way toward the target was found after the bounded number of tries.
    Unreachable,
    /// The leg limit was hit first.
    LegLimit,
    /// The robot touched an obstacle (reported by the caller, e.g. a simulator).
    Collision,
    /// The laser failed or was lost for good (reported by the caller).
    SensorFailure,
    /// The base reported an error (reported by the caller).
    BaseFailure,
    /// The scans show that the robot does not move when told to drive.
    BaseStalled,
    /// The operator stopped the run (Ctrl-C, SIGTERM; reported by the caller).
    Interrupted,
    /// The estimate reached the target while its position uncertainty exceeded
    /// `[navigator] arrival_max_sigma_m`: the arrival is flagged, not claimed.
    UncertainArrival,
    /// The estimate reached the target but the robot is not there: set by an evaluator that
    /// knows the truth (a simulator); the navigator never ends with it.
    FalseArrival,
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Reason::Reached => "reached",
            Reason::Unreachable => "unreachable",
            Reason::LegLimit => "leg_limit",
            Reason::Collision => "collision",
            Reason::SensorFailure => "sensor_failure",
            Reason::BaseFailure => "base_failure",
            Reason::BaseStalled => "base_stalled",
            Reason::Interrupted => "interrupted",
            Reason::FalseArrival => "false_arrival",
            Reason::UncertainArrival => "uncertain_arrival",
        })
    }
}

/// The estimate at the end of a leg (leg 0 is the start) and what the leg localised on.
#[derive(Debug, Clone, PartialEq)]
pub struct Leg {
    /// Leg number (0 = start).
    pub leg: usize,
    /// Time of the scan that ended the leg (the first scan for leg 0), seconds: the scan's
    /// `host_time_s` (the simulated clock in the simulator, the log's clock in a replay).
    pub time_s: f64,
    /// The robot's estimate.
    pub estimate: Pose2,
    /// The landmark the leg localised on, world frame by the estimate.
    pub landmark: Option<WorldPoint>,
    /// Point B of the leg (where the side ray should see the landmark).
    pub point_b: Option<WorldPoint>,
    /// The hits of the scan taken at the end of the leg, world frame by the estimate.
    pub scan_points: Vec<WorldPoint>,
    /// The estimate's position uncertainty (one standard deviation, metres) by the
    /// navigator's own error model: it grows with every turn and drive, less where the laser
    /// measured them ([`crate::LocaliserParams`]'s `*_sigma_*` keys).
    pub position_sigma_m: f64,
    /// The estimate's heading uncertainty (one standard deviation), degrees.
    pub heading_sigma_deg: f64,
}

/// How a run ended and what it recorded.
#[derive(Debug, Clone)]
pub struct Outcome {
    /// Why the run ended.
    pub reason: Reason,
    /// One line on how it ended.
    pub note: String,
    /// Every leg end, starting with the start.
    pub legs: Vec<Leg>,
    /// Legs driven.
    pub legs_driven: usize,
    /// Scans taken.
    pub scans: usize,
    /// Sum of the forward moves commanded and completed, metres.
    pub path_length_m: f64,
    /// The final estimate.
    pub estimate: Pose2,
    /// The occupancy grid built from the localised scans.
    pub grid: OccupancyGrid,
    /// The first leg's landmark and point B, world frame.
    pub first_leg: Option<(WorldPoint, WorldPoint)>,
    /// Every narrow passage a leg was planned through (graded clearance; legs that only
    /// approach one are not listed).
    pub narrow_passages: Vec<NarrowPassage>,
}

/// A leg planned through a passage narrower than the full margin allows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NarrowPassage {
    /// The leg's number (1 = the first leg driven).
    pub leg: usize,
    /// Where the robot's centre passes closest to an obstacle, world frame by the estimate.
    pub at: WorldPoint,
    /// Distance from there to the nearest hit of the planning scan, metres.
    pub clearance_m: f64,
    /// The passage's narrowest width across the leg on the planning scan, metres.
    pub width_m: f64,
}
