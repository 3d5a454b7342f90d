//! The navigator run against a laser and a base, with the simulator's truth recorded beside
//! the estimate by the caller (never read by the navigator).

use navigator::{Leg, Monitor, Navigator, Outcome, Params, TruthMonitor};
use scan_types::{GroundTruth, LaserSource, MotionBase, Pose2, WorldPoint};

use scan_log::{LegRecord, RunLog};

/// Called with every scan and the estimate of the pose it was taken at.
pub type ScanPoseHook<'a> = navigator::ScanHook<'a>;

/// Called with every leg end the navigator records, right after the scan that ended it.
pub type LegHook<'a> = &'a mut dyn FnMut(&Leg);

/// A [`TruthMonitor`] that also shows every leg end to a hook.
struct Watch<'a, 'b> {
    inner: TruthMonitor<'a>,
    legs: Option<LegHook<'b>>,
}

impl<'a, 'b> Watch<'a, 'b> {
    /// The simulator's `eval` recorded beside the estimate, `hook` on every scan, `legs` on
    /// every leg end, Ctrl-C heard.
    fn new(
        eval: Option<&'a dyn GroundTruth>,
        hook: Option<ScanPoseHook<'a>>,
        legs: Option<LegHook<'b>>,
    ) -> Self {
        Self {
            inner: TruthMonitor::new(eval, hook, interrupted),
            legs,
        }
    }
}

impl Monitor for Watch<'_, '_> {
    fn scan(&mut self, scan: &scan_types::Scan, estimate: &Pose2) {
        self.inner.scan(scan, estimate);
    }
    fn leg(&mut self, leg: &Leg) {
        self.inner.leg(leg);
        if let Some(f) = self.legs.as_mut() {
            f(leg);
        }
    }
    fn collision(&mut self) -> Option<String> {
        self.inner.collision()
    }
    fn interrupted(&mut self) -> Option<String> {
        self.inner.interrupted()
    }
}

/// A finished run: the navigator's outcome and the rows of `trajectory.csv`.
pub struct LoopRun {
    /// The navigator's outcome.
    pub outcome: Outcome,
    /// Leg ends with the true pose beside the estimate where a simulator knows it.
    pub log: RunLog,
}

/// The note of a run stopped by Ctrl-C or SIGTERM ([`crate::interrupt`]).
fn interrupted() -> Option<String> {
    crate::interrupt::requested().then(|| "stopped by a signal (Ctrl-C, SIGTERM or SIGHUP)".into())
}

/// Runs the navigator with `params` from `start` to `goal` on `laser` and `base`; `eval`
/// (a simulator's truth) is recorded beside the estimate, `hook` sees every scan.
pub fn run_loop<'a, L, M>(
    laser: &mut L,
    base: &mut M,
    params: &Params,
    (start, goal): (Pose2, WorldPoint),
    eval: Option<&'a dyn GroundTruth>,
    hook: Option<ScanPoseHook<'a>>,
) -> anyhow::Result<LoopRun>
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    run_loop_legs(laser, base, params, (start, goal), eval, hook, None)
}

/// [`run_loop`] that also shows every leg end to `legs`.
pub fn run_loop_legs<'a, 'b, L, M>(
    laser: &mut L,
    base: &mut M,
    params: &Params,
    (start, goal): (Pose2, WorldPoint),
    eval: Option<&'a dyn GroundTruth>,
    hook: Option<ScanPoseHook<'a>>,
    legs: Option<LegHook<'b>>,
) -> anyhow::Result<LoopRun>
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    let nav = Navigator::new(params.clone(), *laser.geometry(), start, goal)?;
    let mut watch = Watch::new(eval, hook, legs);
    let outcome = navigator::run(nav, laser, base, &mut watch);
    let log = run_log(&outcome, &watch.inner, Some(goal));
    Ok(LoopRun { outcome, log })
}

/// An exploration's [`navigator::Exploration`] and the rows of `trajectory.csv`.
pub struct ExploreRun {
    /// What the exploration did.
    pub exploration: navigator::Exploration,
    /// Leg ends with the true pose beside the estimate where a simulator knows it.
    pub log: RunLog,
}

/// Explores from `start` with `params` on `laser` and `base` ([`navigator::explore`]); `eval`
/// (a simulator's truth) is recorded beside the estimate, `hook` sees every scan and `legs`
/// every leg end.
#[allow(clippy::too_many_arguments)]
pub fn explore_loop<'a, 'b, L, M>(
    laser: &mut L,
    base: &mut M,
    params: &Params,
    explore: &navigator::ExploreParams,
    start: Pose2,
    eval: Option<&'a dyn GroundTruth>,
    hook: Option<ScanPoseHook<'a>>,
    legs: Option<LegHook<'b>>,
) -> anyhow::Result<ExploreRun>
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    let nav = Navigator::new(params.clone(), *laser.geometry(), start, start.position())?;
    let mut watch = Watch::new(eval, hook, legs);
    let exploration = navigator::explore(nav, laser, base, &mut watch, explore);
    let log = run_log(&exploration.outcome, &watch.inner, None);
    Ok(ExploreRun { exploration, log })
}

/// The legs of `outcome` with the truths `watch` recorded beside them.
fn run_log(outcome: &Outcome, watch: &TruthMonitor, goal: Option<WorldPoint>) -> RunLog {
    let legs = outcome
        .legs
        .iter()
        .zip(
            watch
                .truths()
                .iter()
                .copied()
                .chain(std::iter::repeat(None)),
        )
        .map(|(l, truth)| LegRecord {
            leg: l.leg,
            time_s: l.time_s,
            estimate: l.estimate,
            truth,
            landmark: l.landmark,
            point_b: l.point_b,
            scan_points: l.scan_points.clone(),
        })
        .collect();
    RunLog { goal, legs }
}
