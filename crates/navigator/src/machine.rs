//! The loop as a state machine: [`Navigator`] is fed scans and motion results and answers
//! with the next [`Action`]. It never touches a sensor or a base.

use expansion::Expander;
use landmarks::{DetectParams, Landmark, SelectParams, TrackParams, detect, select};
use localiser::{AxesParams, OccupancyGrid};
use planner::{Plan, Planner};
use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

use crate::MAX_COORD_M;

/// Legs commanded shorter than this are not judged for a stall, metres.
const STALL_JUDGED_M: f64 = 0.2;
use crate::clearance::{block_by_unseen_hits, denoised, erode};
use crate::drive::{Drive, LegKind, Watch};
use crate::revisit::Revisits;
use crate::{HeadingRule, Leg, NarrowPassage, NavigatorError, Outcome, Params, PlanRule, Reason};

/// What the navigator asks its driver to do next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Action {
    /// Take a scan and pass it to [`Navigator::on_scan`].
    Scan,
    /// Turn in place by this angle (counter-clockwise positive), then call
    /// [`Navigator::on_motion_done`].
    Rotate {
        /// The angle, radians.
        angle_rad: f64,
    },
    /// Drive straight ahead by this distance, then call [`Navigator::on_motion_done`].
    Forward {
        /// The distance, metres.
        distance_m: f64,
    },
    /// The run is over: stop the base and take [`Navigator::into_outcome`].
    Finish(Reason),
}

/// The named phases of the loop.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Phase {
    /// Waiting for the first scan.
    Starting,
    /// Turning in place, in measured chunks, toward a planned ray or to look elsewhere.
    Turning,
    /// Driving a leg in steps, tracking a landmark.
    Driving,
    /// The run is over.
    Finished,
}

/// A turn in place under way.
struct Turn {
    /// The scan before the chunk under way.
    before: Scan,
    /// One chunk, radians.
    chunk_rad: f64,
    /// Chunks not yet commanded.
    left: usize,
    /// True once the chunk's motion is done and its scan is awaited.
    awaiting_scan: bool,
    /// What the turn is for.
    then: AfterTurn,
}

/// What follows a turn.
#[derive(Clone, Copy)]
enum AfterTurn {
    /// A recovery turn: plan again.
    Replan,
    /// The turn onto a planned ray: drive the leg.
    Leg {
        travel_m: f64,
        target_in_view: bool,
        narrow: Option<planner::NarrowSpot>,
    },
}

enum State {
    Starting,
    Turning(Turn),
    Driving(Box<Drive>),
    Finished,
}

/// A narrow leg whose straight-ahead clearance after the turn falls this much short of the
/// plan missed its passage, metres.
const NARROW_MISS_M: f64 = 0.05;
/// Turns again toward a missed narrow passage before driving what is free.
const NARROW_RETRIES: usize = 6;
/// The most a SLAM refinement may turn beyond the search window, degrees (its shift is the
/// slam front end's `max_refine_shift_m`).
const SLAM_REFINE_TURN_DEG: f64 = 2.0;

/// A watched leg's progress is judged only when it was planned to gain at least this much
/// per metre toward the target (a detour planned sideways is left alone).
const WATCH_MIN_RATE: f64 = 0.2;
/// A watched leg ends when the rest of it now gains less than this share of the progress it
/// was planned for...
const WATCH_KEEP_SHARE: f64 = 0.5;
/// ...less this slack (the grid's quantisation), metres.
const WATCH_SLACK_M: f64 = 0.1;

/// The goal-seeking loop of `docs/method.md` for one run, from `start` to `goal`.
///
/// Feed it with the driver loop of [`crate::run`] or your own: answer [`Action::Scan`] with
/// [`Navigator::on_scan`], a motion with [`Navigator::on_motion_done`] (or
/// [`Navigator::fail`]), until it answers [`Action::Finish`]. An event that does not answer
/// the pending action is ignored and the pending action is returned again.
pub struct Navigator {
    pub(crate) params: Params,
    pub(crate) geometry: ScanGeometry,
    goal: WorldPoint,
    pub(crate) estimate: Pose2,
    /// The estimate when motion was last commanded after it changed, and the motion
    /// commanded since (in that estimate's frame).
    commanded_since: (Pose2, Pose2),
    expander: Expander,
    clearances: Vec<f64>,
    eroded: Vec<f64>,
    /// Clearances at the narrow radius (graded clearance).
    narrow: Vec<f64>,
    planner: Planner,
    grid: OccupancyGrid,
    detect_params: DetectParams,
    select_params: SelectParams,
    pub(crate) track_params: TrackParams,
    legs_log: Vec<Leg>,
    scans: usize,
    path_length_m: f64,
    legs: usize,
    /// Legs driven before the current goal was set ([`Navigator::retarget`]).
    legs_before_goal: usize,
    /// Most legs toward the current goal ([`Params::leg_limit`]).
    leg_limit: usize,
    first_leg: Option<(WorldPoint, WorldPoint)>,
    /// Where the robot stands and the hits seen from there (world frame) while it turns in
    /// place: a replan there still knows what has left the field of view.
    spot: (WorldPoint, Vec<WorldPoint>),
    /// Planning failures in a row.
    failures: usize,
    /// Narrow legs refused after their turn, in a row (the heading missed the passage).
    narrow_misses: usize,
    narrow_passages: Vec<NarrowPassage>,
    /// Stalled legs in a row: commanded to drive, and the laser saw (almost) no motion.
    stalled_legs: usize,
    state: State,
    pending: Action,
    end: Option<(Reason, String)>,
    /// The online SLAM of `[localiser] slam` (`None` when off).
    slam: Option<Box<slam::FrontEnd>>,
    /// While driving: the last pose SLAM placed (or the leg's origin) and the commanded
    /// travel there, metres.
    slam_anchor: (Pose2, f64),
    /// The pose SLAM gave the last scan fed to it while driving, and that scan's commanded
    /// travel (`None` when it could not place it).
    slam_leg_pose: Option<(Pose2, f64)>,
    /// The estimate's heading uncertainty (one standard deviation), radians.
    sigma_heading_rad: f64,
    /// The estimate's position uncertainty (one standard deviation), metres.
    sigma_position_m: f64,
    /// Covariances of the estimate's position with its heading and with the axes.
    position_cov: PositionCov,
    /// Leg ends kept for `[localiser] revisit`.
    revisits: Revisits,
    /// The leg of the last revisit correction (0: none yet).
    last_revisit_leg: usize,
    /// `[localiser] rectilinear`: the building's axes (`None` until a scan shows walls).
    axes: Option<Axes>,
    /// Cycles begun beside a target inside a mapped obstacle's clearance.
    blocked_target_seen: usize,
    /// `[navigator] final_approach_m`: the approach to this target has been made.
    approached: bool,
    /// Legs ended early by `[planner] replan_step_m`.
    legs_cut_short: usize,
}

/// The building's axes as `[localiser] rectilinear` estimates them.
#[derive(Debug, Clone, Copy)]
struct Axes {
    /// Their direction in the world frame, modulo 90 deg, radians.
    angle_rad: f64,
    /// Its variance, rad^2.
    var_rad2: f64,
    /// Its covariance with the estimate's heading, rad^2.
    cov_heading_rad2: f64,
}

impl Axes {
    /// Their covariance with a heading of variance `p_hh`, held to what the two variances
    /// allow (revisits and SLAM shrink the heading's variance alone), rad^2.
    fn heading_cov_rad2(&self, p_hh: f64) -> f64 {
        let bound = (p_hh * self.var_rad2).sqrt();
        self.cov_heading_rad2.clamp(-bound, bound)
    }
}

/// Covariances of the estimate's position (x, y) with its heading and with the building's
/// axes, metre radians: what the legs driven on an uncertain heading carry of it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct PositionCov {
    heading: [f64; 2],
    axes: [f64; 2],
}

impl PositionCov {
    /// A leg displaced the position by (`dx`, `dy`): its end moves by (-dy, dx) per radian
    /// of heading error, with the heading's variance `p_hh` and covariance `p_ha` with the axes.
    fn leg(&mut self, dx: f64, dy: f64, p_hh: f64, p_ha: f64) {
        for (i, j) in [-dy, dx].into_iter().enumerate() {
            self.heading[i] += j * p_hh;
            self.axes[i] += j * p_ha;
        }
    }

    /// The walls' Kalman update (innovation axes less heading, variance `s`): the position's
    /// gain per radian of innovation; the covariances become those after the update.
    fn wall_update(&mut self, p_hh: f64, p_ha: f64, p_aa: f64, s: f64) -> [f64; 2] {
        let gain = [0, 1].map(|i| (self.axes[i] - self.heading[i]) / s);
        for (i, k) in gain.iter().enumerate() {
            self.heading[i] -= k * (p_ha - p_hh);
            self.axes[i] -= k * (p_aa - p_ha);
        }
        gain
    }
}

impl Navigator {
    /// A navigator for a sensor of `geometry`, starting at `start` (the estimate's origin)
    /// and heading for `goal`. The first action is [`Action::Scan`].
    pub fn new(
        params: Params,
        geometry: ScanGeometry,
        start: Pose2,
        goal: WorldPoint,
    ) -> Result<Self, NavigatorError> {
        params.validate()?;
        let finite = |what, ok: bool, value: String| {
            if ok {
                Ok(())
            } else {
                Err(NavigatorError::NotFinite { what, value })
            }
        };
        let coord = |v: f64| v.is_finite() && v.abs() <= MAX_COORD_M;
        finite(
            "start",
            coord(start.x_m) && coord(start.y_m) && start.theta_rad.is_finite(),
            format!("{}, {}, {}", start.x_m, start.y_m, start.theta_rad),
        )?;
        finite(
            "goal",
            coord(goal.x_m()) && coord(goal.y_m()),
            format!("{}, {}", goal.x_m(), goal.y_m()),
        )?;
        let (detect_params, select_params, track_params) = params.landmark_params();
        let planner = Planner::new(params.planner_params());
        let leg_limit = params.leg_limit(start.position(), goal);
        let slam = if params.localiser.slam {
            let front = slam::FrontEnd::new(params.localiser.slam_front_end())?;
            Some(Box::new(front))
        } else {
            None
        };
        Ok(Self {
            expander: Expander::new(&geometry),
            clearances: vec![0.0; geometry.ray_count],
            eroded: Vec::new(),
            narrow: vec![0.0; geometry.ray_count],
            commanded_since: (start, Pose2::default()),
            grid: OccupancyGrid::new(params.localiser.map_resolution_m),
            params,
            geometry,
            goal,
            estimate: start,
            planner,
            detect_params,
            select_params,
            track_params,
            legs_log: Vec::new(),
            scans: 0,
            path_length_m: 0.0,
            legs: 0,
            legs_before_goal: 0,
            leg_limit,
            first_leg: None,
            spot: (start.position(), Vec::new()),
            failures: 0,
            narrow_misses: 0,
            narrow_passages: Vec::new(),
            stalled_legs: 0,
            state: State::Starting,
            pending: Action::Scan,
            end: None,
            slam,
            slam_anchor: (start, 0.0),
            slam_leg_pose: None,
            sigma_heading_rad: 0.0,
            sigma_position_m: 0.0,
            position_cov: PositionCov::default(),
            revisits: Revisits::default(),
            last_revisit_leg: 0,
            axes: None,
            blocked_target_seen: 0,
            approached: false,
            legs_cut_short: 0,
        })
    }

    /// The action awaiting its result.
    pub fn pending(&self) -> Action {
        self.pending
    }

    /// The phase the loop is in.
    pub fn phase(&self) -> Phase {
        match self.state {
            State::Starting => Phase::Starting,
            State::Turning(_) => Phase::Turning,
            State::Driving(_) => Phase::Driving,
            State::Finished => Phase::Finished,
        }
    }

    /// The latest estimate.
    pub fn estimate(&self) -> Pose2 {
        self.estimate
    }

    /// The latest estimate moved by the motion commanded since it was set: the best guess of
    /// the pose the next scan is taken at.
    pub fn estimate_now(&self) -> Pose2 {
        let (at, moved) = self.commanded_since;
        if at == self.estimate {
            at.compose(&moved)
        } else {
            self.estimate
        }
    }

    /// The target.
    pub fn goal(&self) -> WorldPoint {
        self.goal
    }

    /// The sensor geometry the navigator expects.
    pub fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }

    /// The parameters of the run.
    pub fn params(&self) -> &Params {
        &self.params
    }

    /// Leg ends so far, starting with the start.
    pub fn legs(&self) -> &[Leg] {
        &self.legs_log
    }

    /// Scans accepted so far.
    pub fn scans(&self) -> usize {
        self.scans
    }

    /// Legs ended early so far because the map seen while driving showed they no longer led
    /// toward the target (`[planner] replan_step_m`).
    pub fn legs_cut_short(&self) -> usize {
        self.legs_cut_short
    }

    /// The occupancy grid built so far.
    pub fn grid(&self) -> &OccupancyGrid {
        &self.grid
    }

    /// Feeds the scan that answers [`Action::Scan`]; returns the next action.
    pub fn on_scan(&mut self, scan: &Scan) -> Action {
        if self.pending != Action::Scan {
            tracing::warn!(pending = ?self.pending, "a scan arrived while none was asked for; ignored");
            return self.pending;
        }
        if scan.len() != self.geometry.ray_count {
            let note = format!(
                "laser returned {} rays, its geometry says {}",
                scan.len(),
                self.geometry.ray_count
            );
            return self.fail(Reason::SensorFailure, note);
        }
        self.scans += 1;
        let next = match std::mem::replace(&mut self.state, State::Finished) {
            State::Starting => {
                let scan = scan.clone();
                if let Some(pose) = self.slam_place(&scan, self.estimate) {
                    self.estimate = pose;
                }
                self.square_up(&scan);
                self.integrate(&scan);
                // After a retarget the last leg's end is already recorded.
                if self.legs_log.is_empty() {
                    self.record(None, None, &scan);
                    if self.params.localiser.revisit {
                        // The start: the one place known exactly.
                        let sigma = (self.sigma_position_m, self.sigma_heading_rad);
                        self.revisits.add(0, self.estimate, &scan, sigma);
                    }
                }
                self.plan_next(scan)
            }
            State::Turning(turn) => self.turn_scanned(turn, scan),
            State::Driving(drive) => self.drive_scanned(drive, scan),
            State::Finished => Action::Finish(self.reason()),
        };
        self.set_pending(next)
    }

    /// Reports that the motion of [`Action::Rotate`] or [`Action::Forward`] is done; returns
    /// the next action.
    pub fn on_motion_done(&mut self) -> Action {
        let next = match (self.pending, &mut self.state) {
            (Action::Rotate { angle_rad }, State::Turning(turn)) if !turn.awaiting_scan => {
                turn.awaiting_scan = true;
                self.note_command(Pose2::new(0.0, 0.0, angle_rad));
                Action::Scan
            }
            (Action::Forward { distance_m }, State::Driving(drive)) => {
                drive.commanded_m += distance_m;
                self.note_command(Pose2::new(distance_m, 0.0, 0.0));
                self.path_length_m += distance_m.abs();
                Action::Scan
            }
            _ => {
                tracing::warn!(pending = ?self.pending, "a motion result arrived while no motion was asked for; ignored");
                self.pending
            }
        };
        self.set_pending(next)
    }

    /// Ends the run for a reason the caller found (a sensor or base failure, a collision
    /// seen by a simulator); returns [`Action::Finish`].
    pub fn fail(&mut self, reason: Reason, note: impl Into<String>) -> Action {
        if self.end.is_none() {
            self.end = Some((reason, note.into()));
        }
        self.state = State::Finished;
        self.set_pending(Action::Finish(self.reason()))
    }

    /// Sets a new target once the run to the last one has finished `reached` (or
    /// `uncertain_arrival`), `unreachable` or at the leg limit (exploration, waypoints). The estimate, the map and the planner's
    /// memory carry over; the leg limit counts from here. Returns the next action (a scan),
    /// or an error for a goal that is not finite or a run that has not finished that way.
    pub fn retarget(&mut self, goal: WorldPoint) -> Result<Action, NavigatorError> {
        let reason = match (&self.state, &self.end) {
            (State::Finished, Some((r, _))) => *r,
            _ => return Err(NavigatorError::NotFinished(self.phase())),
        };
        if !matches!(
            reason,
            Reason::Reached | Reason::UncertainArrival | Reason::Unreachable | Reason::LegLimit
        ) {
            return Err(NavigatorError::EndedBy(reason));
        }
        if !(goal.x_m().is_finite()
            && goal.y_m().is_finite()
            && goal.x_m().abs() <= MAX_COORD_M
            && goal.y_m().abs() <= MAX_COORD_M)
        {
            return Err(NavigatorError::NotFinite {
                what: "goal",
                value: format!("{}, {}", goal.x_m(), goal.y_m()),
            });
        }
        self.goal = goal;
        self.end = None;
        self.legs_before_goal = self.legs;
        self.blocked_target_seen = 0;
        self.approached = false;
        self.leg_limit = self.params.leg_limit(self.estimate.position(), goal);
        self.failures = 0;
        self.narrow_misses = 0;
        self.stalled_legs = 0;
        self.spot = (self.estimate.position(), Vec::new());
        self.state = State::Starting;
        Ok(self.set_pending(Action::Scan))
    }

    /// How the run ended (or how it stands) and what it recorded.
    pub fn into_outcome(self) -> Outcome {
        let (reason, note) = self.end.unwrap_or((
            Reason::SensorFailure,
            "the run was stopped before it finished".into(),
        ));
        Outcome {
            reason,
            note,
            legs: self.legs_log,
            legs_driven: self.legs,
            scans: self.scans,
            path_length_m: self.path_length_m,
            estimate: self.estimate,
            grid: self.grid,
            first_leg: self.first_leg,
            narrow_passages: self.narrow_passages,
        }
    }

    fn reason(&self) -> Reason {
        self.end.as_ref().map_or(Reason::SensorFailure, |e| e.0)
    }

    fn set_pending(&mut self, next: Action) -> Action {
        self.pending = next;
        next
    }

    fn finish(&mut self, reason: Reason, note: String) -> Action {
        self.end = Some((reason, note));
        self.state = State::Finished;
        Action::Finish(reason)
    }

    /// Adds a commanded motion (robot frame) to the motion since the estimate was set.
    fn note_command(&mut self, motion: Pose2) {
        if self.commanded_since.0 != self.estimate {
            self.commanded_since = (self.estimate, Pose2::default());
        }
        self.commanded_since.1 = self.commanded_since.1.compose(&motion);
    }

    fn record(&mut self, landmark: Option<WorldPoint>, point_b: Option<WorldPoint>, scan: &Scan) {
        let scan_points = scan
            .robot_hits(&self.geometry)
            .map(|(_, p)| self.estimate.transform_point(p))
            .collect();
        self.legs_log.push(Leg {
            leg: self.legs,
            time_s: scan.host_time_s,
            estimate: self.estimate,
            landmark,
            point_b,
            scan_points,
            position_sigma_m: self.sigma_position_m,
            heading_sigma_deg: self.sigma_heading_rad.to_degrees(),
        });
    }

    fn integrate(&mut self, scan: &Scan) {
        self.grid.integrate(&self.estimate, &self.geometry, scan);
        self.planner.add_scan(&self.estimate, &self.geometry, scan);
    }

    /// The top of a cycle: stop, make the final approach, or expand, plan and start the turn
    /// onto the chosen ray.
    fn plan_next(&mut self, scan: Scan) -> Action {
        let to_goal = self.estimate.position().distance_m(&self.goal);
        let beside = self.beside_blocked_target(to_goal);
        let n = &self.params.navigator;
        if to_goal <= n.goal_tolerance_m || beside.is_some() {
            if n.flag_uncertain_arrival && self.sigma_position_m > n.arrival_max_sigma_m {
                let note = format!(
                    "the estimate reached the target but its position uncertainty is {:.2} m (more than {:.2} m)",
                    self.sigma_position_m, n.arrival_max_sigma_m
                );
                return self.finish(Reason::UncertainArrival, note);
            }
            if beside.is_none()
                && !self.approached
                && n.final_approach_m > 0.0
                && to_goal > n.final_approach_m.max(n.min_leg_m)
                && self.legs - self.legs_before_goal < self.leg_limit
            {
                // Within tolerance but not at the target: one leg aimed at the target itself.
                self.approached = true;
                let alpha_rad = self
                    .estimate
                    .inverse_transform_point(self.goal)
                    .bearing_rad();
                tracing::debug!(
                    to_goal,
                    alpha_deg = alpha_rad.to_degrees(),
                    "final approach"
                );
                let then = AfterTurn::Leg {
                    travel_m: to_goal,
                    target_in_view: true,
                    narrow: None,
                };
                return self.start_turn(alpha_rad, scan, then);
            }
            let note = beside.unwrap_or_else(|| "estimate within tolerance of the target".into());
            return self.finish(Reason::Reached, note);
        }
        if self.legs - self.legs_before_goal >= self.leg_limit {
            let note = format!(
                "{} legs driven, {to_goal:.2} m from the target by the estimate",
                self.legs - self.legs_before_goal
            );
            return self.finish(Reason::LegLimit, note);
        }
        if self.failures >= self.params.navigator.max_failed_tries {
            let note = format!(
                "no way toward the target after {} tries ({to_goal:.2} m away)",
                self.failures
            );
            return self.finish(Reason::Unreachable, note);
        }
        // 2-3. Expand and plan.
        let r = self.params.expansion_radius_m();
        self.expander.clearances(&scan, r, &mut self.clearances);
        if self.params.planner.remember_turned_away_hits {
            self.block_by_spot_hits(&scan, r);
        }
        let half = (self.params.planner.width_window_deg.to_radians()
            / self.geometry.increment_rad.abs())
        .ceil() as usize;
        erode(&self.clearances, half, &mut self.eroded);
        std::mem::swap(&mut self.clearances, &mut self.eroded);
        let graded = self.planner.params().graded();
        let smooth = graded.then(|| denoised(&scan));
        if let Some(smooth) = &smooth {
            // The exact geometry at the narrow radius: no width window, the turn is checked
            // again on the scan after it.
            let rn = self.planner.params().narrow_radius_m();
            self.expander.clearances(smooth, rn, &mut self.narrow);
            if self.params.planner.remember_turned_away_hits {
                block_by_unseen_hits(
                    &self.geometry,
                    &self.estimate,
                    &self.spot.1,
                    rn,
                    &mut self.narrow,
                );
            }
        }
        let plan = self.planner.plan_graded(
            &self.estimate,
            &self.geometry,
            &scan,
            &self.clearances,
            smooth.as_ref().map(|s| (s, self.narrow.as_slice())),
            self.goal,
        );
        match plan {
            Plan::Go {
                alpha_rad,
                travel_m,
                target_in_view,
                narrow,
                ..
            } => {
                if narrow.is_none()
                    && !target_in_view
                    && self.turn_skippable(alpha_rad, travel_m, &scan)
                {
                    tracing::debug!(
                        alpha_deg = alpha_rad.to_degrees(),
                        travel_m,
                        "small turn skipped; driving straight ahead"
                    );
                    return self.start_leg(scan, travel_m, target_in_view, None);
                }
                self.start_turn(
                    alpha_rad,
                    scan,
                    AfterTurn::Leg {
                        travel_m,
                        target_in_view,
                        narrow,
                    },
                )
            }
            Plan::Unreachable { tries } => self.finish(
                Reason::Unreachable,
                format!("the planner found no way to the target after {tries} tries"),
            ),
            _ => {
                self.failures += 1;
                tracing::debug!(
                    failures = self.failures,
                    "no safe ray; turning to look elsewhere"
                );
                let turn = self.params.navigator.recovery_turn_deg.to_radians();
                self.start_turn(turn, scan, AfterTurn::Replan)
            }
        }
    }

    /// `[navigator] blocked_target_plans`: the note of an arrival at the nearest place the
    /// robot may stand, when the target lies within a mapped obstacle's clearance and the
    /// robot has planned that often within `goal_tolerance_m` of that place.
    fn beside_blocked_target(&mut self, to_goal: f64) -> Option<String> {
        let n = &self.params.navigator;
        if n.blocked_target_plans == 0 {
            return None;
        }
        // The planner approaches a target with the full expansion: its centre stays this far
        // from every hit (the narrow radius is for passages).
        let radius_m = self.params.expansion_radius_m();
        let free_m = self
            .planner
            .memory()
            .nearest_hit_m(self.goal, radius_m)
            .map_or(0.0, |d| radius_m - d);
        if free_m <= n.goal_tolerance_m {
            self.blocked_target_seen = 0;
            return None;
        }
        if to_goal > free_m + n.goal_tolerance_m {
            return None;
        }
        self.blocked_target_seen += 1;
        (self.blocked_target_seen >= n.blocked_target_plans).then(|| {
            format!(
                "stopped {to_goal:.2} m from the target by the estimate, at the nearest place clear of the map's obstacles (the target lies {free_m:.2} m inside their clearance)"
            )
        })
    }

    /// Whether the turn onto a ray `alpha_rad` off the heading can be left out: it is small,
    /// the scan holds too little to measure it on, and the way straight ahead is clear for the
    /// leg, on the scan and on the memory.
    fn turn_skippable(&mut self, alpha_rad: f64, travel_m: f64, scan: &Scan) -> bool {
        let below = self.params.navigator.skip_turn_below_deg.to_radians();
        if alpha_rad == 0.0 || alpha_rad.is_nan() || alpha_rad.abs() >= below {
            return false;
        }
        if scan.robot_hits(&self.geometry).count() >= self.params.navigator.skip_turn_max_hits {
            return false;
        }
        let want = travel_m.min(self.params.planner.max_leg_m);
        // A leg too short to drive would be refused and replanned on the same scan.
        if want < self.params.navigator.min_leg_m {
            return false;
        }
        self.free_ahead_m(scan) >= want && self.planner.free_ahead_m(&self.estimate, want) >= want
    }

    /// Rotates by `alpha` (step 4) in chunks the scans can still align.
    fn start_turn(&mut self, alpha_rad: f64, before: Scan, then: AfterTurn) -> Action {
        let max_chunk = self.params.navigator.rotation_chunk_deg.to_radians();
        let chunks = (alpha_rad.abs() / max_chunk).ceil().max(1.0) as usize;
        let chunk_rad = alpha_rad / chunks as f64;
        self.state = State::Turning(Turn {
            before,
            chunk_rad,
            left: chunks - 1,
            awaiting_scan: false,
            then,
        });
        Action::Rotate {
            angle_rad: chunk_rad,
        }
    }

    /// The scan after a chunk (step 5): the heading by the heading rule, then the next
    /// chunk or what follows the turn.
    fn turn_scanned(&mut self, mut turn: Turn, after: &Scan) -> Action {
        let chunk = turn.chunk_rad;
        let measured = || {
            let m = localiser::measure_rotation(
                &self.geometry,
                &turn.before,
                after,
                chunk,
                self.params.localiser.rotation_search_deg.to_radians(),
            );
            if m.is_none() {
                tracing::debug!(chunk, "rotation not measurable; using the command");
            }
            m
        };
        let l = &self.params.localiser;
        let (matched_sigma, shift_sigma, command_sigma) = (
            l.measured_turn_sigma_deg,
            l.ray_shift_alone_sigma_deg,
            l.turn_sigma_deg,
        );
        // The turn, and the heading uncertainty (degrees) it adds.
        let (turned, mut added_deg) = match l.heading_rule {
            HeadingRule::Commanded => (chunk, command_sigma),
            HeadingRule::ScanMeasured => {
                measured().map_or((chunk, command_sigma), |m| (m, matched_sigma))
            }
            HeadingRule::ScanMatched => {
                let m = measured();
                let guess = m.unwrap_or(chunk);
                let r = self.rotation_matched(&turn.before, after, guess);
                tracing::debug!(
                    chunk_deg = chunk.to_degrees(),
                    ray_shift_deg = m.map(f64::to_degrees),
                    matched_deg = r.map(f64::to_degrees),
                    "turn measured"
                );
                match (r, m) {
                    (Some(r), _) => (r, matched_sigma),
                    (None, Some(m)) if self.ray_shift_alone_fits(m, chunk) => (m, shift_sigma),
                    (None, _) => (chunk, command_sigma),
                }
            }
        };
        let rotated = self.estimate.rotated(turned);
        self.estimate = match self.slam_place(after, rotated) {
            Some(pose) => {
                added_deg = matched_sigma;
                pose
            }
            None => rotated,
        };
        self.sigma_heading_rad = self.sigma_heading_rad.hypot(added_deg.to_radians());
        self.square_up(after);
        turn.before = after.clone();
        if turn.left > 0 {
            turn.left -= 1;
            turn.awaiting_scan = false;
            self.state = State::Turning(turn);
            return Action::Rotate { angle_rad: chunk };
        }
        match turn.then {
            AfterTurn::Replan => self.plan_next(turn.before),
            AfterTurn::Leg {
                travel_m,
                target_in_view,
                narrow,
            } => self.start_leg(turn.before, travel_m, target_in_view, narrow),
        }
    }

    /// Whether a turn chunk measured by the ray shift alone lies close enough to the command
    /// (`[localiser] ray_shift_max_sigmas`): unconfirmed by the scan match, a shift several
    /// turn sigmas off is more likely a wrong alignment than the base's error.
    fn ray_shift_alone_fits(&self, measured_rad: f64, chunk_rad: f64) -> bool {
        let l = &self.params.localiser;
        if l.ray_shift_max_sigmas == 0.0 {
            return true;
        }
        let allowed =
            (l.ray_shift_max_sigmas * l.turn_sigma_deg.to_radians()).max(0.05 * chunk_rad.abs());
        let fits = (measured_rad - chunk_rad).abs() <= allowed;
        if !fits {
            tracing::debug!(
                chunk_deg = chunk_rad.to_degrees(),
                ray_shift_deg = measured_rad.to_degrees(),
                "ray shift alone too far from the command; using the command"
            );
        }
        fits
    }

    /// The rotation in place between `before` and `after` by scan matching, starting from
    /// `guess_rad`; the position is held near the spot by a tight prior.
    fn rotation_matched(&self, before: &Scan, after: &Scan, guess_rad: f64) -> Option<f64> {
        let params = localiser::MatchParams {
            prior_sigma_m: self.params.localiser.turn_match_prior_m,
            initial_gate_m: self.params.localiser.turn_match_gate_m,
            ..localiser::MatchParams::default()
        };
        let mut target = localiser::MatchTarget::from_scan(&self.geometry, before, &params);
        let m = target.align(
            &self.geometry,
            after,
            Pose2::new(0.0, 0.0, guess_rad),
            &params,
        )?;
        Some(guess_rad + scan_types::angle_diff_rad(m.pose.theta_rad, guess_rad))
    }

    /// Clearance straight ahead in `scan` (the rays near bearing 0), metres.
    fn free_ahead_m(&mut self, scan: &Scan) -> f64 {
        let r = self.params.expansion_radius_m();
        self.expander.clearances(scan, r, &mut self.clearances);
        // The robot's own width: the narrowest clearance over the rays within the window.
        let centre = self.geometry.nearest_index(0.0).unwrap_or(0);
        let window = self.params.navigator.free_ahead_window_deg.to_radians();
        let half = (window / self.geometry.increment_rad.abs()).ceil() as usize;
        let lo = centre.saturating_sub(half);
        let hi = (centre + half).min(self.geometry.ray_count - 1);
        self.clearances[lo..=hi]
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min)
    }

    /// Clearance of the ray straight ahead at r + a quarter of the narrow margin (more than
    /// the plan used, so range noise cannot let a drive graze a jamb), metres.
    fn narrow_ahead_m(&mut self, scan: &Scan) -> f64 {
        let p = self.planner.params();
        let rn = p.robot_radius_m + p.narrow_margin_m / 4.0;
        self.expander
            .clearances(&denoised(scan), rn, &mut self.narrow);
        self.geometry
            .nearest_index(0.0)
            .map_or(0.0, |i| self.narrow[i])
    }

    /// After the turn onto a ray: choose the leg (final, to a landmark's B, or short) and
    /// start driving it.
    fn start_leg(
        &mut self,
        scan: Scan,
        travel_m: f64,
        target_in_view: bool,
        mut narrow: Option<planner::NarrowSpot>,
    ) -> Action {
        // A narrow leg keeps as far from what ends it as a full leg does (the base's travel
        // error), so its free stretch is shortened by the margins' difference.
        let mut free = match narrow {
            None => self.free_ahead_m(&scan),
            Some(_) => {
                let p = self.planner.params();
                let short = p.margin_m - p.narrow_margin_m / 4.0;
                self.narrow_ahead_m(&scan) - short
            }
        };
        if narrow.is_some() && free < travel_m - NARROW_MISS_M {
            if self.narrow_misses < NARROW_RETRIES {
                // The turn's error points the robot at a jamb: turn again, from the same spot.
                self.narrow_misses += 1;
                tracing::debug!(
                    free,
                    travel_m,
                    "narrow passage missed after the turn; aiming again"
                );
                return self.plan_next(scan);
            }
            // Out of tries: drive only what the full margin allows.
            free = self.free_ahead_m(&scan);
            narrow = None;
        }
        self.narrow_misses = 0;
        let limit = travel_m.min(free).min(self.params.planner.max_leg_m);
        if limit < self.params.navigator.min_leg_m {
            self.failures += 1;
            tracing::debug!(free, travel_m, "no room ahead after the rotation");
            return self.plan_next(scan);
        }
        let origin = self.estimate;
        let goal_r = origin.inverse_transform_point(self.goal);
        let goal_ahead = goal_r.x_m();
        // 5. Landmarks in front, the nearest usable one (eq. 6).
        let min_cb = self.params.landmarks.min_cb_m;
        let usable: Vec<Landmark> = detect(&self.geometry, &scan, &self.detect_params)
            .into_iter()
            .filter(|l| {
                let ob = l.range_m * l.bearing_rad.cos();
                let cb = (l.range_m * l.bearing_rad.sin()).abs();
                ob <= limit && cb >= min_cb
            })
            .collect();
        let chosen = select(&usable, &self.select_params);
        if let Some(spot) = narrow.filter(|s| s.through) {
            let passage = NarrowPassage {
                leg: self.legs + 1,
                at: spot.at,
                clearance_m: spot.clearance_m,
                width_m: spot.width_m,
            };
            tracing::info!(
                leg = passage.leg,
                x_m = spot.at.x_m(),
                y_m = spot.at.y_m(),
                clearance_m = spot.clearance_m,
                width_m = spot.width_m,
                "narrow passage"
            );
            self.narrow_passages.push(passage);
        }
        let bearing = self.params.navigator.final_leg_bearing_deg.to_radians();
        let final_leg = (target_in_view || goal_r.bearing_rad().abs() < bearing)
            && goal_ahead <= limit + 1e-9
            && chosen.is_none_or(|l| l.range_m * l.bearing_rad.cos() >= goal_ahead);
        self.legs += 1;
        let (kind, limit_m, landmark) = if final_leg {
            // The goal is closer than any landmark: drive to it, measuring the travel on
            // whatever feature stays in view.
            (LegKind::Final, goal_ahead, self.any_landmark(&scan))
        } else if let Some(lm) = chosen {
            // 6. Triangle OBC; 7. drive to B tracking the landmark.
            let tri = localiser::triangle(&origin, lm.range_m, lm.bearing_rad);
            if self.first_leg.is_none() {
                self.first_leg = Some((tri.landmark, tri.point_b));
            }
            let kind = LegKind::ToB {
                landmark: tri.landmark,
                point_b: tri.point_b,
            };
            (kind, limit, Some(lm))
        } else {
            // No landmark in front: a short leg measured on any feature in view.
            let leg = limit.min(self.params.navigator.short_leg_m);
            (LegKind::Short, leg, self.any_landmark(&scan))
        };
        self.slam_anchor = (origin, 0.0);
        self.slam_leg_pose = None;
        let mut drive = Drive::new(self, kind, origin, limit_m, landmark, scan);
        drive.watch = self.watch_of(kind, origin, drive.remaining_m(), narrow.is_some());
        self.drive_step(Box::new(drive))
    }

    /// The next step of a drive, or the drive's end.
    fn drive_step(&mut self, drive: Box<Drive>) -> Action {
        match drive.next_step_m() {
            Some(step) => {
                self.state = State::Driving(drive);
                Action::Forward { distance_m: step }
            }
            None => self.end_leg(drive),
        }
    }

    /// The scan after a step (step 7): track the landmark, maybe stop at B, maybe a new
    /// keyframe.
    fn drive_scanned(&mut self, mut drive: Box<Drive>, scan: &Scan) -> Action {
        let since = drive.commanded_m - self.slam_anchor.1;
        if self.slam.is_some() && since >= self.params.localiser.slam_step_m - 1e-9 {
            self.slam_drive_scan(scan, drive.commanded_m);
        }
        if drive.scanned(self, scan) && !self.leg_outdated(&mut drive, scan) {
            self.drive_step(drive)
        } else {
            self.end_leg(drive)
        }
    }

    /// `[planner] replan_step_m`: how a leg about to be driven `limit_m` (to B for a leg to
    /// B) stands on the planner's map, or `None` when it is not watched (off, greedy, a final
    /// or narrow leg, a short leg).
    fn watch_of(
        &mut self,
        kind: LegKind,
        origin: Pose2,
        limit_m: f64,
        narrow: bool,
    ) -> Option<Watch> {
        let step = self.params.planner.replan_step_m;
        if step <= 0.0
            || narrow
            || self.params.planner.rule != PlanRule::MapPath
            || matches!(kind, LegKind::Final)
            || limit_m < 2.0 * step
        {
            return None;
        }
        let c = self.planner.check_leg(&origin, limit_m, self.goal);
        let rate = match (c.from_start_m, c.from_end_m) {
            (Some(a), Some(b)) => (a - b) / limit_m,
            _ => 0.0,
        };
        Some(Watch {
            rate,
            checked_m: 0.0,
        })
    }

    /// `[planner] replan_step_m`: every so much travel, judges the rest of the leg on the
    /// planner's map with the scan's hits added at the pose reached, when they occupy a new
    /// cell. True when the leg should end here: the rest runs into an obstacle's lethal
    /// core, or now gains clearly less toward the target than it was planned to.
    fn leg_outdated(&mut self, drive: &mut Drive, scan: &Scan) -> bool {
        let step = self.params.planner.replan_step_m;
        let Some(mut w) = drive.watch else {
            return false;
        };
        if drive.commanded_m - w.checked_m < step - 1e-9 {
            return false;
        }
        w.checked_m = drive.commanded_m;
        drive.watch = Some(w);
        let remaining = drive.remaining_m();
        if remaining < step {
            // The leg ends within the next step anyway.
            return false;
        }
        let at = drive
            .origin
            .compose(&Pose2::new(drive.measured_m(), 0.0, 0.0));
        // The scan's hits count for the check only: the leg's end adds them localised.
        let Some(c) =
            self.planner
                .check_leg_with_scan(&at, &self.geometry, scan, remaining, self.goal)
        else {
            return false;
        };
        let gain = match (c.from_start_m, c.from_end_m) {
            (Some(a), Some(b)) => Some(a - b),
            _ => None,
        };
        let why = if c.free_m < remaining - 1e-9 {
            "it runs into an obstacle seen while driving"
        } else if w.rate < WATCH_MIN_RATE {
            return false;
        } else {
            match (c.from_start_m, gain) {
                (_, Some(g)) if g < WATCH_KEEP_SHARE * w.rate * remaining - WATCH_SLACK_M => {
                    "its rest no longer leads toward the target"
                }
                (Some(_), None) => "its end is cut off from the target",
                _ => return false,
            }
        };
        self.legs_cut_short += 1;
        tracing::info!(
            leg = self.legs,
            driven_m = drive.commanded_m,
            remaining_m = remaining,
            free_m = c.free_m,
            gain_m = gain,
            planned_rate = w.rate,
            "leg cut short: {why}"
        );
        true
    }

    /// Localises at the leg's end and maps (steps 7-8), counts the try and plans again.
    fn end_leg(&mut self, drive: Box<Drive>) -> Action {
        let mut drive = *drive;
        let rel = drive.travelled(self);
        self.estimate = drive.origin.compose(&rel);
        let mut by_laser = drive.laser_measured;
        if self.slam.is_some() && drive.commanded_m > 0.0 {
            // The leg's last scan, placed by SLAM unless that was done on its step.
            let placed = match self.slam_leg_pose {
                Some((pose, at)) if at == drive.commanded_m => Some(pose),
                _ => self.slam_drive_scan(&drive.last_scan, drive.commanded_m),
            };
            if let Some(pose) = placed {
                self.estimate = pose;
                by_laser = true;
            }
        }
        // The error model: the drive's own error, and the heading's error carried along it.
        let driven = drive
            .origin
            .position()
            .distance_m(&self.estimate.position());
        let l = &self.params.localiser;
        let share = if by_laser {
            l.measured_drive_sigma_share
        } else {
            l.drive_sigma_share
        };
        self.sigma_position_m =
            self.sigma_position_m.hypot(share * driven) + driven * self.sigma_heading_rad;
        let p_hh = self.sigma_heading_rad.powi(2);
        let p_ha = self.axes.map_or(0.0, |a| a.heading_cov_rad2(p_hh));
        self.position_cov.leg(
            self.estimate.x_m - drive.origin.x_m,
            self.estimate.y_m - drive.origin.y_m,
            p_hh,
            p_ha,
        );
        self.square_up(&drive.last_scan);
        if self.params.localiser.revisit && drive.commanded_m > 0.0 {
            self.revisit(&drive.last_scan);
        }
        let judged = (drive.laser_measured, drive.commanded_m);
        let scan = drive.last_scan;
        self.integrate(&scan);
        match drive.kind {
            LegKind::ToB { landmark, point_b } => self.record(Some(landmark), Some(point_b), &scan),
            LegKind::Final | LegKind::Short => self.record(None, None, &scan),
        }
        // Greedy: a leg that brings the robot no closer failed (the paper's rule turns in
        // place forever behind a wall). MapPath: detours away from the target are how it
        // leaves a dead end, so only a leg that hardly moved failed; the planner itself
        // reports a target cut off on the map.
        let before_leg = drive.origin.position();
        let moved = before_leg.distance_m(&self.estimate.position());
        if let Some(action) = self.check_stall(judged, moved) {
            return action;
        }
        let progress = match self.params.planner.rule {
            PlanRule::Greedy => {
                before_leg.distance_m(&self.goal) - self.estimate.position().distance_m(&self.goal)
            }
            PlanRule::MapPath => moved,
        };
        if progress < self.params.navigator.min_progress_m {
            self.failures += 1;
        } else {
            self.failures = 0;
        }
        self.plan_next(scan)
    }

    /// `[localiser] rectilinear`: the heading and the building's axes corrected by the scan's
    /// walls, a Kalman update of the two (the walls' direction in the robot frame is the axes
    /// less the heading); the first scan with walls sets the axes.
    fn square_up(&mut self, scan: &Scan) {
        let l = &self.params.localiser;
        if !l.rectilinear {
            return;
        }
        let r = l.rectilinear_sigma_deg.to_radians().powi(2);
        let p_hh = self.sigma_heading_rad.powi(2);
        // Walls are no truer than this: once the axes are set, they correct only a heading
        // known worse (and the scan is not fitted otherwise).
        if self.axes.is_some() && p_hh < r {
            return;
        }
        let walls = AxesParams {
            min_share: l.rectilinear_min_share,
            ..AxesParams::default()
        };
        let Some(walls) = localiser::wall_axes(&self.geometry, scan, &walls) else {
            return;
        };
        let seen = localiser::wrap_quarter_rad(walls.angle_rad + self.estimate.theta_rad);
        let Some(axes) = self.axes else {
            self.axes = Some(Axes {
                angle_rad: seen,
                var_rad2: p_hh + r,
                cov_heading_rad2: p_hh,
            });
            // The axes are the heading plus the walls' own error.
            self.position_cov.axes = self.position_cov.heading;
            return;
        };
        let off = localiser::wrap_quarter_rad(seen - axes.angle_rad);
        let p_aa = axes.var_rad2;
        let p_ha = axes.heading_cov_rad2(p_hh);
        let innovation_var = p_hh + p_aa - 2.0 * p_ha + r;
        let gate = (l.rectilinear_gate_sigmas * innovation_var.sqrt())
            .min(l.rectilinear_max_deg.to_radians());
        if off.abs() > gate {
            tracing::debug!(
                off_deg = off.to_degrees(),
                gate_deg = gate.to_degrees(),
                "walls off the building's axes; heading kept"
            );
            return;
        }
        // Gains of the heading and the axes for the innovation `off`.
        let k_h = (p_ha - p_hh) / innovation_var;
        let k_a = (p_aa - p_ha) / innovation_var;
        tracing::debug!(
            off_deg = off.to_degrees(),
            correction_deg = (k_h * off).to_degrees(),
            walls = walls.points,
            "heading squared up to the building's axes"
        );
        self.estimate.theta_rad =
            scan_types::normalize_angle_rad(self.estimate.theta_rad + k_h * off);
        // (I - K H) P with H = [-1, 1].
        let new_hh = p_hh + k_h * (p_hh - p_ha);
        let new_ha = p_ha + k_h * (p_ha - p_aa);
        let new_aa = p_aa - k_a * (p_aa - p_ha);
        let gain = self
            .position_cov
            .wall_update(p_hh, p_ha, p_aa, innovation_var);
        if l.rectilinear_moves_position {
            self.estimate.x_m += gain[0] * off;
            self.estimate.y_m += gain[1] * off;
        }
        self.sigma_heading_rad = new_hh.max(0.0).sqrt();
        self.axes = Some(Axes {
            angle_rad: localiser::wrap_quarter_rad(axes.angle_rad + k_a * off),
            var_rad2: new_aa.max(0.0),
            cov_heading_rad2: new_ha,
        });
    }

    /// `[localiser] revisit`: corrects the estimate by the earlier leg ends near it, and keeps
    /// this one.
    fn revisit(&mut self, scan: &Scan) {
        let sigma = (self.sigma_position_m, self.sigma_heading_rad);
        if let Some(c) = self.revisits.correct(
            &self.params.localiser,
            &self.geometry,
            self.legs,
            scan,
            self.estimate,
            sigma,
        ) {
            // The drift grew since the later of the matched leg end and the last correction:
            // the leg ends in between move with it, and the map is drawn again from them.
            let from = c.anchor_leg.max(self.last_revisit_leg);
            self.revisits
                .distribute(from, self.legs, self.estimate, c.pose);
            self.estimate = c.pose;
            self.sigma_position_m = c.sigma_m;
            self.sigma_heading_rad = c.sigma_heading_rad;
            // The position now rests on the matched leg end, not on the legs since.
            self.position_cov = PositionCov::default();
            self.last_revisit_leg = self.legs;
            self.grid = self
                .revisits
                .grid(self.params.localiser.map_resolution_m, &self.geometry);
        }
        let sigma = (self.sigma_position_m, self.sigma_heading_rad);
        self.revisits.add(self.legs, self.estimate, scan, sigma);
    }

    /// Places `scan` by the online SLAM with the search centred on `prediction`; the placed
    /// pose, or `None` when SLAM is off or could not place the scan.
    fn slam_place(&mut self, scan: &Scan, prediction: Pose2) -> Option<Pose2> {
        let front = self.slam.as_mut()?;
        let placed = front.locate_near(&self.geometry, scan, prediction);
        let accepted = self.slam_accepts(placed, prediction);
        // The submap takes the scan where the estimate puts it, so it stays in the estimate's
        // frame whether or not the placement was taken.
        if let Some(front) = self.slam.as_mut() {
            front.insert_at(&self.geometry, scan, accepted.unwrap_or(prediction));
        }
        accepted
    }

    /// The pose of `placed` when it may become the estimate: refined, its data pinning the
    /// position to `slam_max_sigma_m`.
    fn slam_accepts(&self, placed: slam::Placement, prediction: Pose2) -> Option<Pose2> {
        let l = &self.params.localiser;
        if let slam::Placement::Placed { pose, .. } = placed {
            // Never farther than the search window and the refinement's largest shift.
            let shift = pose.position().distance_m(&prediction.position());
            let turn = scan_types::angle_diff_rad(pose.theta_rad, prediction.theta_rad).abs();
            let refine_m = slam::FrontEndParams::default().max_refine_shift_m;
            if shift > l.slam_window_m * std::f64::consts::SQRT_2 + refine_m
                || turn > (l.slam_window_deg + SLAM_REFINE_TURN_DEG).to_radians()
            {
                tracing::debug!(shift, turn, "slam placement outside its window; refused");
                return None;
            }
        }
        match placed {
            slam::Placement::Placed {
                pose,
                quality,
                sigma_m,
                ..
            } if sigma_m.map_or(!self.params.localiser.slam_refined_only, |s| {
                s <= self.params.localiser.slam_max_sigma_m
            }) =>
            {
                tracing::debug!(
                    dx = pose.x_m - prediction.x_m,
                    dy = pose.y_m - prediction.y_m,
                    dth_deg = scan_types::angle_diff_rad(pose.theta_rad, prediction.theta_rad)
                        .to_degrees(),
                    quality,
                    sigma_m,
                    "slam placed the scan"
                );
                Some(pose)
            }
            slam::Placement::Placed { sigma_m, .. } => {
                tracing::debug!(
                    sigma_m,
                    "slam's placement is unrefined or loose; keeping the rules' pose"
                );
                None
            }
            slam::Placement::Skipped { reason } => {
                tracing::debug!(%reason, "slam could not place the scan; keeping the rules' pose");
                None
            }
        }
    }

    /// Places a scan taken while driving, `commanded_m` into the leg: predicted from the
    /// last placed pose and the travel commanded since.
    fn slam_drive_scan(&mut self, scan: &Scan, commanded_m: f64) -> Option<Pose2> {
        let (anchor, at) = self.slam_anchor;
        let prediction = anchor.compose(&Pose2::new(commanded_m - at, 0.0, 0.0));
        let placed = self.slam_place(scan, prediction);
        self.slam_anchor = (placed.unwrap_or(prediction), commanded_m);
        self.slam_leg_pose = placed.map(|p| (p, commanded_m));
        placed
    }

    /// Counts a leg on which the laser saw less than `stall_share` of the commanded travel;
    /// `stall_legs` of them in a row end the run as base_stalled.
    /// `(laser_measured, commanded_m)` are the drive's.
    fn check_stall(
        &mut self,
        (laser_measured, commanded_m): (bool, f64),
        moved_m: f64,
    ) -> Option<Action> {
        let n = &self.params.navigator;
        let judged = laser_measured && commanded_m >= STALL_JUDGED_M;
        if !(judged && moved_m < n.stall_share * commanded_m) {
            self.stalled_legs = 0;
            return None;
        }
        self.stalled_legs += 1;
        tracing::warn!(
            commanded_m,
            measured_m = moved_m,
            stalled_legs = self.stalled_legs,
            "the laser saw the robot not move as commanded"
        );
        (self.stalled_legs >= n.stall_legs).then(|| {
            let note = format!(
                "the base was told to drive {:.2} m and the laser measured {:.2} m, {} legs in a row",
                commanded_m, moved_m, self.stalled_legs
            );
            self.finish(Reason::BaseStalled, note)
        })
    }

    /// A landmark to measure travel by on a leg without a goal landmark: the nearest stable
    /// feature anywhere in the field of view.
    fn any_landmark(&self, scan: &Scan) -> Option<Landmark> {
        let found = detect(&self.geometry, scan, &self.detect_params);
        let all = SelectParams {
            max_bearing_rad: std::f64::consts::PI,
            min_ahead_m: f64::NEG_INFINITY,
            ..self.select_params
        };
        select(&found, &all)
    }

    /// Cuts each ray's clearance where the disc of radius `r` around a hit seen earlier from
    /// this spot, now outside the field of view, enters it, then remembers the hits of
    /// `scan`. Without it a turn in place forgets an obstacle right behind the robot and the
    /// next plan turns back into it.
    fn block_by_spot_hits(&mut self, scan: &Scan, r: f64) {
        let here = self.estimate.position();
        if here.distance_m(&self.spot.0) > 1e-9 {
            self.spot = (here, Vec::new());
        }
        block_by_unseen_hits(
            &self.geometry,
            &self.estimate,
            &self.spot.1,
            r,
            &mut self.clearances,
        );
        // Only hits that can block a leg.
        let reach = r + self.params.planner.max_leg_m;
        let estimate = self.estimate;
        self.spot.1.extend(
            scan.robot_hits(&self.geometry)
                .filter(|(_, p)| p.range_m() <= reach)
                .map(|(_, p)| estimate.transform_point(p)),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::PositionCov;

    #[test]
    fn the_position_gain_follows_the_kalman_filter_by_hand() {
        // Heading and axes in units of the first turn's variance (q = 1); walls of variance
        // r. At the start the heading is exact and the walls set the axes: p_aa = r, no
        // covariance. A turn makes p_hh = 1; the walls' update (S = 1 + 2r) leaves
        // h1 = 2r / (1 + 2r), c1 = r / (1 + 2r) with the axes, a1 = r (1 + r) / (1 + 2r).
        let r: f64 = 0.5625;
        let (h1, c1, a1) = (
            2.0 * r / (1.0 + 2.0 * r),
            r / (1.0 + 2.0 * r),
            r * (1.0 + r) / (1.0 + 2.0 * r),
        );
        let mut cov = PositionCov::default();
        // Nothing driven yet: the first update moves no position.
        assert_eq!(cov.wall_update(1.0, 0.0, r, 1.0 + 2.0 * r), [0.0, 0.0]);
        // A 2 m leg along +x: its end moves along +y by 2 per unit of heading error.
        cov.leg(2.0, 0.0, h1, c1);
        assert_eq!(cov.heading, [0.0, 2.0 * h1]);
        assert_eq!(cov.axes, [0.0, 2.0 * c1]);
        // The next turn adds 1 to the heading's variance alone; the walls then give the
        // position the gain (P_pa - P_ph) / S = 2 (c1 - h1) / S = -2 c1 / S along y.
        let p_hh = h1 + 1.0;
        let s = p_hh + a1 - 2.0 * c1 + r;
        let gain = cov.wall_update(p_hh, c1, a1, s);
        let k_y = -2.0 * c1 / s;
        assert_eq!(gain[0], 0.0);
        assert!((gain[1] - k_y).abs() < 1e-12, "{} vs {k_y}", gain[1]);
        // Per radian the heading moves by k_h = (c1 - p_hh) / S: the position by
        // 2 c1 / (p_hh - c1) = 0.4186 m per radian, not the 2 h1 / p_hh = 0.6923 m of a
        // position correlated with the axes only through the heading.
        let k_h = (c1 - p_hh) / s;
        assert!((gain[1] / k_h - 0.4186).abs() < 1e-4, "{}", gain[1] / k_h);
        // (I - K H) P: with r = 9/16, h1 = 9/17, c1 = 9/34, a1 = 225/544 and p_hh = 26/17,
        // the covariances after the update are 0.72 (heading) and 0.569302 (axes).
        assert!((cov.heading[1] - 0.72).abs() < 1e-6, "{}", cov.heading[1]);
        assert!((cov.axes[1] - 0.569302).abs() < 1e-6, "{}", cov.axes[1]);
    }
}
