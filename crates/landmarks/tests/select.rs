//! Selection rules (eq. 6 and goalseek's filters) on hand-made landmark lists.

use landmarks::{Landmark, LandmarkKind, SelectParams, select, select_nearest};
use std::f64::consts::FRAC_PI_2;

fn lm(range_m: f64, bearing_deg: f64, score: f64) -> Landmark {
    Landmark {
        index: 0,
        range_m,
        bearing_rad: bearing_deg.to_radians(),
        kind: LandmarkKind::MaxRangeJump,
        open_side: None,
        near_range_limit: score < 1.0,
        surface_continues: false,
        hidden_at_side: false,
        support_rays: 5,
        score,
    }
}

#[test]
fn nearest_within_ninety_degrees() {
    let all = [lm(0.5, 95.0, 1.0), lm(2.0, -89.0, 1.0), lm(1.5, 10.0, 1.0)];
    // 0.5 m lies behind the side ray; of the others 1.5 m is nearer.
    assert_eq!(select_nearest(&all, FRAC_PI_2).unwrap().range_m, 1.5);
    // Exactly 90 deg does not count (strictly within).
    assert!(select_nearest(&[lm(1.0, 90.0, 1.0)], FRAC_PI_2).is_none());
    // Ties: the smaller |bearing|.
    let tie = [lm(1.0, 40.0, 1.0), lm(1.0, -20.0, 1.0)];
    assert_eq!(
        select_nearest(&tie, FRAC_PI_2).unwrap().bearing_rad,
        (-20f64).to_radians()
    );
    // NaN ranges are ignored.
    assert!(select_nearest(&[lm(f64::NAN, 0.0, 1.0)], FRAC_PI_2).is_none());
}

#[test]
fn goalseek_filters() {
    let p = SelectParams::default();
    // Flagged (score 0.2) is skipped for the clean one further away.
    let all = [lm(1.0, 30.0, 0.2), lm(2.0, 30.0, 1.0)];
    assert_eq!(select(&all, &p).unwrap().range_m, 2.0);
    assert_eq!(select(&all, &SelectParams::paper()).unwrap().range_m, 1.0);
    // 1 m at 10 deg is 0.17 m beside the path (1 sin 10 deg): the robot cannot pass it.
    let near_path = [lm(1.0, 10.0, 1.0), lm(3.0, 20.0, 1.0)];
    assert_eq!(select(&near_path, &p).unwrap().range_m, 3.0);
    // 1 m at 85 deg is only 0.087 m ahead: B is where the robot stands.
    assert!(select(&[lm(1.0, 85.0, 1.0)], &p).is_none());
    assert!(select(&[lm(1.0, 85.0, 1.0)], &SelectParams::paper()).is_some());
}
