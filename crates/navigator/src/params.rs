//! Every number the loop uses, in one serde-deserialisable tree with two presets.
//!
//! [`Params::goalseek`] is goalseek's default; [`Params::paper`] is the paper as written. The
//! sections and keys are those of a `robot-app --config` file (`docs/method.md` lists them
//! all with both presets' values).

use std::str::FromStr;

use landmarks::{DetectParams, SelectParams, TrackParams};
use scan_types::WorldPoint;
use serde::{Deserialize, Serialize};

use crate::NavigatorError;

/// Which variant of the method to run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// The paper as written: greedy ray choice, commanded heading, the paper's landmark rule.
    Paper,
    /// goalseek's default: map path, scan-measured rotation, stability rules, tight gate.
    #[default]
    Goalseek,
}

impl FromStr for Method {
    type Err = NavigatorError;
    fn from_str(s: &str) -> Result<Self, NavigatorError> {
        match s {
            "paper" => Ok(Method::Paper),
            "goalseek" => Ok(Method::Goalseek),
            other => Err(NavigatorError::UnknownMethod(other.to_string())),
        }
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Paper => "paper",
            Method::Goalseek => "goalseek",
        })
    }
}

/// How the next ray is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PlanRule {
    /// The paper: the safe ray whose clear stretch passes closest to the target.
    Greedy,
    /// goalseek: the safe ray with the shortest path to the target over the robot's own map.
    MapPath,
}

/// Where the heading after a rotation comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum HeadingRule {
    /// The paper: theta += commanded alpha.
    Commanded,
    /// The shift that best aligns the scans before and after the rotation.
    ScanMeasured,
    /// goalseek: the shift, refined by matching the two scans' surfaces (point-to-line ICP).
    ScanMatched,
}

/// Where the distance driven on a leg comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TravelRule {
    /// The paper: the tracked landmark (OB minus its current distance ahead), else the command.
    Landmark,
    /// goalseek: the landmark's figure refined by matching the scan at the leg's end against
    /// the scans at its start (point-to-line ICP), which also measures the sideways drift.
    ScanMatched,
}

/// The robot and the obstacle expansion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotParams {
    /// Robot radius r, metres (the paper: 0.3).
    pub radius_m: f64,
    /// Extra margin added to r when expanding obstacles, metres.
    pub expansion_margin_m: f64,
    /// The margin in a narrow passage: any passage at least 2 (r + this) wide is taken
    /// (graded clearance; off when not below `expansion_margin_m`), metres.
    pub narrow_margin_m: f64,
}

/// Path selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlanningParams {
    /// Ray choice rule.
    pub rule: PlanRule,
    /// Shortest clear stretch a ray needs to count as safe, metres.
    pub min_travel_m: f64,
    /// Longest leg driven without a landmark fix, metres.
    pub max_leg_m: f64,
    /// Cell size of the planner's own obstacle grid (map_path), metres.
    pub grid_resolution_m: f64,
    /// A ray's clearance is the smallest over the rays within this bearing of it, degrees
    /// (the robot's width). 0 = the ray alone (the paper).
    pub width_window_deg: f64,
    /// While the robot turns in place, hits seen earlier from the same spot that have left the
    /// field of view still cut the rays' clearance (the paper: no memory).
    pub remember_turned_away_hits: bool,
    /// While a leg is driven (map_path only), every this much travel the scan's hits join the
    /// planner's map and the rest of the leg is judged on it: a leg that no longer leads toward
    /// the target, or runs into a newly seen obstacle, ends early, metres. 0 = off (the paper;
    /// also what a stored configuration without the key means).
    #[serde(default)]
    pub replan_step_m: f64,
    /// map_path only: a leg end from which the target is in line of sight on the planner's
    /// map is ranked by its straight-line distance (the grid path's 8 directions would aim
    /// up to 22.5 deg off the target). Off (the grid path alone) in a stored configuration
    /// without the key.
    #[serde(default)]
    pub line_of_sight: bool,
    /// map_path with graded clearance: where the map's path runs through the band, the gap it
    /// crosses is measured on the scan and closed when narrower than a narrow leg takes (a
    /// gap no ray passes, which the map's coarse cells may leave open). Off in a stored
    /// configuration without the key.
    #[serde(default)]
    pub measure_path_gaps: bool,
}

/// Landmark detection and selection.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LandmarkParams {
    /// Neighbour offset n of the jump rule (ray x in A, ray x +/- n not in A).
    pub neighbour_n: usize,
    /// Landmarks count only within this bearing of the central ray, degrees (the paper: 90).
    pub max_bearing_deg: f64,
    /// Hits closer than this to the maximum range are not landmarks (range-limit artefacts), metres.
    pub range_limit_margin_m: f64,
    /// ... or than this many of the range gaps between neighbouring hits on a wall 1 m to the
    /// side at the maximum range (r_max^2 times the ray spacing, per metre), when that is more:
    /// a longer-ranged scanner's last hit on a receding wall lies farther inside its limit. 0
    /// (a configuration without the key): the margin alone.
    #[serde(default)]
    pub range_limit_gaps: f64,
    /// Also use occlusion edges (range jumps between two hits).
    pub occlusion_edges: bool,
    /// Also select corners (two straight arms meeting at an angle) as landmarks; the paper
    /// selects only max-range jumps. Tracking re-identifies every kind either way.
    pub corners: bool,
    /// Smallest range jump that makes an occlusion edge, metres.
    pub min_jump_m: f64,
    /// Smallest OB (distance to drive to B) for a landmark to be usable, metres.
    pub min_ob_m: f64,
    /// Smallest |CB| (distance of the landmark from the path), metres.
    pub min_cb_m: f64,
}

/// Tracking the landmark while driving to B.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TrackingParams {
    /// Length of one forward step between scans, metres.
    pub step_m: f64,
    /// Re-identification gate around the predicted landmark point, metres.
    pub gate_m: f64,
    /// Scans in a row the landmark may be missed before it counts as lost.
    pub max_missed_scans: usize,
    /// On a round object, measure the travel on its fitted centre, not on the edge hit that
    /// slides around it (a configuration without the key, made before it: the edge).
    #[serde(default)]
    pub round_centre: bool,
    /// Re-identify nothing within `[landmarks] range_limit_margin_m` of the maximum range,
    /// where a surface's last hit moves with the robot (a configuration without the key: any).
    #[serde(default)]
    pub reject_near_range_limit: bool,
}

/// Localisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LocaliserParams {
    /// Heading update rule.
    pub heading_rule: HeadingRule,
    /// Half-width of the search around the commanded rotation, degrees.
    pub rotation_search_deg: f64,
    /// Travel rule of a leg.
    pub travel_rule: TravelRule,
    /// While driving, a new reference scan for matching every this many metres.
    pub keyframe_m: f64,
    /// Standard deviation of a drive's guessed end (landmark or command) at zero distance,
    /// metres: what scan matching weighs the data against.
    pub match_prior_m: f64,
    /// ... growing by this much per metre driven (the base's drive scale error).
    pub match_prior_per_m: f64,
    /// Standard deviation of the position prior when matching the scans before and after a
    /// turn in place (heading rule scan_matched), metres.
    pub turn_match_prior_m: f64,
    /// First pairing gate of that match, metres.
    pub turn_match_gate_m: f64,
    /// Occupancy grid cell size, metres.
    pub map_resolution_m: f64,
    /// A drive's scan match that turns the robot more than this from the drive's heading is
    /// refused (the base drives straight; such a match paired the wrong points), degrees.
    #[serde(default = "no_drive_turn_gate")]
    pub drive_max_turn_deg: f64,
    /// Standard deviation of a drive's heading change, what a drive's scan match weighs the
    /// data's heading against (the base drives straight), degrees.
    #[serde(default = "loose_drive_turn_prior")]
    pub drive_turn_sigma_deg: f64,
    /// A drive's match that puts the travel at a share of the command (a base that stalled or
    /// slipped) replaces the command only when its data pin the travel this well, metres (one
    /// standard deviation; 0: never).
    #[serde(default = "loose_partial_travel_sigma")]
    pub partial_travel_max_sigma_m: f64,
    /// A turn measured by the ray shift alone (the scan match refused it) counts only within
    /// this many `turn_sigma_deg`, or 5 % of the turn if more, of the command; beyond, the
    /// command stands (0: always counts, as a configuration without the key).
    #[serde(default)]
    pub ray_shift_max_sigmas: f64,
    /// Heading uncertainty a turn chunk measured by the ray shift alone adds, degrees (a
    /// configuration without the key: 0.2, a match's).
    #[serde(default = "default_measured_turn_sigma_deg")]
    pub ray_shift_alone_sigma_deg: f64,
    /// Online SLAM: every turn chunk's scan, every `slam_step_m` of a drive and every leg's
    /// last scan are placed against a submap of recent keyframes by the slam crate's
    /// correlative scan-to-submap matching, searched around the pose the rules above give;
    /// the placed pose becomes the estimate (a scan it cannot place keeps the rules' pose).
    #[serde(default)]
    pub slam: bool,
    /// Half-width of the SLAM search around that pose, metres.
    #[serde(default = "default_slam_window_m")]
    pub slam_window_m: f64,
    /// Half-width of the SLAM search around its heading, degrees.
    #[serde(default = "default_slam_window_deg")]
    pub slam_window_deg: f64,
    /// While driving, a scan is placed by SLAM every this many metres commanded.
    #[serde(default = "default_slam_step_m")]
    pub slam_step_m: f64,
    /// A placed scan becomes a keyframe of the SLAM submap this far from the last one,
    /// metres (or turned 10 deg from it).
    #[serde(default = "default_slam_keyframe_m")]
    pub slam_keyframe_m: f64,
    /// Keyframes in the SLAM submap (the oldest leaves when it is full).
    #[serde(default = "default_slam_keyframes")]
    pub slam_keyframes: usize,
    /// Fewest hits (one per 5 cm cell) for SLAM to place a scan.
    #[serde(default = "default_slam_min_points")]
    pub slam_min_points: usize,
    /// Least correlative score (0..1) of a SLAM placement.
    #[serde(default = "default_slam_min_quality")]
    pub slam_min_quality: f64,
    /// Heading uncertainty a turn chunk adds when no scan measured it (the commands alone),
    /// degrees (one standard deviation).
    #[serde(default = "default_turn_sigma_deg")]
    pub turn_sigma_deg: f64,
    /// ... and when a scan match or SLAM measured it (or the ray shift, under heading rule
    /// `scan_measured`), degrees.
    #[serde(default = "default_measured_turn_sigma_deg")]
    pub measured_turn_sigma_deg: f64,
    /// Position uncertainty a drive adds per metre when no scan measured it (a share of the
    /// distance; a heading uncertainty adds its own lateral error on top).
    #[serde(default = "default_drive_sigma_share")]
    pub drive_sigma_share: f64,
    /// ... and when a scan measured it.
    #[serde(default = "default_measured_drive_sigma_share")]
    pub measured_drive_sigma_share: f64,
    /// Gaussian fall-off of the SLAM submap's likelihood field around each point, metres.
    #[serde(default = "default_slam_smoothing_m")]
    pub slam_smoothing_m: f64,
    /// SLAM's placement is combined with the rules' prediction, each weighed by its
    /// information, so that the prediction holds what the scans leave free (along a
    /// corridor). Off in a stored configuration without the key.
    #[serde(default)]
    pub slam_fuse_prediction: bool,
    /// SLAM's refinement takes a hit's neighbours for a line when their variance across it
    /// is at most this share of that along it (0..1): stricter than the 0.1 of the offline
    /// `slam`, so that lines fitted around corners and posts do not pull each placement
    /// along the motion. 0.1 in a stored configuration without the key.
    #[serde(default = "default_slam_line_scatter")]
    pub slam_line_scatter: f64,
    /// A leg whose landmark measured a travel more than 0.2 m and 30 % away from the commands
    /// keeps it only when the scan match pins that travel to this, metres; else the match
    /// starts from the commands (a feature that moves with the robot, where a wall leaves the
    /// range, looks like a stall). 0: the landmark's travel stands, as in a stored
    /// configuration without the key.
    #[serde(default)]
    pub stray_landmark_max_sigma_m: f64,
    /// Cell of the SLAM submap's likelihood field, metres.
    #[serde(default = "default_slam_resolution_m")]
    pub slam_resolution_m: f64,
    /// Only a placement that ICP refined becomes the estimate (the correlative pose alone is
    /// good to about a cell and an angular step).
    #[serde(default = "default_true")]
    pub slam_refined_only: bool,
    /// A refined placement becomes the estimate only when its data pin the position this
    /// well in the worst direction, metres (one standard deviation; a lone wall or post
    /// lets the scan slide).
    #[serde(default = "default_slam_max_sigma_m")]
    pub slam_max_sigma_m: f64,
    /// Revisits: at each leg's end the scan is also matched against the leg-end scans of
    /// earlier legs taken near the estimate, and a good match pulls the estimate back to
    /// them (a place seen again corrects the drift since). Absent from a stored configuration,
    /// it is off (as the runs recorded before it).
    #[serde(default)]
    pub revisit: bool,
    /// Earlier leg ends within this distance of the estimate are matched, metres.
    #[serde(default = "default_revisit_radius_m")]
    pub revisit_radius_m: f64,
    /// Only leg ends at least this many legs old are matched (the recent ones are what the
    /// estimate was chained from).
    #[serde(default = "default_revisit_min_age_legs")]
    pub revisit_min_age_legs: usize,
    /// Most earlier leg ends matched at once (the nearest).
    #[serde(default = "default_revisit_keyframes")]
    pub revisit_keyframes: usize,
    /// A revisit match is taken only when its data pin the position this well in the worst
    /// direction, metres (one standard deviation, without the prior).
    #[serde(default = "default_revisit_max_sigma_m")]
    pub revisit_max_sigma_m: f64,
    /// Rectilinear heading: after each turn and at each leg's end the scan's straight walls,
    /// folded modulo 90 deg, measure the heading against the building's axes (those of the
    /// first scan with walls), so that a blind turn's error does not steer every later leg.
    /// Absent from a stored configuration, it is off (as the runs recorded before it).
    #[serde(default)]
    pub rectilinear: bool,
    /// The rectilinear measurement's standard deviation, degrees (walls off true and the
    /// fit's own error).
    #[serde(default = "default_rectilinear_sigma_deg")]
    pub rectilinear_sigma_deg: f64,
    /// A rectilinear measurement more than this many standard deviations (of the heading's
    /// uncertainty and the measurement's together) from the estimate is ignored: walls that
    /// do not run along the axes ...
    #[serde(default = "default_rectilinear_gate_sigmas")]
    pub rectilinear_gate_sigmas: f64,
    /// ... and so is one more than this from it, degrees.
    #[serde(default = "default_rectilinear_max_deg")]
    pub rectilinear_max_deg: f64,
    /// Share of a scan's straight-wall fits that must run along one pair of axes (0..1).
    #[serde(default = "default_rectilinear_min_share")]
    pub rectilinear_min_share: f64,
    /// A heading corrected by the walls also moves the position it displaced (off when absent).
    #[serde(default)]
    pub rectilinear_moves_position: bool,
}

fn default_rectilinear_sigma_deg() -> f64 {
    0.75
}

fn default_rectilinear_gate_sigmas() -> f64 {
    3.0
}

fn default_rectilinear_max_deg() -> f64 {
    5.0
}

fn default_rectilinear_min_share() -> f64 {
    0.7
}

fn default_revisit_radius_m() -> f64 {
    1.5
}

fn default_revisit_min_age_legs() -> usize {
    5
}

fn default_revisit_keyframes() -> usize {
    4
}

fn default_revisit_max_sigma_m() -> f64 {
    0.02
}

fn default_slam_max_sigma_m() -> f64 {
    0.01
}

fn default_turn_sigma_deg() -> f64 {
    1.0
}

fn default_measured_turn_sigma_deg() -> f64 {
    0.2
}

fn default_drive_sigma_share() -> f64 {
    0.02
}

fn default_measured_drive_sigma_share() -> f64 {
    0.005
}

fn default_slam_smoothing_m() -> f64 {
    0.2
}

fn default_slam_resolution_m() -> f64 {
    0.05
}

fn default_true() -> bool {
    true
}

fn default_slam_min_points() -> usize {
    20
}

fn default_slam_min_quality() -> f64 {
    0.45
}

fn default_slam_keyframe_m() -> f64 {
    0.5
}

fn default_slam_keyframes() -> usize {
    60
}

fn default_slam_line_scatter() -> f64 {
    0.1
}

fn default_drive_max_turn_deg() -> f64 {
    1.0
}

/// A configuration without `drive_max_turn_deg` (a recording made before it) runs as then:
/// no gate.
fn no_drive_turn_gate() -> f64 {
    180.0
}

fn default_drive_turn_sigma_deg() -> f64 {
    0.1
}

fn default_partial_travel_max_sigma_m() -> f64 {
    0.02
}

/// A configuration without `partial_travel_max_sigma_m` (a recording made before it) runs as
/// then: any match that pins the travel to 0.05 m.
fn loose_partial_travel_sigma() -> f64 {
    0.05
}

/// A configuration without `drive_turn_sigma_deg` (a recording made before it) runs as then:
/// the matcher's own 2 deg.
fn loose_drive_turn_prior() -> f64 {
    2.0
}

fn default_slam_window_m() -> f64 {
    0.3
}

fn default_slam_window_deg() -> f64 {
    8.0
}

fn default_slam_step_m() -> f64 {
    0.25
}

impl LocaliserParams {
    /// The slam front end's parameters for the online option: the library's defaults with
    /// the search window narrowed to `slam_window_m` / `slam_window_deg` (the rules' pose is
    /// a far better prediction than the offline constant-velocity model).
    pub fn slam_front_end(&self) -> slam::FrontEndParams {
        slam::FrontEndParams {
            linear_window_m: self.slam_window_m,
            angular_window_deg: self.slam_window_deg,
            keyframe_distance_m: self.slam_keyframe_m,
            submap_keyframes: self.slam_keyframes,
            min_points: self.slam_min_points,
            min_quality: self.slam_min_quality,
            resolution_m: self.slam_resolution_m,
            smoothing_m: self.slam_smoothing_m,
            fuse_located: self.slam_fuse_prediction,
            icp_line_scatter: self.slam_line_scatter,
            ..slam::FrontEndParams::default()
        }
    }
}

/// The loop itself.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoopParams {
    /// Most legs toward one target, however far it is: the run then ends as leg_limit.
    pub max_legs: usize,
    /// Legs always allowed toward a target (when `max_legs` allows them).
    #[serde(default = "default_min_legs")]
    pub min_legs: usize,
    /// Legs allowed per metre of the straight line from the start to the target, when that
    /// is more than `min_legs`: the limit grows with the world. A configuration without it (a
    /// recording made before it) gets 0, a fixed limit, as then.
    #[serde(default)]
    pub legs_per_m: f64,
    /// The estimate within this of the target counts as arrival, metres.
    pub goal_tolerance_m: f64,
    /// An arrival farther than this (and than `min_leg_m`) from the target first drives onto
    /// it, once, within the leg limit, metres (0: never, also a stored configuration without it).
    #[serde(default)]
    pub final_approach_m: f64,
    /// Planning failures in a row (no safe ray, no progress) before the goal is unreachable.
    pub max_failed_tries: usize,
    /// Turn in place by this much when no safe ray exists, degrees.
    pub recovery_turn_deg: f64,
    /// A rotation is commanded in chunks of at most this much, each measured on its scans,
    /// degrees.
    pub rotation_chunk_deg: f64,
    /// The way ahead after a rotation is the narrowest clearance within this bearing of the
    /// heading, degrees.
    pub free_ahead_window_deg: f64,
    /// The final leg drives straight at the target when it lies within this bearing (or in
    /// the view of the chosen ray), degrees.
    pub final_leg_bearing_deg: f64,
    /// A turn onto a ray less than this off the heading is left out when the scan holds fewer
    /// than `skip_turn_max_hits` hits and the leg's way straight ahead is clear, degrees; 0:
    /// every turn is made.
    #[serde(default)]
    pub skip_turn_below_deg: f64,
    /// A scan with at least this many hits measures a turn: its small turns are made.
    #[serde(default = "default_skip_turn_max_hits")]
    pub skip_turn_max_hits: usize,
    /// A leg shorter than this is not driven (counts as a failed try), metres.
    pub min_leg_m: f64,
    /// A leg that brings less progress than this counts as a failed try, metres.
    pub min_progress_m: f64,
    /// Length of a leg without a landmark in front, metres.
    pub short_leg_m: f64,
    /// A leg is stalled when the laser measures less than this share of the commanded travel
    /// (0 to 1; legs of less than 0.2 m commanded are not judged).
    pub stall_share: f64,
    /// Stalled legs in a row that end the run as base_stalled.
    pub stall_legs: usize,
    /// An arrival whose position uncertainty (the legs' `position_sigma_m`) exceeds
    /// `arrival_max_sigma_m` ends the run as uncertain_arrival instead of reached.
    #[serde(default)]
    pub flag_uncertain_arrival: bool,
    /// The largest position uncertainty of a claimed arrival, metres.
    #[serde(default = "default_arrival_max_sigma_m")]
    pub arrival_max_sigma_m: f64,
    /// A target that lies within a mapped obstacle's clearance (`expansion_margin_m` beyond
    /// r), farther than `goal_tolerance_m` from any place the robot may stand, counts as
    /// reached after this many plans made within `goal_tolerance_m` of the nearest such place;
    /// 0: never (also what a stored configuration without the key means).
    #[serde(default)]
    pub blocked_target_plans: usize,
}

fn default_arrival_max_sigma_m() -> f64 {
    0.3
}

fn default_skip_turn_max_hits() -> usize {
    60
}

fn default_min_legs() -> usize {
    60
}

/// Every tuning parameter of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// The preset these values started from.
    pub method: Method,
    /// Robot and expansion.
    pub robot: RobotParams,
    /// Path selection.
    pub planner: PlanningParams,
    /// Landmark detection and selection.
    pub landmarks: LandmarkParams,
    /// Landmark tracking.
    pub tracking: TrackingParams,
    /// Localisation and mapping.
    pub localiser: LocaliserParams,
    /// The loop.
    pub navigator: LoopParams,
}

impl Default for Params {
    fn default() -> Self {
        Self::goalseek()
    }
}

impl Params {
    /// goalseek's defaults.
    pub fn goalseek() -> Self {
        Params {
            method: Method::Goalseek,
            robot: RobotParams {
                radius_m: 0.3,
                expansion_margin_m: 0.1,
                narrow_margin_m: 0.025,
            },
            planner: PlanningParams {
                rule: PlanRule::MapPath,
                min_travel_m: 0.3,
                max_leg_m: 3.0,
                grid_resolution_m: 0.1,
                width_window_deg: 2.0,
                remember_turned_away_hits: true,
                // Off: measured no better (docs/navigator.md, "Replanning while driving").
                replan_step_m: 0.0,
                line_of_sight: true,
                measure_path_gaps: true,
            },
            landmarks: LandmarkParams {
                neighbour_n: 1,
                max_bearing_deg: 90.0,
                range_limit_margin_m: 0.15,
                range_limit_gaps: 1.5,
                occlusion_edges: false,
                corners: false,
                min_jump_m: 0.5,
                min_ob_m: 0.2,
                min_cb_m: 0.15,
            },
            tracking: TrackingParams {
                step_m: 0.05,
                gate_m: 0.06,
                max_missed_scans: 3,
                round_centre: true,
                reject_near_range_limit: true,
            },
            localiser: LocaliserParams {
                heading_rule: HeadingRule::ScanMatched,
                rotation_search_deg: 6.0,
                travel_rule: TravelRule::ScanMatched,
                keyframe_m: 1.0,
                match_prior_m: 0.005,
                match_prior_per_m: 0.02,
                turn_match_prior_m: 0.01,
                turn_match_gate_m: 0.15,
                map_resolution_m: 0.05,
                drive_max_turn_deg: default_drive_max_turn_deg(),
                drive_turn_sigma_deg: default_drive_turn_sigma_deg(),
                partial_travel_max_sigma_m: default_partial_travel_max_sigma_m(),
                ray_shift_max_sigmas: 3.0,
                ray_shift_alone_sigma_deg: default_turn_sigma_deg(),
                slam: false,
                slam_window_m: default_slam_window_m(),
                slam_window_deg: default_slam_window_deg(),
                slam_step_m: default_slam_step_m(),
                slam_keyframe_m: default_slam_keyframe_m(),
                slam_keyframes: default_slam_keyframes(),
                slam_min_points: default_slam_min_points(),
                slam_min_quality: default_slam_min_quality(),
                slam_resolution_m: default_slam_resolution_m(),
                slam_refined_only: true,
                slam_max_sigma_m: default_slam_max_sigma_m(),
                revisit: true,
                revisit_radius_m: default_revisit_radius_m(),
                revisit_min_age_legs: default_revisit_min_age_legs(),
                revisit_keyframes: default_revisit_keyframes(),
                revisit_max_sigma_m: default_revisit_max_sigma_m(),
                rectilinear: true,
                rectilinear_sigma_deg: default_rectilinear_sigma_deg(),
                rectilinear_gate_sigmas: default_rectilinear_gate_sigmas(),
                rectilinear_max_deg: default_rectilinear_max_deg(),
                rectilinear_min_share: default_rectilinear_min_share(),
                rectilinear_moves_position: false,
                slam_smoothing_m: default_slam_smoothing_m(),
                slam_fuse_prediction: true,
                slam_line_scatter: 0.03,
                stray_landmark_max_sigma_m: 0.01,
                turn_sigma_deg: default_turn_sigma_deg(),
                measured_turn_sigma_deg: default_measured_turn_sigma_deg(),
                drive_sigma_share: default_drive_sigma_share(),
                measured_drive_sigma_share: default_measured_drive_sigma_share(),
            },
            navigator: LoopParams {
                max_legs: 400,
                min_legs: 60,
                legs_per_m: 12.0,
                goal_tolerance_m: 0.15,
                final_approach_m: 0.05,
                max_failed_tries: 8,
                recovery_turn_deg: 60.0,
                rotation_chunk_deg: 90.0,
                free_ahead_window_deg: 2.0,
                final_leg_bearing_deg: 3.0,
                skip_turn_below_deg: 4.0,
                skip_turn_max_hits: default_skip_turn_max_hits(),
                min_leg_m: 0.05,
                min_progress_m: 0.05,
                short_leg_m: 1.0,
                stall_share: 0.25,
                stall_legs: 2,
                flag_uncertain_arrival: false,
                arrival_max_sigma_m: default_arrival_max_sigma_m(),
                blocked_target_plans: 3,
            },
        }
    }

    /// The paper as written: goalseek's values where the paper names none.
    pub fn paper() -> Self {
        let mut c = Self::goalseek();
        c.method = Method::Paper;
        c.robot.expansion_margin_m = 0.0;
        c.robot.narrow_margin_m = 0.0;
        c.planner.rule = PlanRule::Greedy;
        c.planner.width_window_deg = 0.0;
        c.planner.remember_turned_away_hits = false;
        c.planner.replan_step_m = 0.0;
        c.planner.line_of_sight = false;
        c.planner.measure_path_gaps = false;
        c.landmarks.range_limit_margin_m = 0.0;
        c.landmarks.range_limit_gaps = 0.0;
        c.tracking.gate_m = 0.2;
        c.tracking.round_centre = false;
        c.tracking.reject_near_range_limit = false;
        c.localiser.heading_rule = HeadingRule::Commanded;
        c.localiser.travel_rule = TravelRule::Landmark;
        c.localiser.revisit = false;
        c.localiser.rectilinear = false;
        c.localiser.stray_landmark_max_sigma_m = 0.0;
        c.navigator.skip_turn_below_deg = 0.0;
        // Its greedy rule loops where a wall blocks it: more legs only lengthen the loop.
        c.navigator.legs_per_m = 4.0;
        c.navigator.blocked_target_plans = 0;
        c.navigator.final_approach_m = 0.0;
        c
    }

    /// The preset of a method.
    pub fn preset(method: Method) -> Self {
        match method {
            Method::Goalseek => Self::goalseek(),
            Method::Paper => Self::paper(),
        }
    }

    /// The leg limit of a run from `start` to `goal`: `legs_per_m` legs per metre of the
    /// straight line between them, at least `min_legs` and at most `max_legs`.
    pub fn leg_limit(&self, start: WorldPoint, goal: WorldPoint) -> usize {
        let n = &self.navigator;
        let scaled = (n.legs_per_m * start.distance_m(&goal)).ceil();
        let wanted = if scaled.is_finite() {
            (scaled.min(1e6) as usize).max(n.min_legs)
        } else {
            n.min_legs
        };
        wanted.min(n.max_legs)
    }

    /// Checks every value against its valid range ([`Params::ranges`]); the error names the
    /// key.
    pub fn validate(&self) -> Result<(), NavigatorError> {
        for (key, v, lo, hi, open_low) in self.ranges() {
            let ok = v.is_finite() && (if open_low { v > lo } else { v >= lo }) && v <= hi;
            if !ok {
                let low = if open_low { "above" } else { "at least" };
                return Err(invalid(
                    key,
                    v,
                    &format!("must be {low} {lo} and at most {hi}"),
                ));
            }
        }
        if self.planner.max_leg_m < self.planner.min_travel_m {
            return Err(invalid(
                "planner.max_leg_m",
                self.planner.max_leg_m,
                &format!(
                    "must be at least planner.min_travel_m = {}",
                    self.planner.min_travel_m
                ),
            ));
        }
        Ok(())
    }

    /// Every numeric key with its value and valid range: `(key, value, low, high, low is
    /// excluded)`.
    pub fn ranges(&self) -> Vec<(&'static str, f64, f64, f64, bool)> {
        let (r, p, l, t) = (&self.robot, &self.planner, &self.landmarks, &self.tracking);
        let (z, n) = (&self.localiser, &self.navigator);
        let count = |v: usize| v as f64;
        // One key a line: the table is read by people checking a range.
        #[rustfmt::skip]
        let table = vec![
            ("robot.radius_m", r.radius_m, 0.0, 5.0, true),
            ("robot.expansion_margin_m", r.expansion_margin_m, 0.0, 2.0, false),
            ("robot.narrow_margin_m", r.narrow_margin_m, 0.0, 2.0, false),
            ("planner.min_travel_m", p.min_travel_m, 0.0, 20.0, true),
            ("planner.max_leg_m", p.max_leg_m, 0.0, 100.0, true),
            ("planner.grid_resolution_m", p.grid_resolution_m, 0.01, 1.0, false),
            ("planner.width_window_deg", p.width_window_deg, 0.0, 90.0, false),
            ("planner.replan_step_m", p.replan_step_m, 0.0, 100.0, false),
            ("landmarks.neighbour_n", count(l.neighbour_n), 1.0, 100.0, false),
            ("landmarks.max_bearing_deg", l.max_bearing_deg, 0.0, 180.0, true),
            ("landmarks.range_limit_margin_m", l.range_limit_margin_m, 0.0, 10.0, false),
            ("landmarks.range_limit_gaps", l.range_limit_gaps, 0.0, 100.0, false),
            ("landmarks.min_jump_m", l.min_jump_m, 0.0, 10.0, true),
            ("landmarks.min_ob_m", l.min_ob_m, 0.0, 10.0, false),
            ("landmarks.min_cb_m", l.min_cb_m, 0.0, 10.0, false),
            ("tracking.step_m", t.step_m, 0.0, 5.0, true),
            ("tracking.gate_m", t.gate_m, 0.0, 5.0, true),
            ("tracking.max_missed_scans", count(t.max_missed_scans), 0.0, 1000.0, false),
            ("localiser.rotation_search_deg", z.rotation_search_deg, 0.0, 180.0, true),
            ("localiser.keyframe_m", z.keyframe_m, 0.0, 100.0, true),
            ("localiser.match_prior_m", z.match_prior_m, 0.0, 10.0, true),
            ("localiser.match_prior_per_m", z.match_prior_per_m, 0.0, 10.0, false),
            ("localiser.turn_match_prior_m", z.turn_match_prior_m, 0.0, 10.0, true),
            ("localiser.turn_match_gate_m", z.turn_match_gate_m, 0.0, 5.0, true),
            ("localiser.map_resolution_m", z.map_resolution_m, 0.01, 1.0, false),
            ("localiser.drive_max_turn_deg", z.drive_max_turn_deg, 0.0, 180.0, true),
            ("localiser.drive_turn_sigma_deg", z.drive_turn_sigma_deg, 0.001, 90.0, false),
            ("localiser.partial_travel_max_sigma_m", z.partial_travel_max_sigma_m, 0.0, 1.0, false),
            ("localiser.ray_shift_max_sigmas", z.ray_shift_max_sigmas, 0.0, 100.0, false),
            ("localiser.ray_shift_alone_sigma_deg", z.ray_shift_alone_sigma_deg, 0.0, 90.0, false),
            ("localiser.slam_window_m", z.slam_window_m, 0.0, 1.6, true),
            ("localiser.slam_window_deg", z.slam_window_deg, 0.0, 90.0, true),
            ("localiser.slam_step_m", z.slam_step_m, 0.0, 10.0, true),
            ("localiser.slam_keyframe_m", z.slam_keyframe_m, 0.0, 10.0, true),
            ("localiser.slam_keyframes", count(z.slam_keyframes), 1.0, 10000.0, false),
            ("localiser.slam_min_points", count(z.slam_min_points), 3.0, 10000.0, false),
            ("localiser.slam_min_quality", z.slam_min_quality, 0.0, 1.0, false),
            ("localiser.slam_resolution_m", z.slam_resolution_m, 0.01, 1.0, false),
            ("localiser.slam_max_sigma_m", z.slam_max_sigma_m, 0.0, 10.0, true),
            ("localiser.slam_smoothing_m", z.slam_smoothing_m, 0.0, 1.0, true),
            ("localiser.slam_line_scatter", z.slam_line_scatter, 0.0, 1.0, true),
            ("localiser.stray_landmark_max_sigma_m", z.stray_landmark_max_sigma_m, 0.0, 1.0, false),
            ("localiser.revisit_radius_m", z.revisit_radius_m, 0.0, 100.0, true),
            ("localiser.revisit_min_age_legs", count(z.revisit_min_age_legs), 1.0, 1e6, false),
            ("localiser.revisit_keyframes", count(z.revisit_keyframes), 1.0, 100.0, false),
            ("localiser.revisit_max_sigma_m", z.revisit_max_sigma_m, 0.0, 10.0, true),
            ("localiser.rectilinear_sigma_deg", z.rectilinear_sigma_deg, 0.0, 90.0, true),
            ("localiser.rectilinear_gate_sigmas", z.rectilinear_gate_sigmas, 0.0, 100.0, true),
            ("localiser.rectilinear_max_deg", z.rectilinear_max_deg, 0.0, 45.0, true),
            ("localiser.rectilinear_min_share", z.rectilinear_min_share, 0.0, 1.0, false),
            ("localiser.turn_sigma_deg", z.turn_sigma_deg, 0.0, 90.0, false),
            ("localiser.measured_turn_sigma_deg", z.measured_turn_sigma_deg, 0.0, 90.0, false),
            ("localiser.drive_sigma_share", z.drive_sigma_share, 0.0, 1.0, false),
            ("localiser.measured_drive_sigma_share", z.measured_drive_sigma_share, 0.0, 1.0, false),
            ("navigator.max_legs", count(n.max_legs), 1.0, 1e6, false),
            ("navigator.min_legs", count(n.min_legs), 1.0, 1e6, false),
            ("navigator.legs_per_m", n.legs_per_m, 0.0, 1000.0, false),
            ("navigator.goal_tolerance_m", n.goal_tolerance_m, 0.0, 10.0, true),
            ("navigator.final_approach_m", n.final_approach_m, 0.0, 10.0, false),
            ("navigator.max_failed_tries", count(n.max_failed_tries), 1.0, 1000.0, false),
            ("navigator.recovery_turn_deg", n.recovery_turn_deg, 0.0, 180.0, true),
            ("navigator.rotation_chunk_deg", n.rotation_chunk_deg, 0.0, 180.0, true),
            ("navigator.free_ahead_window_deg", n.free_ahead_window_deg, 0.0, 90.0, false),
            ("navigator.final_leg_bearing_deg", n.final_leg_bearing_deg, 0.0, 90.0, false),
            ("navigator.skip_turn_below_deg", n.skip_turn_below_deg, 0.0, 90.0, false),
            ("navigator.skip_turn_max_hits", count(n.skip_turn_max_hits), 0.0, 1e6, false),
            ("navigator.min_leg_m", n.min_leg_m, 0.0, 10.0, false),
            ("navigator.min_progress_m", n.min_progress_m, 0.0, 10.0, false),
            ("navigator.short_leg_m", n.short_leg_m, 0.0, 100.0, true),
            ("navigator.stall_share", n.stall_share, 0.0, 1.0, false),
            ("navigator.stall_legs", count(n.stall_legs), 1.0, 1000.0, false),
            ("navigator.arrival_max_sigma_m", n.arrival_max_sigma_m, 0.0, 100.0, true),
            ("navigator.blocked_target_plans", count(n.blocked_target_plans), 0.0, 1000.0, false),
        ];
        table
    }

    /// Landmark detection, selection and tracking parameters: the method's preset with the
    /// configured keys applied.
    pub fn landmark_params(&self) -> (DetectParams, SelectParams, TrackParams) {
        let (mut detect, mut select, mut track) = match self.method {
            Method::Paper => (
                DetectParams::paper(),
                SelectParams::paper(),
                TrackParams::paper(),
            ),
            Method::Goalseek => (
                DetectParams::default(),
                SelectParams::default(),
                TrackParams::default(),
            ),
        };
        let l = &self.landmarks;
        detect.neighbour_n = l.neighbour_n;
        detect.range_limit_margin_m = l.range_limit_margin_m;
        detect.range_limit_gaps = l.range_limit_gaps;
        detect.reject_near_range_limit = l.range_limit_margin_m > 0.0;
        detect.occlusion_edges = l.occlusion_edges;
        detect.corners = l.corners;
        detect.occlusion_jump_m = l.min_jump_m;
        select.max_bearing_rad = l.max_bearing_deg.to_radians();
        select.min_ahead_m = l.min_ob_m;
        track.gate_m = self.tracking.gate_m;
        track.max_missed_scans = self.tracking.max_missed_scans;
        track.reject_near_range_limit = self.tracking.reject_near_range_limit;
        track.detect = detect;
        (detect, select, track)
    }

    /// The planner's parameters.
    pub fn planner_params(&self) -> planner::PlannerParams {
        planner::PlannerParams {
            rule: match self.planner.rule {
                PlanRule::Greedy => planner::PlanRule::Greedy,
                PlanRule::MapPath => planner::PlanRule::MapPath,
            },
            robot_radius_m: self.robot.radius_m,
            margin_m: self.robot.expansion_margin_m,
            narrow_margin_m: self.robot.narrow_margin_m,
            line_of_sight: self.planner.line_of_sight,
            measure_path_gaps: self.planner.measure_path_gaps,
            min_travel_m: self.planner.min_travel_m,
            max_travel_m: self.planner.max_leg_m,
            grid_resolution_m: self.planner.grid_resolution_m,
            ..planner::PlannerParams::default()
        }
    }

    /// The expansion radius: r plus the margin, metres.
    pub fn expansion_radius_m(&self) -> f64 {
        self.robot.radius_m + self.robot.expansion_margin_m
    }
}

fn invalid(key: &'static str, value: impl ToString, requirement: &str) -> NavigatorError {
    NavigatorError::InvalidParam {
        key,
        value: value.to_string(),
        requirement: requirement.to_string(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use scan_types::ScanGeometry;
    use std::f64::consts::TAU;

    #[test]
    fn presets_differ_where_the_paper_differs() {
        let p = Params::paper();
        let g = Params::goalseek();
        assert_eq!(p.planner.rule, PlanRule::Greedy);
        assert_eq!(g.planner.rule, PlanRule::MapPath);
        assert_eq!(p.localiser.heading_rule, HeadingRule::Commanded);
        assert_eq!(g.localiser.heading_rule, HeadingRule::ScanMatched);
        assert_eq!(p.robot.expansion_margin_m, 0.0);
        assert_eq!(g.robot.expansion_margin_m, 0.1);
        assert_eq!(g.navigator.max_legs, 400);
        assert_eq!(p.robot.radius_m, 0.3);
        assert_eq!(Params::preset(Method::Paper), p);
        assert!(p.validate().is_ok() && g.validate().is_ok());
        assert_eq!(p.planner.replan_step_m, 0.0);
        assert_eq!(g.navigator.skip_turn_below_deg, 4.0);
        assert_eq!(p.navigator.skip_turn_below_deg, 0.0);
        assert_eq!(g.localiser.drive_turn_sigma_deg, 0.1);
        assert_eq!(p.localiser.drive_turn_sigma_deg, 0.1);
    }

    #[test]
    fn settings_stored_before_the_drive_and_turn_rules_keep_the_old_ones() {
        let g = Params::goalseek();
        let mut stored = serde_json::to_value(&g).unwrap();
        stored["localiser"]
            .as_object_mut()
            .unwrap()
            .remove("drive_turn_sigma_deg");
        stored["localiser"]
            .as_object_mut()
            .unwrap()
            .remove("partial_travel_max_sigma_m");
        stored["localiser"]
            .as_object_mut()
            .unwrap()
            .remove("ray_shift_max_sigmas");
        stored["localiser"]
            .as_object_mut()
            .unwrap()
            .remove("ray_shift_alone_sigma_deg");
        let n = stored["navigator"].as_object_mut().unwrap();
        n.remove("skip_turn_below_deg");
        n.remove("skip_turn_max_hits");
        let planner = stored["planner"].as_object_mut().unwrap();
        planner.remove("line_of_sight");
        planner.remove("measure_path_gaps");
        let t = stored["tracking"].as_object_mut().unwrap();
        t.remove("round_centre");
        t.remove("reject_near_range_limit");
        stored["landmarks"]
            .as_object_mut()
            .unwrap()
            .remove("range_limit_gaps");
        stored["localiser"]
            .as_object_mut()
            .unwrap()
            .remove("stray_landmark_max_sigma_m");
        let old: Params = serde_json::from_value(stored).unwrap();
        // The fixed range-limit margin; a landmark's travel always stands.
        assert_eq!(old.landmarks.range_limit_gaps, 0.0);
        assert_eq!(old.localiser.stray_landmark_max_sigma_m, 0.0);
        // The matcher's own heading prior (2 deg), every turn made.
        assert_eq!(old.localiser.drive_turn_sigma_deg, 2.0);
        assert_eq!(old.localiser.partial_travel_max_sigma_m, 0.05);
        // Every ray shift counts.
        assert_eq!(old.localiser.ray_shift_max_sigmas, 0.0);
        // A ray shift alone as certain as a scan match.
        assert_eq!(old.localiser.ray_shift_alone_sigma_deg, 0.2);
        assert_eq!(old.navigator.skip_turn_below_deg, 0.0);
        assert_eq!(old.navigator.skip_turn_max_hits, 60);
        // The grid path alone ranks the rays.
        assert!(!old.planner.line_of_sight && !old.planner_params().line_of_sight);
        // Gaps on the map's path are not measured.
        assert!(!old.planner.measure_path_gaps && !old.planner_params().measure_path_gaps);
        // Travel measured on a landmark's edge hit.
        assert!(!old.tracking.round_centre);
        // Landmarks re-identified at the range limit too.
        assert!(!old.tracking.reject_near_range_limit);
        assert!(!old.landmark_params().2.reject_near_range_limit);
        assert!(old.validate().is_ok());
        let mut back = old;
        back.localiser.drive_turn_sigma_deg = g.localiser.drive_turn_sigma_deg;
        back.localiser.partial_travel_max_sigma_m = 0.02;
        back.localiser.ray_shift_max_sigmas = 3.0;
        back.localiser.ray_shift_alone_sigma_deg = 1.0;
        back.navigator.skip_turn_below_deg = g.navigator.skip_turn_below_deg;
        back.planner.line_of_sight = true;
        back.planner.measure_path_gaps = true;
        back.tracking.round_centre = true;
        back.tracking.reject_near_range_limit = true;
        back.landmarks.range_limit_gaps = 1.5;
        back.localiser.stray_landmark_max_sigma_m = 0.01;
        assert_eq!(back, g);
    }

    #[test]
    fn the_range_limit_margin_grows_with_the_scanner_range() {
        let g = Params::goalseek();
        let margin = |geometry: &ScanGeometry| {
            g.landmark_params()
                .2
                .detect
                .range_limit_margin_for(geometry)
        };
        // The paper's 4 m, 240 deg / 684 steps: 1.5 x 16 x 0.00612 = 0.147 m, under 0.15 m.
        assert_eq!(margin(&ScanGeometry::paper()), 0.15);
        // The URG-04LX's 5.6 m, 2 pi / 1024 steps: 1.5 x 31.36 x 0.006136 = 0.2886 m.
        let urg = ScanGeometry::new(-340.0 * TAU / 1024.0, TAU / 1024.0, 682, 0.02, 5.6).unwrap();
        let (detect, _, track) = g.landmark_params();
        let m = detect.range_limit_margin_for(&urg);
        assert!((m - 0.2886).abs() < 1e-4, "{detect:?}");
        assert_eq!(track.detect.range_limit_margin_for(&urg), m);
        // The paper's method keeps no margin.
        let p = Params::paper();
        assert_eq!(p.landmark_params().0.range_limit_margin_for(&urg), 0.0);
    }

    #[test]
    fn the_leg_limit_grows_with_the_distance_to_the_target() {
        let g = Params::paper();
        let o = WorldPoint::new(0.0, 0.0);
        // 4 legs per metre: 30 m allows 120 legs; 10 m (40) keeps the floor of 60; 200 m
        // (800) is capped at 400.
        assert_eq!(g.leg_limit(o, WorldPoint::new(30.0, 0.0)), 120);
        assert_eq!(g.leg_limit(o, WorldPoint::new(6.0, 8.0)), 60);
        assert_eq!(g.leg_limit(o, WorldPoint::new(15.1, 0.0)), 61);
        assert_eq!(g.leg_limit(o, WorldPoint::new(200.0, 0.0)), 400);
        // goalseek's 12 per metre: 10 m allows 120 legs, 4 m keeps the floor, 40 m the cap.
        let s = Params::goalseek();
        assert_eq!(s.leg_limit(o, WorldPoint::new(6.0, 8.0)), 120);
        assert_eq!(s.leg_limit(o, WorldPoint::new(4.0, 0.0)), 60);
        assert_eq!(s.leg_limit(o, WorldPoint::new(40.0, 0.0)), 400);
        // A cap below the floor wins (a test's max_legs = 1).
        let mut one = g.clone();
        one.navigator.max_legs = 1;
        assert_eq!(one.leg_limit(o, WorldPoint::new(30.0, 0.0)), 1);
        let mut fixed = g.clone();
        fixed.navigator.legs_per_m = 0.0;
        assert_eq!(fixed.leg_limit(o, WorldPoint::new(300.0, 0.0)), 60);
    }

    #[test]
    fn invalid_values_name_their_key() {
        let mut p = Params::goalseek();
        p.navigator.min_leg_m = f64::NAN;
        let e = p.validate().unwrap_err().to_string();
        assert!(
            e.contains("navigator.min_leg_m") && e.contains("NaN"),
            "{e}"
        );
        let mut p = Params::goalseek();
        p.robot.radius_m = -1.0;
        assert!(
            p.validate()
                .unwrap_err()
                .to_string()
                .contains("robot.radius_m")
        );
        let mut p = Params::goalseek();
        p.planner.replan_step_m = -0.25;
        assert!(
            p.validate()
                .unwrap_err()
                .to_string()
                .contains("planner.replan_step_m")
        );
        let mut p = Params::goalseek();
        p.navigator.max_legs = 0;
        assert!(p.validate().unwrap_err().to_string().contains("max_legs"));
        assert!(
            "astar"
                .parse::<Method>()
                .unwrap_err()
                .to_string()
                .contains("astar")
        );
    }

    #[test]
    fn landmark_params_apply_the_configured_keys_to_detection_and_tracking() {
        let mut p = Params::goalseek();
        p.landmarks.corners = true;
        p.landmarks.max_bearing_deg = 30.0;
        p.tracking.gate_m = 0.15;
        let (detect, select, track) = p.landmark_params();
        assert!(detect.corners);
        // The tracker detects with the same parameters as the leg's detection.
        assert!(track.detect.corners);
        assert_eq!(track.gate_m, 0.15);
        assert!((select.max_bearing_rad - 30f64.to_radians()).abs() < 1e-15);
        p.landmarks.corners = false;
        let (detect, _, track) = p.landmark_params();
        assert!(!detect.corners && !track.detect.corners);
    }

    #[test]
    fn planner_params_follow_the_keys() {
        let mut c = Params::goalseek();
        c.robot.radius_m = 0.25;
        c.robot.expansion_margin_m = 0.05;
        c.planner.min_travel_m = 0.4;
        c.planner.max_leg_m = 1.5;
        c.planner.grid_resolution_m = 0.2;
        c.planner.rule = PlanRule::Greedy;
        let p = c.planner_params();
        assert_eq!(p.robot_radius_m, 0.25);
        assert_eq!(p.margin_m, 0.05);
        assert_eq!(p.min_travel_m, 0.4);
        assert_eq!(p.max_travel_m, 1.5);
        assert_eq!(p.grid_resolution_m, 0.2);
        assert_eq!(p.rule, planner::PlanRule::Greedy);
    }
}
