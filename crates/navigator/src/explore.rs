//! Exploration without a goal: the robot drives to the frontiers of its own map (free cells
//! beside unknown ones), one after another, until none it can reach is left.

use std::collections::VecDeque;

use localiser::{CellState, OccupancyGrid};
use scan_types::{LaserSource, MotionBase, WorldPoint};
use serde::{Deserialize, Serialize};

use crate::run::drive;
use crate::{Monitor, Navigator, Outcome, Reason};

/// The numbers of exploration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct ExploreParams {
    /// Shortest frontier worth a visit, metres along it.
    pub min_frontier_m: f64,
    /// A frontier's target keeps at least this clearance from the map's occupied cells where
    /// the frontier has room, else the robot's radius, metres; a frontier with neither is
    /// skipped.
    pub target_clearance_m: f64,
    /// Frontier targets within this distance of a target reached are not tried again, metres.
    pub reached_radius_m: f64,
    /// Frontier targets within this distance of a target given up (unreachable, leg limit)
    /// are not tried again, metres.
    pub failed_radius_m: f64,
    /// Most goals (frontiers tried) in one exploration.
    pub max_goals: usize,
    /// Most legs toward one frontier before it is given up as out of reach.
    pub legs_per_goal: usize,
}

impl Default for ExploreParams {
    fn default() -> Self {
        Self {
            min_frontier_m: 0.4,
            target_clearance_m: 0.4,
            reached_radius_m: 0.5,
            failed_radius_m: 1.0,
            max_goals: 200,
            legs_per_goal: 20,
        }
    }
}

/// A frontier of the map: connected free cells that border unknown ones.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frontier {
    /// Where to drive: a frontier cell ([`frontiers`] says which).
    pub target: WorldPoint,
    /// The target's clearance from the nearest occupied cell, metres (capped at the target
    /// clearance).
    pub clearance_m: f64,
    /// Frontier cells.
    pub cells: usize,
}

/// The frontiers of `grid` at least `params.min_frontier_m` long, each with its target: the
/// frontier cell nearest `from` that keeps the target clearance (where none does, `radius_m`)
/// from occupied cells and lies outside every disc (centre, radius) of `avoid`.
/// Nearest first.
pub fn frontiers(
    grid: &OccupancyGrid,
    from: WorldPoint,
    radius_m: f64,
    avoid: &[(WorldPoint, f64)],
    params: &ExploreParams,
) -> Vec<Frontier> {
    let (w, h) = (grid.width(), grid.height());
    let res = grid.resolution_m();
    let state = |c: i64, r: i64| {
        if c < 0 || r < 0 || c >= w as i64 || r >= h as i64 {
            CellState::Unknown
        } else {
            grid.cell_state(c as usize, r as usize)
        }
    };
    let is_frontier = |c: i64, r: i64| {
        state(c, r) == CellState::Free
            && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .any(|(dc, dr)| state(c + dc, r + dr) == CellState::Unknown)
    };
    let mut seen = vec![false; w * h];
    // Clearances are looked for out to the larger of the target clearance and the radius.
    let search_m = params.target_clearance_m.max(radius_m);
    let reach = (search_m / res).ceil() as i64;
    let min_cells = (params.min_frontier_m / res).ceil().max(1.0) as usize;
    let mut out = Vec::new();
    for k in 0..w * h {
        let (c0, r0) = ((k % w) as i64, (k / w) as i64);
        if seen[k] || !is_frontier(c0, r0) {
            continue;
        }
        // One frontier: its 8-connected frontier cells.
        seen[k] = true;
        let mut cells = Vec::new();
        let mut queue = VecDeque::from([(c0, r0)]);
        while let Some((c, r)) = queue.pop_front() {
            cells.push((c, r));
            for dc in -1..=1 {
                for dr in -1..=1 {
                    let (nc, nr) = (c + dc, r + dr);
                    if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                        continue;
                    }
                    let nk = nr as usize * w + nc as usize;
                    if !seen[nk] && is_frontier(nc, nr) {
                        seen[nk] = true;
                        queue.push_back((nc, nr));
                    }
                }
            }
        }
        if cells.len() < min_cells {
            continue;
        }
        // Clearance of a cell: distance to the nearest occupied cell within reach.
        let clearance = |(c, r): (i64, i64)| {
            let mut best = reach * reach;
            for dc in -reach..=reach {
                for dr in -reach..=reach {
                    if dc * dc + dr * dr < best && state(c + dc, r + dr) == CellState::Occupied {
                        best = dc * dc + dr * dr;
                    }
                }
            }
            ((best as f64).sqrt() * res).min(search_m)
        };
        let centre = |(c, r): (i64, i64)| grid.cell_centre(c as usize, r as usize);
        let mut order: Vec<(f64, (i64, i64))> = cells
            .iter()
            .map(|&cell| (from.distance_m(&centre(cell)), cell))
            .collect();
        order.sort_by(|a, b| a.0.total_cmp(&b.0));
        let pick = |need: f64| {
            order.iter().find_map(|&(_, cell)| {
                let p = centre(cell);
                if avoid.iter().any(|(t, r)| t.distance_m(&p) <= *r) {
                    return None;
                }
                let clear = clearance(cell);
                (clear >= need).then_some((p, clear))
            })
        };
        // The target clearance where the frontier has it, else the robot's radius (a door).
        let chosen = pick(params.target_clearance_m.max(radius_m)).or_else(|| pick(radius_m));
        if let Some((target, clearance_m)) = chosen {
            out.push(Frontier {
                target,
                clearance_m,
                cells: cells.len(),
            });
        }
    }
    out.sort_by(|a, b| {
        from.distance_m(&a.target)
            .total_cmp(&from.distance_m(&b.target))
    });
    out
}

/// True when a free cell within `radius_m` of `p` borders an unknown one: the frontier at
/// `p` is still open.
fn frontier_near(grid: &OccupancyGrid, p: WorldPoint, radius_m: f64) -> bool {
    let res = grid.resolution_m();
    let n = (radius_m / res).ceil() as i64;
    let at = |i: i64, j: i64| {
        grid.state(WorldPoint::new(
            p.x_m() + i as f64 * res,
            p.y_m() + j as f64 * res,
        ))
    };
    (-n..=n).any(|i| {
        (-n..=n).any(|j| {
            (i as f64).hypot(j as f64) * res <= radius_m
                && at(i, j) == CellState::Free
                && [(1, 0), (-1, 0), (0, 1), (0, -1)]
                    .iter()
                    .any(|(di, dj)| at(i + di, j + dj) == CellState::Unknown)
        })
    })
}

/// How an exploration ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ExploreEnd {
    /// No frontier left that has not been tried.
    Explored,
    /// `max_goals` frontiers were tried.
    GoalLimit,
    /// A run to a frontier ended by a failure (collision, sensor, base, interrupted): the
    /// outcome's reason says which.
    Failed,
}

/// One frontier tried.
#[derive(Debug, Clone, PartialEq)]
pub struct GoalTry {
    /// The frontier's target.
    pub target: WorldPoint,
    /// How the run to it ended.
    pub reason: Reason,
    /// Legs driven toward it.
    pub legs: usize,
}

/// What an exploration did.
#[derive(Debug, Clone)]
pub struct Exploration {
    /// How it ended.
    pub end: ExploreEnd,
    /// The frontiers tried, in order.
    pub goals: Vec<GoalTry>,
    /// The navigator's outcome: every leg, the map, the final estimate, the last run's reason.
    pub outcome: Outcome,
}

/// Explores from where `nav` stands: drives to the nearest untried frontier of its map, again
/// and again, until none is left. `nav` is a fresh navigator whose goal is its start. Scans
/// come from `laser`, motions go to `base`, and the base gets `stop` however it ends.
pub fn explore<L, M>(
    mut nav: Navigator,
    laser: &mut L,
    base: &mut M,
    monitor: &mut dyn Monitor,
    params: &ExploreParams,
) -> Exploration
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    let radius = nav.params().robot.radius_m;
    let mut goals: Vec<GoalTry> = Vec::new();
    let mut tried: Vec<(WorldPoint, f64)> = vec![(nav.goal(), params.reached_radius_m)];
    let mut legs_at_goal = nav.legs().len();
    let budget = params.legs_per_goal;
    let mut reason = drive(&mut nav, laser, base, monitor, &mut |_| None);
    let end = loop {
        if let Some(last) = goals.last_mut() {
            last.reason = reason;
            last.legs = nav.legs().len().saturating_sub(legs_at_goal);
            let r = if matches!(reason, Reason::Reached | Reason::UncertainArrival) {
                params.reached_radius_m
            } else {
                params.failed_radius_m
            };
            tried.push((last.target, r));
        }
        if !matches!(
            reason,
            Reason::Reached | Reason::UncertainArrival | Reason::Unreachable | Reason::LegLimit
        ) {
            break ExploreEnd::Failed;
        }
        if goals.len() >= params.max_goals {
            break ExploreEnd::GoalLimit;
        }
        let here = nav.estimate().position();
        let next = frontiers(nav.grid(), here, radius, &tried, params)
            .into_iter()
            .next();
        let Some(f) = next else {
            break ExploreEnd::Explored;
        };
        tracing::info!(
            goal = goals.len() + 1,
            x = f.target.x_m(),
            y = f.target.y_m(),
            cells = f.cells,
            "frontier"
        );
        goals.push(GoalTry {
            target: f.target,
            reason: Reason::Reached,
            legs: 0,
        });
        if nav.retarget(f.target).is_err() {
            break ExploreEnd::Failed;
        }
        legs_at_goal = nav.legs().len();
        let at = f.target;
        let mut check = |n: &Navigator| {
            if !frontier_near(n.grid(), at, radius) {
                return Some((Reason::Reached, "frontier mapped".to_string()));
            }
            (n.legs().len() - legs_at_goal >= budget).then(|| {
                (
                    Reason::LegLimit,
                    format!("{budget} legs toward a frontier: given up"),
                )
            })
        };
        reason = drive(&mut nav, laser, base, monitor, &mut check);
    };
    if let Err(e) = base.stop() {
        tracing::warn!("the base did not take stop: {e}");
    }
    Exploration {
        end,
        goals,
        outcome: nav.into_outcome(),
    }
}
