//! Triangles OBC / OAB and the arrival at B, checked against the paper's numbers and
//! hand-built scans.

use localiser::{
    ArrivalHow, ArrivalParams, ArrivalRule, Side, check_arrival, travelled_from_fallback, triangle,
};
use scan_types::{Pose2, ScanGeometry, WorldPoint};
use std::f64::consts::FRAC_PI_2;

#[test]
fn paper_first_leg() {
    // Paper section 4: from O = (-3.92, -4.26) heading toward the target (4, 4), the
    // landmark at (-2.38, -2.06) is to be re-detected from B = (-2.09, -2.34).
    let theta = (4.0f64 + 4.26).atan2(4.0 + 3.92);
    let o = Pose2::new(-3.92, -4.26, theta);
    let (dx, dy) = (-2.38f64 + 3.92, -2.06f64 + 4.26);
    let rho = dx.hypot(dy);
    let phi = dy.atan2(dx) - theta;
    let t = triangle(&o, rho, phi);
    assert!(
        t.point_b.distance_m(&WorldPoint::new(-2.09, -2.34)) < 0.02,
        "{t:?}"
    );
    assert_eq!(t.side, Side::Left); // seen by R_SL
    // The landmark is recovered in the world frame.
    assert!(t.landmark.distance_m(&WorldPoint::new(-2.38, -2.06)) < 1e-9);
    // By hand: OB = 1.54 cos(46.2 deg) + 2.20 sin(46.2 deg) = 2.654 m; CB = 0.41 m.
    assert!((t.ob_m - 2.654).abs() < 0.002, "{}", t.ob_m);
    assert!((t.cb_m - 0.410).abs() < 0.002, "{}", t.cb_m);
}

#[test]
fn right_side_by_hand() {
    // Facing +y from (1, 1): a landmark 5 m away at bearing -36.87 deg (3-4-5 triangle) is
    // 4 m ahead and 3 m to the right: B = (1, 5), C = (4, 5).
    let o = Pose2::new(1.0, 1.0, FRAC_PI_2);
    let t = triangle(&o, 5.0, -(3.0f64 / 4.0).atan());
    assert_eq!(t.side, Side::Right);
    assert!((t.ob_m - 4.0).abs() < 1e-12 && (t.cb_m - 3.0).abs() < 1e-12);
    assert!(t.point_b.distance_m(&WorldPoint::new(1.0, 5.0)) < 1e-12);
    assert!(t.landmark.distance_m(&WorldPoint::new(4.0, 5.0)) < 1e-12);
}

#[test]
fn fallback_formula_by_hand() {
    // First seen at (3, 1) from the origin; later at (-0.5, 1) relative: travelled 3.5.
    let (rho, phi) = (10f64.sqrt(), (1.0f64).atan2(3.0));
    let (rho2, beta) = ((1.25f64).sqrt(), (1.0f64).atan2(-0.5));
    assert!((travelled_from_fallback(rho, phi, rho2, beta) - 3.5).abs() < 1e-12);
}

/// The landmark (3, 1) seen from the origin facing +x: B = (3, 0), CB = 1.
fn leg() -> (ScanGeometry, localiser::Triangle) {
    let g = ScanGeometry::paper();
    let t = triangle(
        &Pose2::new(0.0, 0.0, 0.0),
        10f64.sqrt(),
        (1.0f64).atan2(3.0),
    );
    (g, t)
}

/// Range and bearing of (3, 1) from (x, 0).
fn seen_from(x: f64) -> (f64, f64) {
    ((3.0 - x).hypot(1.0), (1.0f64).atan2(3.0 - x))
}

#[test]
fn side_ray_sees_the_landmark_at_cb() {
    let (g, t) = leg();
    let paper = ArrivalParams::paper();
    // Short of B (bearing 84 deg): keep driving.
    let (r, b) = seen_from(2.9);
    assert!(check_arrival(&t, &g, r, b, &paper).is_none());
    // The side ray (the ray nearest to +90 deg) sees it at range CB: at B.
    let side = g.nearest_index(FRAC_PI_2).unwrap();
    let a = check_arrival(&t, &g, 1.0, g.bearing_rad(side), &paper).unwrap();
    assert_eq!(a.how, ArrivalHow::SideRay);
    assert!((a.travelled_m - 3.0).abs() < 1e-12);
    assert!(a.pose.position().distance_m(&WorldPoint::new(3.0, 0.0)) < 1e-12);
}

#[test]
fn noisy_side_ray_uses_the_fallback() {
    let (g, t) = leg();
    let paper = ArrivalParams::paper();
    let side = g.nearest_index(FRAC_PI_2).unwrap();
    // Noise: the side ray reads 1.2 m instead of CB = 1 m: not accepted.
    assert!(check_arrival(&t, &g, 1.2, g.bearing_rad(side), &paper).is_none());
    // Next scan, 0.1 m further: a ray beyond 90 deg sees it at 1.005 m, 95.7 deg.
    // Fig. 6: travelled = 3 - 1.005 cos(95.7 deg) = 3.1.
    let (r, b) = seen_from(3.1);
    let a = check_arrival(&t, &g, r, b, &paper).unwrap();
    assert_eq!(a.how, ArrivalHow::Fallback);
    assert!((a.travelled_m - 3.1).abs() < 1e-9);
    assert!(a.pose.position().distance_m(&WorldPoint::new(3.1, 0.0)) < 1e-9);
}

#[test]
fn measured_rule_fires_at_the_side_ray_with_the_exact_distance() {
    let (g, t) = leg();
    let ours = ArrivalParams::default();
    assert_eq!(ours.rule, ArrivalRule::Measured);
    let (r, b) = seen_from(2.9);
    assert!(check_arrival(&t, &g, r, b, &ours).is_none());
    // 0.5 deg short of abeam counts; the distance comes from the measured bearing.
    let x = 3.0 - (0.4f64).to_radians().tan();
    let (r, b) = seen_from(x);
    let a = check_arrival(&t, &g, r, b, &ours).unwrap();
    assert_eq!(a.how, ArrivalHow::Measured);
    assert!((a.travelled_m - x).abs() < 1e-9);
}

#[test]
fn right_side_landmark_passes_the_right_side_ray() {
    // Mirror of the leg: landmark at (3, -1).
    let g = ScanGeometry::paper();
    let t = triangle(
        &Pose2::new(0.0, 0.0, 0.0),
        10f64.sqrt(),
        -(1.0f64).atan2(3.0),
    );
    assert_eq!(t.side, Side::Right);
    let a = check_arrival(
        &t,
        &g,
        1.005,
        -(95.7f64).to_radians(),
        &ArrivalParams::paper(),
    )
    .unwrap();
    assert_eq!(a.how, ArrivalHow::Fallback);
    assert!((a.travelled_m - 3.1).abs() < 2e-3);
    // A landmark on the right says nothing when seen on the left.
    assert!(check_arrival(&t, &g, 1.0, 1.6, &ArrivalParams::default()).is_none());
}
