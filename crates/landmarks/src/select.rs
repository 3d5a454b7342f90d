//! Choosing the landmark to drive by (eq. 6).

use crate::Landmark;

/// Rules for choosing a landmark beyond the paper's nearest-within-90-deg.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelectParams {
    /// Only landmarks with |bearing| below this count, radians (paper: 90 deg).
    pub max_bearing_rad: f64,
    /// Skip landmarks whose distance ahead (`range cos bearing`) is below this, metres.
    pub min_ahead_m: f64,
    /// Skip landmarks whose stability score is below this.
    pub min_score: f64,
    /// Skip landmarks closer to the path than this (`range |sin bearing|` = CB), metres: the
    /// robot cannot pass a landmark nearer than its radius.
    pub min_lateral_m: f64,
}

impl Default for SelectParams {
    /// goalseek: within 90 deg, at least 0.2 m ahead, at least 0.4 m beside the path (robot
    /// radius 0.3 m plus a margin), no stability flag raised (a flag scores 0.3 or less).
    fn default() -> Self {
        Self {
            max_bearing_rad: std::f64::consts::FRAC_PI_2,
            min_ahead_m: 0.2,
            min_score: 0.4,
            min_lateral_m: 0.4,
        }
    }
}

impl SelectParams {
    /// The paper: the nearest landmark within 90 deg of the central ray, nothing else.
    pub fn paper() -> Self {
        Self {
            max_bearing_rad: std::f64::consts::FRAC_PI_2,
            min_ahead_m: 0.0,
            min_score: 0.0,
            min_lateral_m: 0.0,
        }
    }
}

/// The nearest landmark (eq. 6: smallest Euclidean distance from the robot, i.e. range)
/// whose bearing lies strictly within `max_bearing_rad` of the central ray.
///
/// Ties go to the smaller |bearing|. Landmarks with a non-finite range are ignored.
///
/// ```
/// use landmarks::{select_nearest, Landmark, LandmarkKind};
/// let l = |range_m: f64, bearing_rad: f64| Landmark {
///     index: 0, range_m, bearing_rad, kind: LandmarkKind::MaxRangeJump, open_side: None,
///     near_range_limit: false, surface_continues: false, hidden_at_side: false,
///     support_rays: 5, score: 1.0,
/// };
/// let all = [l(1.0, 2.0), l(2.0, 0.3), l(3.0, -0.2)];
/// // The 1 m landmark lies behind the side rays (2 rad > 90 deg).
/// let best = select_nearest(&all, std::f64::consts::FRAC_PI_2).unwrap();
/// assert_eq!(best.range_m, 2.0);
/// ```
pub fn select_nearest(landmarks: &[Landmark], max_bearing_rad: f64) -> Option<Landmark> {
    landmarks
        .iter()
        .filter(|l| l.range_m.is_finite() && l.bearing_rad.abs() < max_bearing_rad)
        .min_by(|a, b| {
            a.range_m
                .total_cmp(&b.range_m)
                .then(a.bearing_rad.abs().total_cmp(&b.bearing_rad.abs()))
        })
        .copied()
}

/// [`select_nearest`] among the landmarks that pass `params` (ahead far enough, stable enough).
pub fn select(landmarks: &[Landmark], params: &SelectParams) -> Option<Landmark> {
    let ok: Vec<Landmark> = landmarks
        .iter()
        .filter(|l| {
            l.score >= params.min_score
                && l.range_m * l.bearing_rad.cos() >= params.min_ahead_m
                && l.range_m * l.bearing_rad.sin().abs() >= params.min_lateral_m
        })
        .copied()
        .collect();
    select_nearest(&ok, params.max_bearing_rad)
}
