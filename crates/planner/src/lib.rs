//! Path choice for goal seeking: which ray to follow toward the target, the rotation alpha
//! and the safe travel distance along it.
//!
//! A ray is **safe** when its clearance after obstacle expansion (the `expansion` crate, with
//! the robot radius plus a margin) is at least [`PlannerParams::min_travel_m`]; the leg along it
//! is its clearance capped at [`PlannerParams::max_travel_m`], and its **safe end** is the point
//! that far along it. Among the safe rays:
//!
//! - when the target is in view and the ray toward it is clear all the way, head straight for it;
//! - [`PlanRule::Greedy`] (the paper): the ray whose safe end lies closest to the target
//!   (straight-line distance; see `docs/planner.md` for why not the bearing);
//! - [`PlanRule::MapPath`] (default): the ray whose safe end has the shortest path to the target
//!   over the planner's own obstacle memory ([`Planner::add_scan`]; unknown space is free).
//!
//! When no ray is safe the plan is [`Plan::NoSafeRay`] (turn and rescan); after
//! [`PlannerParams::max_no_safe_tries`] of those in a row, [`Plan::Unreachable`].
//!
//! ```
//! use planner::{Plan, Planner, PlannerParams};
//! use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};
//! // Open space: the target 2 m ahead and 30 deg to the left is in view and reachable.
//! let g = ScanGeometry::paper();
//! let scan = Scan::from_ranges(&g, &vec![4.0; g.ray_count], 0.0);
//! let clearance = vec![4.0; g.ray_count];
//! let pose = Pose2::new(0.0, 0.0, 0.0);
//! let a = 30f64.to_radians();
//! let target = WorldPoint::new(2.0 * a.cos(), 2.0 * a.sin());
//! let mut planner = Planner::new(PlannerParams::default());
//! match planner.plan(&pose, &g, &scan, &clearance, target) {
//!     Plan::Go { alpha_rad, travel_m, target_in_view, .. } => {
//!         assert!((alpha_rad - a).abs() < 1e-9);
//!         assert!((travel_m - 2.0).abs() < 1e-9);
//!         assert!(target_in_view);
//!     }
//!     other => panic!("{other:?}"),
//! }
//! ```

mod error;
mod map;

pub use error::PlannerError;
pub use map::{BAND_FACTOR, MAX_CELLS, ObstacleMemory, TARGET_CELLS};

use scan_types::{
    Pose2, RobotPoint, Scan, ScanGeometry, WorldPoint, angle_diff_rad, normalize_angle_rad,
};

/// How the planner ranks the safe rays.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PlanRule {
    /// The paper: the safe ray whose safe end lies closest to the target.
    Greedy,
    /// goalseek: the safe ray whose safe end has the shortest path to the target over the
    /// map built so far (unknown = free).
    #[default]
    MapPath,
}

/// The planner's parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannerParams {
    /// Ray ranking rule.
    pub rule: PlanRule,
    /// Robot radius r, metres (inflates the planner's obstacle memory).
    pub robot_radius_m: f64,
    /// Safety margin added to r in the obstacle memory, metres (the caller expands the scan by
    /// r + margin too: 0.1 m was collision-free in the prototype).
    pub margin_m: f64,
    /// Shortest clear stretch that makes a ray safe, metres.
    pub min_travel_m: f64,
    /// Travel cap: the longest leg the planner proposes, metres.
    pub max_travel_m: f64,
    /// The target counts as reachable in view when the ray toward it is clear to within this
    /// distance of it, metres.
    pub target_tolerance_m: f64,
    /// Consecutive plans without a safe ray (or, for MapPath, without any path to the target
    /// on the map) after which the target is reported unreachable.
    pub max_no_safe_tries: usize,
    /// Cell size of the obstacle memory, metres.
    pub grid_resolution_m: f64,
    /// Graded clearance (MapPath only, when below `margin_m`): a passage at least
    /// 2 (r + `narrow_margin_m`) wide is accepted; the full margin is kept wherever there is
    /// room, metres.
    pub narrow_margin_m: f64,
    /// MapPath only: a safe end from which the target is in line of sight on the memory is
    /// ranked by its straight-line distance, not its grid path (whose 8 directions would pick
    /// a ray up to 22.5 deg off the target's bearing in the open).
    pub line_of_sight: bool,
    /// Graded clearance only: a gap the field's path crosses in the band is measured on the
    /// scan and closed when narrower than [`PlannerParams::narrowest_m`], as a narrow leg's is.
    pub measure_path_gaps: bool,
}

impl Default for PlannerParams {
    /// goalseek defaults: MapPath, r = 0.3 m + 0.1 m margin (0.025 m in a narrow passage),
    /// legs 0.3 .. 2.0 m, 0.1 m cells, 12 tries (a full turn in 30 deg steps) before giving up.
    fn default() -> Self {
        Self {
            rule: PlanRule::MapPath,
            robot_radius_m: 0.3,
            margin_m: 0.1,
            min_travel_m: 0.3,
            max_travel_m: 2.0,
            target_tolerance_m: 0.1,
            max_no_safe_tries: 12,
            grid_resolution_m: 0.1,
            narrow_margin_m: 0.025,
            line_of_sight: true,
            measure_path_gaps: true,
        }
    }
}

impl PlannerParams {
    /// The paper's rule with otherwise default parameters.
    pub fn paper() -> Self {
        Self {
            rule: PlanRule::Greedy,
            ..Self::default()
        }
    }

    /// True when narrow passages are planned with the smaller margin.
    pub fn graded(&self) -> bool {
        self.rule == PlanRule::MapPath && self.narrow_margin_m < self.margin_m
    }

    /// Radius of the ray test of a narrow candidate: r itself (its passage's measured width
    /// and the check after the turn keep the margin), metres.
    pub fn narrow_radius_m(&self) -> f64 {
        self.robot_radius_m
    }

    /// The narrowest passage a narrow leg takes, as measured on one scan: 2 (r +
    /// `narrow_margin_m`) less a 0.02 m allowance for range noise, metres.
    pub fn narrowest_m(&self) -> f64 {
        2.0 * (self.robot_radius_m + self.narrow_margin_m) - WIDTH_ALLOWANCE_M
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlannerError> {
        let bad = |field, value, why| Err(PlannerError::InvalidParam { field, value, why });
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
        if !nonneg(self.narrow_margin_m) {
            return bad("narrow_margin_m", self.narrow_margin_m, "finite and >= 0");
        }
        if !nonneg(self.robot_radius_m) {
            return bad("robot_radius_m", self.robot_radius_m, "finite and >= 0");
        }
        if !nonneg(self.margin_m) {
            return bad("margin_m", self.margin_m, "finite and >= 0");
        }
        if !nonneg(self.min_travel_m) {
            return bad("min_travel_m", self.min_travel_m, "finite and >= 0");
        }
        if !(self.max_travel_m.is_finite() && self.max_travel_m >= self.min_travel_m) {
            return bad(
                "max_travel_m",
                self.max_travel_m,
                "finite and >= min_travel_m",
            );
        }
        if !nonneg(self.target_tolerance_m) {
            return bad(
                "target_tolerance_m",
                self.target_tolerance_m,
                "finite and >= 0",
            );
        }
        if !(self.grid_resolution_m.is_finite() && self.grid_resolution_m >= 0.01) {
            return bad(
                "grid_resolution_m",
                self.grid_resolution_m,
                "finite and >= 0.01",
            );
        }
        Ok(())
    }
}

/// What the robot should do next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Plan {
    /// Rotate in place by `alpha_rad` (counter-clockwise positive) so that the central ray
    /// points along ray `ray_index`, then drive at most `travel_m`.
    Go {
        /// The chosen ray.
        ray_index: usize,
        /// Rotation to apply, radians, in (-pi, pi].
        alpha_rad: f64,
        /// Safe travel distance along the new heading, metres.
        travel_m: f64,
        /// True when heading straight for the target (in view and reachable).
        target_in_view: bool,
        /// Set when the leg takes a narrow passage (inside the full margin).
        narrow: Option<NarrowSpot>,
    },
    /// No ray is safe: turn and rescan.
    NoSafeRay,
    /// No safe ray after [`PlannerParams::max_no_safe_tries`] plans in a row, or (MapPath) no
    /// path to the target from any safe end on the map for as many plans in a row: give up.
    Unreachable {
        /// Consecutive tries without a safe ray.
        tries: usize,
    },
}

/// A passage measured this much wider than the full margin needs is never taken narrow, metres.
const WIDE_ALLOWANCE_M: f64 = 0.1;
/// Range noise allowed for when a passage's width is measured on one scan, metres.
const WIDTH_ALLOWANCE_M: f64 = 0.02;
/// How much shorter (path cost) a way through narrow passages must be than the way with the
/// full margin to be taken, metres.
const GRADED_GAIN_M: f64 = 1.0;
/// Plans that must measure a gap too narrow before it is closed on the map.
pub const GAP_VERDICTS: usize = 3;
/// Two measured gap middles closer than this are the same gap, metres.
const GAP_SAME_M: f64 = 0.25;
/// How far along the field's path from the robot gaps are measured on the scan, metres.
const PINCH_LOOK_M: f64 = 2.0;
/// The nearest hits on either side of a gap's middle lie across it: the cosine of the angle
/// between them, seen from there, is below this (about 154 deg).
const PINCH_ACROSS_COS: f64 = -0.9;

/// The tightest spot of a leg through a narrow passage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NarrowSpot {
    /// Where along the leg the robot's centre passes closest to a hit (world frame).
    pub at: WorldPoint,
    /// Distance from there to that hit, metres (half the passage's width when centred).
    pub clearance_m: f64,
    /// The passage's narrowest width across the leg, metres.
    pub width_m: f64,
    /// True when the leg passes through the passage's narrowest cross-section (false: it
    /// only approaches it, inside the full margin).
    pub through: bool,
}

/// A ranked candidate leg: score, ray, travel, and for a narrow leg its tightest spot (robot
/// frame, as `band_cost` gives it).
#[derive(Debug, Clone, Copy)]
struct Candidate {
    score: f64,
    ray: usize,
    travel: f64,
    narrow: Option<NarrowSpot>,
}

/// The rest of a leg judged on the memory as it is now ([`Planner::check_leg`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LegCheck {
    /// How far along the leg the robot stays out of the lethal core of remembered
    /// obstacles, metres (the leg's length when nothing blocks it).
    pub free_m: f64,
    /// Path length from the leg's start to the target, metres (`None`: no path).
    pub from_start_m: Option<f64>,
    /// Path length from the leg's end to the target, metres (`None`: no path).
    pub from_end_m: Option<f64>,
}

/// Chooses rays toward a target; remembers obstacles for [`PlanRule::MapPath`].
#[derive(Debug, Clone)]
pub struct Planner {
    params: PlannerParams,
    memory: ObstacleMemory,
    no_safe_tries: usize,
    no_path_tries: usize,
    /// Scratch: every safe leg.
    candidates: Vec<Candidate>,
    /// Scratch: the hits of the scan narrow passages are judged on, robot frame.
    narrow_hits: Vec<[f64; 2]>,
    /// Gaps measured too narrow (middle, world frame) and in how many plans.
    gaps: Vec<(WorldPoint, usize)>,
    /// Gaps measured wide enough at least once: never closed.
    open_gaps: Vec<WorldPoint>,
    /// Whether this plan's field passes through the band (the full margin found no way).
    through_band: bool,
    /// Scratch: the hits added for one check.
    scratch_hits: Vec<WorldPoint>,
}

impl Planner {
    /// A planner with an empty obstacle memory. Out-of-domain parameters are clamped to the
    /// nearest valid value (use [`PlannerParams::validate`] to report them instead).
    pub fn new(params: PlannerParams) -> Self {
        let mut p = params;
        let fix = |v: f64, lo: f64| if v.is_finite() { v.max(lo) } else { lo };
        p.robot_radius_m = fix(p.robot_radius_m, 0.0);
        p.margin_m = fix(p.margin_m, 0.0);
        p.min_travel_m = fix(p.min_travel_m, 0.0);
        p.max_travel_m = fix(p.max_travel_m, p.min_travel_m);
        p.target_tolerance_m = fix(p.target_tolerance_m, 0.0);
        p.grid_resolution_m = fix(p.grid_resolution_m, 0.01);
        p.narrow_margin_m = fix(p.narrow_margin_m, 0.0);
        // Shrunk by one cell, so that a safe end right at the edge of an expanded obstacle
        // does not fall into a blocked cell.
        let inflate = |m: f64| (p.robot_radius_m + m - p.grid_resolution_m).max(0.0);
        let memory = if p.graded() {
            ObstacleMemory::graded(
                p.grid_resolution_m,
                inflate(p.narrow_margin_m),
                inflate(p.margin_m),
            )
        } else {
            ObstacleMemory::new(p.grid_resolution_m, inflate(p.margin_m))
        };
        Self {
            memory,
            params: p,
            no_safe_tries: 0,
            no_path_tries: 0,
            candidates: Vec::new(),
            narrow_hits: Vec::new(),
            gaps: Vec::new(),
            open_gaps: Vec::new(),
            through_band: false,
            scratch_hits: Vec::new(),
        }
    }

    /// The parameters in use.
    pub fn params(&self) -> &PlannerParams {
        &self.params
    }

    /// The obstacle memory built by [`Planner::add_scan`].
    pub fn memory(&self) -> &ObstacleMemory {
        &self.memory
    }

    /// Consecutive [`Plan::NoSafeRay`] answers so far (reset by every [`Plan::Go`]); the
    /// planner answers [`Plan::Unreachable`] when it reaches
    /// [`PlannerParams::max_no_safe_tries`].
    pub fn no_safe_tries(&self) -> usize {
        self.no_safe_tries
    }

    /// Remembers the hits of a scan taken at `pose` (world frame).
    pub fn add_scan(&mut self, pose: &Pose2, geometry: &ScanGeometry, scan: &Scan) {
        self.memory.ensure_contains(pose.position());
        let n = geometry.ray_count.min(scan.len());
        let dirs = geometry.directions();
        for i in 0..n {
            if let Some(r) = scan.hit_range_m(i).filter(|r| r.is_finite() && *r >= 0.0) {
                self.memory
                    .add_hit(pose.transform_point(RobotPoint::new(r * dirs[i][0], r * dirs[i][1])));
            }
        }
    }

    /// Judges the leg of `length_m` straight ahead of `from` on the memory as it is now: where
    /// a remembered obstacle's lethal core blocks it, and the path lengths to `target` from
    /// its start and its end over the field of the last plan's kind (through the band or
    /// not), recomputed only when the memory or the target changed.
    pub fn check_leg(&mut self, from: &Pose2, length_m: f64, target: WorldPoint) -> LegCheck {
        let length_m = if length_m.is_finite() {
            length_m.max(0.0)
        } else {
            0.0
        };
        let free_m = self.memory_cap_m(from, 0.0, length_m, true);
        self.memory.ensure_contains(from.position());
        self.memory.update_field_through(target, self.through_band);
        let end = from.advanced(length_m).position();
        LegCheck {
            free_m,
            from_start_m: self.memory.path_length_m(from.position()),
            from_end_m: self.memory.path_length_m(end),
        }
    }

    /// How far straight ahead of `from` a full-margin leg stays out of remembered obstacles
    /// (their band included), up to `length_m` and the longest leg, metres; 0 for a length
    /// that is not finite and positive.
    ///
    /// A leg that starts within an obstacle's inflation is free until it leaves it, as in
    /// [`Planner::check_leg`].
    pub fn free_ahead_m(&self, from: &Pose2, length_m: f64) -> f64 {
        if !(length_m.is_finite() && length_m > 0.0) {
            return 0.0;
        }
        let length_m = length_m.min(self.params.max_travel_m);
        self.memory_cap_m(from, 0.0, length_m, false)
    }

    /// [`Planner::check_leg`] on the memory with the hits of `scan`, taken at `from`, added for
    /// the check only (the memory is left as it was: a scan taken while driving, not yet
    /// localised, is not remembered); `None` when the scan occupies no new cell (nothing new
    /// to judge on).
    pub fn check_leg_with_scan(
        &mut self,
        from: &Pose2,
        geometry: &ScanGeometry,
        scan: &Scan,
        length_m: f64,
        target: WorldPoint,
    ) -> Option<LegCheck> {
        self.memory.ensure_contains(from.position());
        let n = geometry.ray_count.min(scan.len());
        let dirs = geometry.directions();
        let mut added = std::mem::take(&mut self.scratch_hits);
        added.clear();
        let mut new = false;
        for i in 0..n {
            if let Some(r) = scan.hit_range_m(i).filter(|r| r.is_finite() && *r >= 0.0) {
                let p = from.transform_point(RobotPoint::new(r * dirs[i][0], r * dirs[i][1]));
                if let Some(fresh) = self.memory.count_hit(p) {
                    new |= fresh;
                    added.push(p);
                }
            }
        }
        let check = new.then(|| self.check_leg(from, length_m, target));
        for &p in &added {
            self.memory.uncount_hit(p);
        }
        self.scratch_hits = added;
        check
    }

    /// Chooses the next ray from `pose` toward `target`, given the clearance of every ray of
    /// `scan` after expansion by the robot radius plus the margin.
    pub fn plan(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        scan: &Scan,
        clearances_m: &[f64],
        target: WorldPoint,
    ) -> Plan {
        self.plan_graded(pose, geometry, scan, clearances_m, None, target)
    }

    /// [`Planner::plan`] that may also take a narrow passage: `narrow` is the scan to judge
    /// passages on (denoised) and every ray's clearance in it after expansion by
    /// [`PlannerParams::narrow_radius_m`] (used only when [`PlannerParams::graded`]). A narrow
    /// leg needs a passage at least [`PlannerParams::narrowest_m`] wide; it is ranked by its
    /// end's path cost plus the cost of its own stretch inside the full margin, so the middle
    /// of a passage wins.
    pub fn plan_graded(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        scan: &Scan,
        clearances_m: &[f64],
        narrow: Option<(&Scan, &[f64])>,
        target: WorldPoint,
    ) -> Plan {
        let n = geometry.ray_count.min(clearances_m.len()).min(scan.len());
        let narrow = narrow.filter(|(s, c)| self.params.graded() && c.len() >= n && s.len() >= n);
        self.narrow_hits = narrow.map_or_else(Vec::new, |(s, _)| robot_hits(geometry, s));
        let narrow_m = narrow.map(|(_, c)| c);
        let any_narrow = narrow_m.is_some_and(|c| (0..n).any(|i| self.leg(c, i).is_some()));
        if !any_narrow && !(0..n).any(|i| self.leg(clearances_m, i).is_some()) {
            self.no_safe_tries += 1;
            tracing::debug!(tries = self.no_safe_tries, "no safe ray");
            if self.no_safe_tries >= self.params.max_no_safe_tries {
                return Plan::Unreachable {
                    tries: self.no_safe_tries,
                };
            }
            return Plan::NoSafeRay;
        }

        // Straight for the target when it is in view and the ray toward it is clear.
        let local = pose.inverse_transform_point(target);
        let (t_range, t_bearing) = (local.range_m(), local.bearing_rad());
        if let Some(plan) = self.straight_for_target(geometry, clearances_m, n, t_range, t_bearing)
        {
            self.no_safe_tries = 0;
            return plan;
        }

        let map_path =
            match self.map_path_usable(pose, geometry, (clearances_m, narrow_m), n, target) {
                Ok(usable) => usable,
                Err(unreachable) => return unreachable,
            };
        self.rank_candidates(pose, geometry, clearances_m, (n, target), map_path);
        if map_path && self.params.line_of_sight {
            self.rank_in_sight(pose, geometry, target);
        }
        if let (Some(narrow), true) = (narrow_m, map_path && self.through_band) {
            self.rank_narrow(pose, geometry, (clearances_m, narrow), n);
        }
        // Best score first; ties go to the ray nearer the target's bearing, then the longer leg.
        let order = |a: &Candidate, b: &Candidate| {
            a.score.total_cmp(&b.score).then_with(|| {
                tie_key(geometry, a.ray, a.travel, t_bearing)
                    .cmp(&tie_key(geometry, b.ray, b.travel, t_bearing))
            })
        };
        // The scan cannot see obstacles just outside its field of view: a leg is also cut
        // where it enters an obstacle remembered from earlier scans.
        // Usually the best candidate passes: try it (the first of equal ones, as a stable sort
        // puts first) before sorting them all.
        let best = self.candidates.iter().copied().min_by(order);
        let mut plan = best.and_then(|c| self.go_if_long_enough(pose, geometry, c));
        if plan.is_none() {
            self.candidates.sort_by(order);
            plan = self
                .candidates
                .iter()
                .find_map(|&c| self.go_if_long_enough(pose, geometry, c));
        }
        if let Some(plan) = plan {
            self.no_safe_tries = 0;
            return plan;
        }
        self.no_safe_tries += 1;
        if self.no_safe_tries >= self.params.max_no_safe_tries {
            return Plan::Unreachable {
                tries: self.no_safe_tries,
            };
        }
        Plan::NoSafeRay
    }

    /// The safe travel along ray `i`, if it has one.
    fn leg(&self, clearances_m: &[f64], i: usize) -> Option<f64> {
        let p = &self.params;
        let c = clearances_m[i];
        (c.is_finite() && c >= p.min_travel_m && c > 0.0).then(|| c.min(p.max_travel_m))
    }

    /// Whether to rank by path length on the map ([`PlanRule::MapPath`] with a path from some
    /// safe end); `Err` when the map has cut the target off for too many plans in a row.
    fn map_path_usable(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        (clearances_m, narrow_m): (&[f64], Option<&[f64]>),
        n: usize,
        target: WorldPoint,
    ) -> Result<bool, Plan> {
        if self.params.rule != PlanRule::MapPath {
            return Ok(false);
        }
        self.memory.ensure_contains(pose.position());
        let reaches = |me: &Self, c: &[f64], narrow: bool| {
            (0..n)
                .filter_map(|i| me.leg(c, i).map(|t| (i, t)))
                .any(|(i, t)| {
                    let end = pose.transform_point(geometry.robot_point(i, t));
                    // A narrow leg must not cross what the memory holds (a closed gap).
                    me.memory.path_length_m(end).is_some()
                        && (!narrow || me.memory_cap_m(pose, geometry.bearing_rad(i), t, true) >= t)
                })
        };
        // The way with the full margin, unless narrow passages shorten it by more than
        // GRADED_GAIN_M (a door instead of a detour through the unknown).
        let best = |me: &Self, c: &[f64]| {
            (0..n)
                .filter_map(|i| me.leg(c, i).map(|t| (i, t)))
                .filter_map(|(i, t)| {
                    me.memory
                        .path_length_m(pose.transform_point(geometry.robot_point(i, t)))
                        .map(|d| d + t)
                })
                .fold(f64::INFINITY, f64::min)
        };
        let mut graded = None;
        if let Some(narrow) = narrow_m {
            self.memory.update_field_through(target, true);
            if reaches(self, clearances_m, false) || reaches(self, narrow, true) {
                graded = Some(best(self, clearances_m).min(best(self, narrow)));
            }
        }
        self.memory.update_field_through(target, false);
        self.through_band = false;
        let mut reachable = reaches(self, clearances_m, false);
        let full = if reachable {
            best(self, clearances_m)
        } else {
            f64::INFINITY
        };
        if let Some(g) = graded
            && g + GRADED_GAIN_M < full
        {
            self.memory.update_field_through(target, true);
            self.through_band = true;
            reachable = true;
        }
        if reachable {
            self.no_path_tries = 0;
            return Ok(true);
        }
        // Every safe end is cut off from the target on the map: walled in, or a spurious
        // closure; rank by straight-line distance meanwhile.
        self.no_path_tries += 1;
        tracing::debug!(
            tries = self.no_path_tries,
            "no path to the target on the map"
        );
        if self.no_path_tries >= self.params.max_no_safe_tries {
            return Err(Plan::Unreachable {
                tries: self.no_path_tries,
            });
        }
        Ok(false)
    }

    /// Fills the candidates with (score, ray, travel) of every safe ray: the path length from
    /// its end on the map, or the straight-line distance to the target.
    fn rank_candidates(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        clearances_m: &[f64],
        (n, target): (usize, WorldPoint),
        map_path: bool,
    ) {
        self.candidates.clear();
        let dirs = geometry.directions();
        for i in 0..n {
            let Some(travel) = self.leg(clearances_m, i) else {
                continue;
            };
            let end =
                pose.transform_point(RobotPoint::new(travel * dirs[i][0], travel * dirs[i][1]));
            let score = if map_path {
                self.memory.path_length_m(end).unwrap_or(f64::INFINITY)
            } else {
                end.distance_m(&target)
            };
            self.candidates.push(Candidate {
                score,
                ray: i,
                travel,
                narrow: None,
            });
        }
    }

    /// Ranks the candidates whose safe end sees the target on the memory by their straight-line
    /// distance to it, nearest first, as long as that can beat the best score.
    fn rank_in_sight(&mut self, pose: &Pose2, geometry: &ScanGeometry, target: WorldPoint) {
        let dirs = geometry.directions();
        let end = |c: &Candidate| {
            let u = dirs[c.ray];
            pose.transform_point(RobotPoint::new(c.travel * u[0], c.travel * u[1]))
        };
        let mut order: Vec<(f64, usize, WorldPoint)> = self
            .candidates
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let e = end(c);
                (e.distance_m(&target), k, e)
            })
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut best = self
            .candidates
            .iter()
            .map(|c| c.score)
            .fold(f64::INFINITY, f64::min);
        for (straight, k, e) in order {
            if straight >= best {
                break;
            }
            if let Some(d) = self.memory.line_of_sight_m(e) {
                self.candidates[k].score = d;
                best = best.min(d);
            }
        }
    }

    /// Adds the narrow legs: rays whose narrow clearance reaches clearly farther than their
    /// full one, scored by their end's path cost plus the band cost of their own stretch.
    fn rank_narrow(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        (full, narrow): (&[f64], &[f64]),
        n: usize,
    ) {
        let dirs = geometry.directions();
        let (mut too_narrow, mut wide_enough) = (Vec::new(), Vec::new());
        let best_full = self
            .candidates
            .iter()
            .map(|c| c.score)
            .fold(f64::INFINITY, f64::min);
        // A narrow leg ends where the full margin holds again (as far from what stops it as a
        // full leg would), never right against an obstacle.
        let pull_back =
            self.params.margin_m + self.params.robot_radius_m - self.params.narrow_radius_m();
        for i in 0..n {
            let Some(travel) = self
                .leg(narrow, i)
                .map(|t| if narrow[i] <= t { t - pull_back } else { t })
                .filter(|&t| t >= self.params.min_travel_m)
            else {
                continue;
            };
            let full_travel = self.leg(full, i).unwrap_or(0.0);
            if travel < full_travel + self.params.grid_resolution_m {
                continue;
            }
            let end =
                pose.transform_point(RobotPoint::new(travel * dirs[i][0], travel * dirs[i][1]));
            // The band only adds cost: a leg no better than the best full one is not judged.
            let Some(to_go) = self.to_go_m(end).filter(|&c| c < best_full) else {
                continue;
            };
            let (band, spot, mid) = self.band_cost(dirs[i], travel);
            // A passage between obstacles on both sides (not a stretch along one wall), no
            // wider than the full margin needs: the narrow one is not for cutting corners.
            let p = &self.params;
            let widest = 2.0 * (p.robot_radius_m + p.margin_m) + WIDE_ALLOWANCE_M;
            if !spot.width_m.is_finite() || spot.width_m >= widest {
                continue;
            }
            if let Some(mid) = mid {
                let mid = pose.transform_point(RobotPoint::new(mid[0], mid[1]));
                if spot.width_m < self.params.narrowest_m() {
                    tracing::trace!(
                        width_m = spot.width_m,
                        x_m = mid.x_m(),
                        y_m = mid.y_m(),
                        "gap too narrow"
                    );
                    push_near(&mut too_narrow, mid);
                    continue;
                }
                tracing::trace!(
                    width_m = spot.width_m,
                    x_m = mid.x_m(),
                    y_m = mid.y_m(),
                    "gap wide enough"
                );
                push_near(&mut wide_enough, mid);
            }
            self.candidates.push(Candidate {
                score: to_go + band,
                ray: i,
                travel,
                narrow: Some(spot),
            });
        }
        // The field may also lead through a gap that no ray takes at all.
        if let Some(mid) = self
            .params
            .measure_path_gaps
            .then(|| self.pinch_on_path(pose))
            .flatten()
        {
            push_near(&mut too_narrow, mid);
        }
        self.judge_gaps(&too_narrow, &wide_enough);
    }

    /// The middle of a gap narrower than [`PlannerParams::narrowest_m`] that the field's path
    /// from the robot crosses within [`PINCH_LOOK_M`], measured on the scan where the path
    /// runs through the band: a gap the band's coarse cells leave open though the robot
    /// cannot pass it (no wider than 2 r, no ray reaches through it).
    fn pinch_on_path(&self, pose: &Pose2) -> Option<WorldPoint> {
        let p = &self.params;
        let reach = 2.0 * (p.robot_radius_m + p.margin_m);
        // The path from the robot, robot frame, with whether each point lies in the band.
        let path: Vec<(RobotPoint, bool)> = std::iter::once(pose.position())
            .chain(self.memory.descent(pose.position(), PINCH_LOOK_M))
            .map(|p| (pose.inverse_transform_point(p), self.memory.is_in_band(p)))
            .collect();
        for w in path.windows(2) {
            let ((a, _), (b, in_band)) = (w[0], w[1]);
            if !in_band {
                continue;
            }
            let (ux, uy) = (b.x_m() - a.x_m(), b.y_m() - a.y_m());
            let mut sides = Sides::default();
            for h in &self.narrow_hits {
                let (dx, dy) = (h[0] - b.x_m(), h[1] - b.y_m());
                let d = dx.hypot(dy);
                if d <= reach {
                    sides.add(*h, d, ux * dy - uy * dx > 0.0);
                }
            }
            let Sides([(right3, rh), (left3, lh)]) = sides;
            if !(left3[2].is_finite() && right3[2].is_finite()) {
                continue;
            }
            // The nearest hits on either side lie across the point (a gap), not both
            // toward one corner it rounds.
            let (l, r) = (
                [lh[0] - b.x_m(), lh[1] - b.y_m()],
                [rh[0] - b.x_m(), rh[1] - b.y_m()],
            );
            let across = (l[0] * r[0] + l[1] * r[1]) / (l[0].hypot(l[1]) * r[0].hypot(r[1]));
            let width = left3.iter().sum::<f64>() / 3.0 + right3.iter().sum::<f64>() / 3.0;
            if across < PINCH_ACROSS_COS && width < p.narrowest_m() {
                tracing::trace!(width_m = width, "gap on the path too narrow");
                let mid = RobotPoint::new((lh[0] + rh[0]) / 2.0, (lh[1] + rh[1]) / 2.0);
                return Some(pose.transform_point(mid));
            }
        }
        None
    }

    /// The path length from `end` to the target on the memory, metres: the smaller of the
    /// grid path and the line of sight when [`PlannerParams::line_of_sight`] is on.
    fn to_go_m(&self, end: WorldPoint) -> Option<f64> {
        let sight = if self.params.line_of_sight {
            self.memory.line_of_sight_m(end)
        } else {
            None
        };
        self.memory
            .path_length_m(end)
            .into_iter()
            .chain(sight)
            .reduce(f64::min)
    }

    /// Counts the plans in which a gap was measured too narrow (and never wide enough); after
    /// [`GAP_VERDICTS`] of them it is closed in the memory, so that the map can prove a target
    /// behind it unreachable.
    fn judge_gaps(&mut self, too_narrow: &[WorldPoint], wide_enough: &[WorldPoint]) {
        let same = |a: &WorldPoint, b: &WorldPoint| a.distance_m(b) < GAP_SAME_M;
        for g in wide_enough {
            self.gaps.retain(|(p, _)| !same(p, g));
            push_near(&mut self.open_gaps, *g);
        }
        for g in too_narrow {
            if self.open_gaps.iter().any(|p| same(p, g)) {
                continue;
            }
            match self.gaps.iter_mut().find(|(p, _)| same(p, g)) {
                Some((_, n)) => {
                    *n += 1;
                    if *n == GAP_VERDICTS {
                        tracing::info!(
                            x_m = g.x_m(),
                            y_m = g.y_m(),
                            plans = GAP_VERDICTS,
                            "passage too narrow; closed on the planner's map"
                        );
                        self.memory.add_hit(*g);
                    }
                }
                None => self.gaps.push((*g, 1)),
            }
        }
    }

    /// The extra cost of driving `travel` m along unit direction `u` (robot frame) inside the
    /// full margin of the narrow scan's hits: up to `BAND_FACTOR - 1` per metre at the
    /// narrow radius, falling linearly to 0 at the full radius; and the tightest spot
    /// (robot frame: `at` is the distance along `u` in its x) with the middle of the
    /// passage's narrowest cross-section (robot frame) when the leg passes through it.
    fn band_cost(&self, u: [f64; 2], travel: f64) -> (f64, NarrowSpot, Option<[f64; 2]>) {
        let p = &self.params;
        let (full_r, narrow_r) = (p.robot_radius_m + p.margin_m, p.narrow_radius_m());
        // Hits that can bound a passage the segment takes (up to twice the full radius from
        // it), with their side.
        let reach = 2.0 * full_r;
        let near: Vec<([f64; 2], bool)> = self
            .narrow_hits
            .iter()
            .filter_map(|h| {
                let along = h[0] * u[0] + h[1] * u[1];
                let side = h[1] * u[0] - h[0] * u[1];
                (side.abs() < reach && along > -reach && along < travel + reach)
                    .then_some((*h, side > 0.0))
            })
            .collect();
        let step = 0.02;
        let steps = (travel / step).ceil().max(1.0) as usize;
        let mut cost = 0.0;
        let mut spot = NarrowSpot {
            at: WorldPoint::new(0.0, 0.0),
            clearance_m: f64::INFINITY,
            width_m: f64::INFINITY,
            through: false,
        };
        let mut mid = [0.0; 2];
        let mut narrowest_at = 0.0;
        for s in 0..=steps {
            let t = (s as f64 * step).min(travel);
            let (x, y) = (t * u[0], t * u[1]);
            // Per side: the nearest hit, and the three nearest distances (their mean measures
            // the passage without the low bias that range noise gives the nearest alone).
            let mut sides = Sides::default();
            for (h, is_left) in &near {
                sides.add(*h, (h[0] - x).hypot(h[1] - y), *is_left);
            }
            let Sides([(right3, rh), (left3, lh)]) = sides;
            let d = left3[0].min(right3[0]);
            if d < spot.clearance_m {
                spot.at = WorldPoint::new(t, 0.0);
                spot.clearance_m = d;
            }
            let width = left3.iter().sum::<f64>() / 3.0 + right3.iter().sum::<f64>() / 3.0;
            if width < spot.width_m {
                spot.width_m = width;
                mid = [(lh[0] + rh[0]) / 2.0, (lh[1] + rh[1]) / 2.0];
                narrowest_at = t;
            }
            let w = ((full_r - d) / (full_r - narrow_r).max(1e-9)).clamp(0.0, 1.0);
            cost += w * f64::from(map::BAND_FACTOR - 1) * step;
        }
        // Only a leg whose narrowest cross-section lies inside it passes through.
        spot.through = narrowest_at > step / 2.0 && narrowest_at < travel - step / 2.0;
        (cost, spot, spot.through.then_some(mid))
    }

    /// `Plan::Go` along a candidate when its leg, cut by the remembered obstacles, is still
    /// at least the shortest allowed.
    fn go_if_long_enough(
        &self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        c: Candidate,
    ) -> Option<Plan> {
        let i = c.ray;
        let travel = self.memory_cap_m(pose, geometry.bearing_rad(i), c.travel, c.narrow.is_some());
        if !(travel >= self.params.min_travel_m && travel > 0.0) {
            return None;
        }
        let narrow = c.narrow.map(|spot| {
            let u = geometry.directions()[i];
            // Measured again only when the memory cut the leg short.
            let spot = if travel == c.travel {
                spot
            } else {
                self.band_cost(u, travel).1
            };
            let along = spot.at.x_m();
            NarrowSpot {
                at: pose.transform_point(RobotPoint::new(along * u[0], along * u[1])),
                ..spot
            }
        });
        Some(Plan::Go {
            ray_index: i,
            alpha_rad: normalize_angle_rad(geometry.bearing_rad(i)),
            travel_m: travel,
            target_in_view: false,
            narrow,
        })
    }

    /// How far along `bearing_rad` from `pose` (at most `travel_m`) the robot stays out of the
    /// remembered obstacles (a narrow leg: out of their lethal core only); a stretch that
    /// starts inside one (the robot next to a wall) is allowed until it leaves it.
    fn memory_cap_m(&self, pose: &Pose2, bearing_rad: f64, travel_m: f64, narrow: bool) -> f64 {
        let step = self.params.grid_resolution_m / 2.0;
        let steps = (travel_m / step).ceil() as usize;
        let blocked_at =
            |p: WorldPoint| self.memory.is_blocked(p) || (!narrow && self.memory.is_in_band(p));
        let mut left_start = !blocked_at(pose.position());
        for s in 1..=steps {
            let t = (s as f64 * step).min(travel_m);
            let p = pose.rotated(bearing_rad).advanced(t).position();
            let blocked = blocked_at(p);
            if left_start && blocked {
                return ((s - 1) as f64 * step).min(travel_m);
            }
            left_start |= !blocked;
        }
        travel_m
    }

    /// `Go` straight at the target when it lies within the field of view and the rays on
    /// either side of its bearing are clear up to it.
    fn straight_for_target(
        &self,
        geometry: &ScanGeometry,
        clearances_m: &[f64],
        n: usize,
        t_range: f64,
        t_bearing: f64,
    ) -> Option<Plan> {
        // Bearings are compared unwrapped against the scan's span.
        let f = geometry.fractional_index(t_bearing);
        let (lo, hi) = (f.floor(), f.ceil());
        if !(lo >= 0.0 && hi <= (n - 1) as f64) {
            return None;
        }
        let need = (t_range - self.params.target_tolerance_m).max(0.0);
        let (a, b) = (lo as usize, hi as usize);
        let clear = clearances_m[a].min(clearances_m[b]);
        if clear.is_nan() || clear < need || t_range < 1e-9 {
            return None;
        }
        let nearest = if f - lo <= hi - f { a } else { b };
        Some(Plan::Go {
            ray_index: nearest,
            alpha_rad: t_bearing,
            travel_m: t_range.min(clear).min(self.params.max_travel_m),
            target_in_view: true,
            narrow: None,
        })
    }
}

/// Per side of a line (right, then left): the three nearest distances, ascending (infinite
/// for none), and the nearest hit.
#[derive(Debug, Clone, Copy)]
struct Sides([([f64; 3], [f64; 2]); 2]);

impl Default for Sides {
    fn default() -> Self {
        Self([([f64::INFINITY; 3], [0.0; 2]); 2])
    }
}

impl Sides {
    /// Counts hit `h` at distance `d` on its side.
    fn add(&mut self, h: [f64; 2], d: f64, left: bool) {
        let (best, at) = &mut self.0[usize::from(left)];
        if d < best[2] {
            if d < best[0] {
                *at = h;
            }
            best[2] = d;
            best.sort_unstable_by(f64::total_cmp);
        }
    }
}

/// Adds `p` to `points` unless one within [`GAP_SAME_M`] is there already.
fn push_near(points: &mut Vec<WorldPoint>, p: WorldPoint) {
    if !points.iter().any(|q| q.distance_m(&p) < GAP_SAME_M) {
        points.push(p);
    }
}

/// The scan's hits in the robot frame.
fn robot_hits(geometry: &ScanGeometry, scan: &Scan) -> Vec<[f64; 2]> {
    let dirs = geometry.directions();
    (0..geometry.ray_count.min(scan.len()))
        .filter_map(|i| {
            let r = scan.hit_range_m(i).filter(|r| r.is_finite() && *r >= 0.0)?;
            Some([r * dirs[i][0], r * dirs[i][1]])
        })
        .collect()
}

/// Secondary key for equal scores: angle off the target's bearing, then the shorter leg last.
fn tie_key(geometry: &ScanGeometry, i: usize, travel: f64, t_bearing: f64) -> (u64, u64) {
    let off = angle_diff_rad(geometry.bearing_rad(i), t_bearing).abs();
    ((off * 1e9) as u64, ((10.0 - travel.min(10.0)) * 1e9) as u64)
}
