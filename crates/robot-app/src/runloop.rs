//! The navigator run against a laser and a base, with the simulator's truth recorded beside
//! the estimate by the caller (never read by the navigator).

use navigator::{Leg, Monitor, Navigator, Outcome, Params};
use scan_types::{LaserSource, MotionBase, Pose2, Scan, WorldPoint};

use scan_log::{LegRecord, RunLog};

/// Read-only access to what only a simulator knows, for evaluation.
pub trait Evaluation {
    /// The true pose.
    fn true_pose(&self) -> Pose2;
    /// Collisions so far.
    fn collisions(&self) -> usize;
}

impl Evaluation for sim_laser::TruthHandle {
    fn true_pose(&self) -> Pose2 {
        self.pose()
    }
    fn collisions(&self) -> usize {
        sim_laser::TruthHandle::collisions(self)
    }
}

/// Called with every scan and the estimate of the pose it was taken at.
pub type ScanPoseHook<'a> = &'a mut dyn FnMut(&Scan, &Pose2);

/// A finished run: the navigator's outcome and the rows of `trajectory.csv`.
pub struct LoopRun {
    /// The navigator's outcome.
    pub outcome: Outcome,
    /// Leg ends with the true pose beside the estimate where a simulator knows it.
    pub log: RunLog,
}

/// Records truth per leg, forwards scans to the hook and reports collisions.
struct Watch<'a> {
    eval: Option<&'a dyn Evaluation>,
    hook: Option<ScanPoseHook<'a>>,
    truths: Vec<Option<Pose2>>,
}

impl Monitor for Watch<'_> {
    fn scan(&mut self, scan: &Scan, estimate: &Pose2) {
        if let Some(f) = self.hook.as_mut() {
            f(scan, estimate);
        }
    }
    fn leg(&mut self, _leg: &Leg) {
        self.truths.push(self.eval.map(|e| e.true_pose()));
    }
    fn interrupted(&mut self) -> Option<String> {
        crate::interrupt::requested().then(|| "stopped by a signal (Ctrl-C or SIGTERM)".into())
    }
    fn collision(&mut self) -> Option<String> {
        let e = self.eval?;
        (e.collisions() > 0).then(|| {
            let t = e.true_pose();
            format!("collision near ({:.2}, {:.2})", t.x_m, t.y_m)
        })
    }
}

/// Runs the navigator with `params` from `start` to `goal` on `laser` and `base`; `eval`
/// (a simulator's truth) is recorded beside the estimate, `hook` sees every scan.
pub fn run_loop<'a, L, M>(
    laser: &mut L,
    base: &mut M,
    params: &Params,
    (start, goal): (Pose2, WorldPoint),
    eval: Option<&'a dyn Evaluation>,
    hook: Option<ScanPoseHook<'a>>,
) -> anyhow::Result<LoopRun>
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    let nav = Navigator::new(params.clone(), *laser.geometry(), start, goal)?;
    let mut watch = Watch {
        eval,
        hook,
        truths: Vec::new(),
    };
    let outcome = navigator::run(nav, laser, base, &mut watch);
    let legs = outcome
        .legs
        .iter()
        .zip(watch.truths.iter().copied().chain(std::iter::repeat(None)))
        .map(|(l, truth)| LegRecord {
            leg: l.leg,
            estimate: l.estimate,
            truth,
            landmark: l.landmark,
            point_b: l.point_b,
            scan_points: l.scan_points.clone(),
        })
        .collect();
    let log = RunLog {
        goal: Some(goal),
        legs,
    };
    Ok(LoopRun { outcome, log })
}
