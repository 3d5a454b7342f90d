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
pub use map::{MAX_CELLS, ObstacleMemory, TARGET_CELLS};

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
}

impl Default for PlannerParams {
    /// goalseek defaults: MapPath, r = 0.3 m + 0.1 m margin, legs 0.3 .. 2.0 m, 0.1 m cells,
    /// 12 tries (a full turn in 30 deg steps) before giving up.
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

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlannerError> {
        let bad = |field, value, why| Err(PlannerError::InvalidParam { field, value, why });
        let nonneg = |v: f64| v.is_finite() && v >= 0.0;
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

/// Chooses rays toward a target; remembers obstacles for [`PlanRule::MapPath`].
#[derive(Debug, Clone)]
pub struct Planner {
    params: PlannerParams,
    memory: ObstacleMemory,
    no_safe_tries: usize,
    no_path_tries: usize,
    /// Scratch: (score, ray, travel) of every safe ray.
    candidates: Vec<(f64, usize, f64)>,
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
        // Shrunk by one cell, so that a safe end right at the edge of an expanded obstacle
        // does not fall into a blocked cell.
        let inflate = (p.robot_radius_m + p.margin_m - p.grid_resolution_m).max(0.0);
        Self {
            memory: ObstacleMemory::new(p.grid_resolution_m, inflate),
            params: p,
            no_safe_tries: 0,
            no_path_tries: 0,
            candidates: Vec::new(),
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
        let n = geometry.ray_count.min(clearances_m.len()).min(scan.len());
        if !(0..n).any(|i| self.leg(clearances_m, i).is_some()) {
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

        let map_path = match self.map_path_usable(pose, geometry, clearances_m, n, target) {
            Ok(usable) => usable,
            Err(unreachable) => return unreachable,
        };
        self.rank_candidates(pose, geometry, clearances_m, (n, target), map_path);
        // Best score first; ties go to the ray nearer the target's bearing, then the longer leg.
        let order = |a: &(f64, usize, f64), b: &(f64, usize, f64)| {
            a.0.total_cmp(&b.0).then_with(|| {
                tie_key(geometry, a.1, a.2, t_bearing).cmp(&tie_key(geometry, b.1, b.2, t_bearing))
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
        clearances_m: &[f64],
        n: usize,
        target: WorldPoint,
    ) -> Result<bool, Plan> {
        if self.params.rule != PlanRule::MapPath {
            return Ok(false);
        }
        self.memory.ensure_contains(pose.position());
        self.memory.update_field(target);
        let reachable = (0..n)
            .filter_map(|i| self.leg(clearances_m, i).map(|t| (i, t)))
            .any(|(i, t)| {
                let end = pose.transform_point(geometry.robot_point(i, t));
                self.memory.path_length_m(end).is_some()
            });
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
            self.candidates.push((score, i, travel));
        }
    }

    /// `Plan::Go` along candidate `(score, ray, travel)` when its leg, cut by the remembered
    /// obstacles, is still at least the shortest allowed.
    fn go_if_long_enough(
        &self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        (_, i, travel): (f64, usize, f64),
    ) -> Option<Plan> {
        let travel = self.memory_cap_m(pose, geometry.bearing_rad(i), travel);
        (travel >= self.params.min_travel_m && travel > 0.0).then(|| Plan::Go {
            ray_index: i,
            alpha_rad: normalize_angle_rad(geometry.bearing_rad(i)),
            travel_m: travel,
            target_in_view: false,
        })
    }

    /// How far along `bearing_rad` from `pose` (at most `travel_m`) the robot stays out of the
    /// remembered obstacles; a stretch that starts inside one (the robot next to a wall) is
    /// allowed until it leaves it.
    fn memory_cap_m(&self, pose: &Pose2, bearing_rad: f64, travel_m: f64) -> f64 {
        let step = self.params.grid_resolution_m / 2.0;
        let steps = (travel_m / step).ceil() as usize;
        let mut left_start = !self.memory.is_blocked(pose.position());
        for s in 1..=steps {
            let t = (s as f64 * step).min(travel_m);
            let p = pose.rotated(bearing_rad).advanced(t).position();
            let blocked = self.memory.is_blocked(p);
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
        })
    }
}

/// Secondary key for equal scores: angle off the target's bearing, then the shorter leg last.
fn tie_key(geometry: &ScanGeometry, i: usize, travel: f64, t_bearing: f64) -> (u64, u64) {
    let off = angle_diff_rad(geometry.bearing_rad(i), t_bearing).abs();
    ((off * 1e9) as u64, ((10.0 - travel.min(10.0)) * 1e9) as u64)
}
