//! `[localiser] revisit`: a run that comes back to where it started corrects itself. A base
//! that drives 6 % long and turns 4 % short, and the paper's rules, which believe the commands:
//! out to a target and back to the start.

use navigator::{Action, HeadingRule, Navigator, Params, Reason, TravelRule};
use scan_types::testkit::Seg;

#[path = "common/base.rs"]
mod base;
#[path = "common/room.rs"]
mod room;
use room::room;
use scan_types::{Pose2, ScanGeometry, WorldPoint};

/// Drives `nav` on the scaled base from `truth` until it finishes; the true pose then.
fn drive(nav: &mut Navigator, segs: &[Seg], truth: Pose2) -> Pose2 {
    base::drive(nav, segs, truth, (0.96, 1.06), |_| {})
}

/// Out from (1, 1) to (7, 4) and back; the estimate's error at the target and at the end.
fn out_and_back(revisit: bool) -> (f64, f64) {
    let mut p = Params::goalseek();
    p.localiser.heading_rule = HeadingRule::Commanded;
    p.localiser.travel_rule = TravelRule::Landmark;
    p.localiser.revisit = revisit;
    // The walls would square up the heading the short turns lose: left to the revisits here.
    p.localiser.rectilinear = false;
    let segs = room();
    let start = Pose2::new(1.0, 1.0, 0.0);
    let mut nav =
        Navigator::new(p, ScanGeometry::paper(), start, WorldPoint::new(7.0, 4.0)).unwrap();
    let truth = drive(&mut nav, &segs, start);
    assert_eq!(nav.pending(), Action::Finish(Reason::Reached));
    let out = nav.estimate().position().distance_m(&truth.position());
    nav.retarget(start.position()).unwrap();
    let truth = drive(&mut nav, &segs, truth);
    let back = nav.estimate().position().distance_m(&truth.position());
    (out, back)
}

#[test]
#[allow(clippy::print_stdout)]
fn coming_back_to_the_start_corrects_the_estimate() {
    let (out0, back0) = out_and_back(false);
    let (out1, back1) = out_and_back(true);
    // Believing the commands, 6.7 m driven 6 % long leaves the estimate decimetres off at the
    // target, and the way back adds more.
    assert!(
        out0 > 0.1 && back0 > out0,
        "without: {out0:.3} then {back0:.3} m"
    );
    // Near the start, the start's scan (taken where the estimate was exact) pulls the
    // estimate back. What is left is what the legs after that correction add: at most the
    // revisit radius plus the goal tolerance (1.5 + 0.15 m), driven 6 % long (0.099 m) after a
    // turn of at most 180 deg made 4 % short (1.65 m x sin 7.2 deg = 0.207 m): 0.31 m.
    println!("without: {out0:.3} then {back0:.3} m; with: {out1:.3} then {back1:.3} m");
    assert!(back1 < 0.31, "with: {out1:.3} then {back1:.3} m");
}
