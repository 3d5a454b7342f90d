//! `[localiser] rectilinear`: the walls in view correct a heading the turns got wrong, in the
//! hand-built room (its walls and boxes all run along x and y).

use navigator::{HeadingRule, Navigator, Params, Reason, TravelRule};
use scan_types::testkit::boxed;
use scan_types::{Pose2, ScanGeometry, WorldPoint};

#[path = "common/base.rs"]
mod base;
#[path = "common/room.rs"]
mod room;
#[path = "common/stored.rs"]
mod stored;

/// Runs from (1, 1, 0) to (7, 4) in the hand-built room on a base that turns `turn_scale` of
/// every command, with the heading from the commands alone (no scan measures a turn); returns
/// how it ended, the final estimate and the true pose.
fn run(rectilinear: bool, turn_scale: f64) -> (Reason, Pose2, Pose2) {
    run_with(rectilinear, false, turn_scale)
}

/// As [`run`], with `[localiser] rectilinear_moves_position` set to `moves`.
fn run_with(rectilinear: bool, moves: bool, turn_scale: f64) -> (Reason, Pose2, Pose2) {
    let mut p = Params::goalseek();
    p.localiser.heading_rule = HeadingRule::Commanded;
    p.localiser.travel_rule = TravelRule::Landmark;
    p.localiser.rectilinear = rectilinear;
    p.localiser.rectilinear_moves_position = moves;
    let start = Pose2::new(1.0, 1.0, 0.0);
    let goal = WorldPoint::new(7.0, 4.0);
    let mut nav = Navigator::new(p, ScanGeometry::paper(), start, goal).unwrap();
    let truth = base::drive(&mut nav, &room::room(), start, (turn_scale, 1.0), |_| {});
    let estimate = nav.estimate();
    (nav.into_outcome().reason, estimate, truth)
}

fn heading_error_deg(est: &Pose2, truth: &Pose2) -> f64 {
    scan_types::angle_diff_rad(est.theta_rad, truth.theta_rad)
        .abs()
        .to_degrees()
}

#[test]
fn the_walls_square_up_a_heading_the_turns_got_wrong() {
    // Every turn of the run is at least atan2(3, 6) = 26.6 deg, so a base turning 4 % short
    // leaves at least 1.06 deg of heading error per turn when only the commands count.
    let (_, est0, truth0) = run(false, 0.96);
    let off0 = heading_error_deg(&est0, &truth0);
    assert!(off0 > 1.06, "{off0:.2} deg");
    // With the walls, each turn's error is weighed against theirs: a turn's 1 deg standard
    // deviation against the walls' 0.75 deg takes 1 / (1 + 0.75^2) = 64 % of it off.
    let (reason, est, truth) = run(true, 0.96);
    assert_eq!(reason, Reason::Reached);
    let off = heading_error_deg(&est, &truth);
    assert!(off < 0.5 * off0, "{off:.2} deg against {off0:.2} deg");
    let (e0, e) = (
        est0.position().distance_m(&truth0.position()),
        est.position().distance_m(&truth.position()),
    );
    assert!(e < e0, "{e:.3} m against {e0:.3} m");
}

#[test]
fn an_exact_base_keeps_its_heading() {
    // Nothing to correct: the walls' own error (range noise of 0.01 m) must not turn the
    // estimate by more than a tenth of a degree.
    let (reason, est, truth) = run(true, 1.0);
    assert_eq!(reason, Reason::Reached);
    let off = heading_error_deg(&est, &truth);
    assert!(off < 0.1, "{off:.3} deg");
}

#[test]
fn a_stored_configuration_without_the_key_keeps_it_off() {
    let (old, removed) =
        stored::without("localiser", &["rectilinear", "rectilinear_moves_position"]);
    assert_eq!(
        removed,
        [
            serde_json::json!(true),
            serde_json::json!(Params::goalseek().localiser.rectilinear_moves_position)
        ]
    );
    assert!(!old.localiser.rectilinear);
    assert!(!old.localiser.rectilinear_moves_position);
    assert!(!Params::paper().localiser.rectilinear);
    assert!(!Params::paper().localiser.rectilinear_moves_position);
}

#[test]
fn rectilinear_keys_are_validated_by_name() {
    for (key, set) in [
        (
            "rectilinear_sigma_deg",
            (|p: &mut Params| p.localiser.rectilinear_sigma_deg = 0.0) as fn(&mut Params),
        ),
        ("rectilinear_max_deg", |p| {
            p.localiser.rectilinear_max_deg = 50.0
        }),
        ("rectilinear_min_share", |p| {
            p.localiser.rectilinear_min_share = 1.5
        }),
        ("rectilinear_gate_sigmas", |p| {
            p.localiser.rectilinear_gate_sigmas = f64::NAN
        }),
    ] {
        let mut p = Params::goalseek();
        set(&mut p);
        let e = p.validate().unwrap_err().to_string();
        assert!(e.contains(&format!("localiser.{key}")), "{key}: {e}");
    }
}

#[test]
fn the_walls_shrink_the_heading_uncertainty_as_a_kalman_filter_does() {
    // One 2 m leg in an empty 6 m x 4 m room from (1, 2) facing +x, an exact base, the heading
    // from the commands. The start's scan sets the axes with the walls' variance r (0.75 deg
    // squared; the heading is exact there). The turn onto the target (one chunk) makes the
    // heading's variance 1 deg squared; its scan measures the heading against axes known to
    // r, with r of its own: 1 x 2r / (1 + 2r) = 0.5294 deg squared, 0.7276 deg. The leg then
    // adds 0.02 x 2 m and 2 m x 0.7276 deg = 0.0254 m of lateral error: 0.0654 m. At its end
    // the heading is known better than the walls measure it: no more correction.
    let g = ScanGeometry::paper();
    let segs = boxed(0.0, 0.0, 6.0, 4.0);
    let mut p = Params::goalseek();
    p.localiser.heading_rule = HeadingRule::Commanded;
    p.localiser.travel_rule = TravelRule::Landmark;
    let start = Pose2::new(1.0, 2.0, 0.0);
    let mut nav = Navigator::new(p, g, start, WorldPoint::new(3.0, 2.0)).unwrap();
    base::drive(&mut nav, &segs, start, (1.0, 1.0), |_| {});
    let o = nav.into_outcome();
    assert_eq!(o.reason, Reason::Reached, "{}", o.note);
    let last = o.legs.last().unwrap();
    let r = 0.75f64 * 0.75;
    let heading = (2.0 * r / (1.0 + 2.0 * r)).sqrt();
    assert!(
        (last.heading_sigma_deg - heading).abs() < 1e-9,
        "{} vs {heading}",
        last.heading_sigma_deg
    );
    let position = 0.04 + 2.0 * heading.to_radians();
    assert!(
        (last.position_sigma_m - position).abs() < 0.003,
        "{} vs {position}",
        last.position_sigma_m
    );
}

/// The final position errors of the walls' run on a base turning `turn_scale` of every
/// command, without and with `rectilinear_moves_position`, metres; both runs must arrive.
fn position_errors(turn_scale: f64) -> (f64, f64) {
    let [off, on] = [false, true].map(|moves| {
        let (reason, est, truth) = run_with(true, moves, turn_scale);
        assert_eq!(reason, Reason::Reached, "moves_position = {moves}");
        est.position().distance_m(&truth.position())
    });
    (off, on)
}

#[test]
fn a_corrected_heading_moves_the_position_its_error_displaced() {
    // The base turns 4 % short: every leg after a turn runs off the estimate's heading until
    // the walls square it up, and its end lies to the side by the leg times that error.
    // Moving the position with the heading takes part of that off.
    let (e0, e) = position_errors(0.96);
    assert!(e < 0.9 * e0, "{e:.3} m against {e0:.3} m");
}

#[test]
fn an_exact_base_keeps_its_position() {
    // Nothing to correct: the walls' own error turns the heading by hundredths of a degree,
    // which move the position by well under a millimetre over the run.
    let (e0, e) = position_errors(1.0);
    assert!((e - e0).abs() < 0.001, "{e:.4} m against {e0:.4} m");
}
