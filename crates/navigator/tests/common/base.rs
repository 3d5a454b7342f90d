//! The simulated base the navigator tests drive: scans cast in a hand-built world from the
//! true pose, and a base that may turn and drive by a scale of what it is told.

use navigator::{Action, Navigator};
use scan_types::Pose2;
use scan_types::testkit::{Seg, scan_at};

/// Answers `nav`'s actions until it finishes (at most 20 000 of them) from the true pose
/// `truth`, turning by `turn_scale` and driving by `drive_scale` of each command; `on_forward`
/// sees the true pose after every drive step. The true pose at the end.
pub fn drive(
    nav: &mut Navigator,
    segs: &[Seg],
    mut truth: Pose2,
    (turn_scale, drive_scale): (f64, f64),
    mut on_forward: impl FnMut(&Pose2),
) -> Pose2 {
    let g = *nav.geometry();
    for _ in 0..20_000 {
        match nav.pending() {
            Action::Scan => {
                let scan = scan_at(&g, segs, truth.x_m, truth.y_m, truth.theta_rad);
                nav.on_scan(&scan);
            }
            Action::Rotate { angle_rad } => {
                truth = truth.rotated(angle_rad * turn_scale);
                nav.on_motion_done();
            }
            Action::Forward { distance_m } => {
                truth = truth.compose(&Pose2::new(distance_m * drive_scale, 0.0, 0.0));
                on_forward(&truth);
                nav.on_motion_done();
            }
            Action::Finish(_) => break,
        }
    }
    truth
}
