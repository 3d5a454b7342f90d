//! The blocking driver: a [`Navigator`] run against any [`LaserSource`] and [`MotionBase`].

use scan_types::{GroundTruth, LaserSource, MotionBase, Pose2, Scan};

use crate::{Action, Leg, Navigator, Outcome, Reason};

/// What a caller watches during [`run`]: recording, evaluation, a live view. Every method
/// has a default that does nothing.
pub trait Monitor {
    /// Every scan the navigator accepted, with the estimate of the pose it was taken at.
    fn scan(&mut self, _scan: &Scan, _estimate: &Pose2) {}
    /// Every leg end the navigator recorded, right after the scan that ended it.
    fn leg(&mut self, _leg: &Leg) {}
    /// After every completed motion: `Some(note)` ends the run as a collision (a simulator
    /// knows; a real robot's bumper might).
    fn collision(&mut self) -> Option<String> {
        None
    }
    /// Before every action: `Some(note)` ends the run as interrupted (Ctrl-C, SIGTERM, an
    /// operator's stop).
    fn interrupted(&mut self) -> Option<String> {
        None
    }
}

/// A [`Monitor`] that watches nothing.
#[derive(Debug, Default, Clone, Copy)]
pub struct NoMonitor;

impl Monitor for NoMonitor {}

/// Called with every scan and the estimate of the pose it was taken at.
pub type ScanHook<'a> = &'a mut dyn FnMut(&Scan, &Pose2);

/// A [`Monitor`] for evaluation: records the truth's pose at every leg end, ends the run on
/// the truth's first collision or when `stop` gives a note, and shows every scan to a hook.
pub struct TruthMonitor<'a> {
    truth: Option<&'a dyn GroundTruth>,
    hook: Option<ScanHook<'a>>,
    stop: fn() -> Option<String>,
    truths: Vec<Option<Pose2>>,
}

impl<'a> TruthMonitor<'a> {
    /// Watches `truth` (if any), calls `hook` (if any) with every scan and `stop` before every
    /// action.
    pub fn new(
        truth: Option<&'a dyn GroundTruth>,
        hook: Option<ScanHook<'a>>,
        stop: fn() -> Option<String>,
    ) -> Self {
        Self {
            truth,
            hook,
            stop,
            truths: Vec::new(),
        }
    }

    /// The true pose at every leg end so far, in order (`None` without a truth).
    pub fn truths(&self) -> &[Option<Pose2>] {
        &self.truths
    }
}

impl Monitor for TruthMonitor<'_> {
    fn scan(&mut self, scan: &Scan, estimate: &Pose2) {
        if let Some(f) = self.hook.as_mut() {
            f(scan, estimate);
        }
    }
    fn leg(&mut self, _leg: &Leg) {
        self.truths.push(self.truth.map(|e| e.true_pose()));
    }
    fn interrupted(&mut self) -> Option<String> {
        (self.stop)()
    }
    fn collision(&mut self) -> Option<String> {
        let e = self.truth?;
        (e.collisions() > 0).then(|| {
            let t = e.true_pose();
            format!("collision near ({:.2}, {:.2})", t.x_m, t.y_m)
        })
    }
}

/// Runs `nav` to its end: scans from `laser`, motions on `base`, and `stop` sent to the base
/// however the run ends.
pub fn run<L, M>(
    mut nav: Navigator,
    laser: &mut L,
    base: &mut M,
    monitor: &mut dyn Monitor,
) -> Outcome
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    drive(&mut nav, laser, base, monitor, &mut |_| None);
    if let Err(e) = base.stop() {
        tracing::warn!("the base did not take stop: {e}");
    }
    nav.into_outcome()
}

/// Answers `nav`'s actions until it finishes, without stopping the base. After every leg end,
/// `check` may end the run to the current goal with a reason and a note.
pub(crate) fn drive<L, M>(
    nav: &mut Navigator,
    laser: &mut L,
    base: &mut M,
    monitor: &mut dyn Monitor,
    check: &mut dyn FnMut(&Navigator) -> Option<(Reason, String)>,
) -> Reason
where
    L: LaserSource + ?Sized,
    M: MotionBase + ?Sized,
{
    let mut action = nav.pending();
    loop {
        if !matches!(action, Action::Finish(_))
            && let Some(note) = monitor.interrupted()
        {
            action = nav.fail(Reason::Interrupted, note);
        }
        action = match action {
            Action::Scan => match laser.next_scan() {
                Ok(scan) => {
                    let (pose, scans, legs) = (nav.estimate_now(), nav.scans(), nav.legs().len());
                    let mut next = nav.on_scan(&scan);
                    if nav.scans() > scans {
                        monitor.scan(&scan, &pose);
                    }
                    for leg in &nav.legs()[legs..] {
                        monitor.leg(leg);
                    }
                    if nav.legs().len() > legs
                        && !matches!(next, Action::Finish(_))
                        && let Some((reason, note)) = check(nav)
                    {
                        next = nav.fail(reason, note);
                    }
                    next
                }
                Err(e) => match monitor.interrupted() {
                    Some(note) => nav.fail(Reason::Interrupted, format!("{note}; laser: {e}")),
                    None => nav.fail(Reason::SensorFailure, format!("laser: {e}")),
                },
            },
            Action::Rotate { angle_rad } => {
                let done = base.rotate(angle_rad);
                motion_done(nav, done, monitor)
            }
            Action::Forward { distance_m } => {
                let done = base.forward(distance_m);
                motion_done(nav, done, monitor)
            }
            Action::Finish(reason) => return reason,
        };
    }
}

fn motion_done<E: std::fmt::Display>(
    nav: &mut Navigator,
    done: Result<(), E>,
    monitor: &mut dyn Monitor,
) -> Action {
    match done {
        Ok(()) => {
            let next = nav.on_motion_done();
            match monitor.collision() {
                Some(note) => nav.fail(Reason::Collision, note),
                None => next,
            }
        }
        // A move given up because of Ctrl-C or SIGTERM (or whose base went with the signal).
        Err(e) => match monitor.interrupted() {
            Some(note) => nav.fail(Reason::Interrupted, format!("{note}; base: {e}")),
            None => nav.fail(Reason::BaseFailure, format!("base: {e}")),
        },
    }
}
