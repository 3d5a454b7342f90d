//! Triangles OBC and OAB: where the side ray will see the landmark, and arrival there.

use scan_types::{Pose2, ScanGeometry, WorldPoint, normalize_angle_rad};

/// On which side of the path the landmark lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// Left of the heading (positive bearing): the left side ray `R_SL` will see it.
    Left,
    /// Right of the heading (negative bearing): the right side ray `R_SR` will see it.
    Right,
}

impl Side {
    /// Bearing of this side's side ray: +90 deg (left) or -90 deg (right).
    pub fn side_bearing_rad(self) -> f64 {
        match self {
            Side::Left => std::f64::consts::FRAC_PI_2,
            Side::Right => -std::f64::consts::FRAC_PI_2,
        }
    }
}

/// The triangles OBC / OAB of one leg (paper Fig. 3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Triangle {
    /// The robot's pose O when the landmark was selected.
    pub origin: Pose2,
    /// Range rho of the landmark from O, metres.
    pub rho_m: f64,
    /// Bearing phi of the landmark from the central ray at O, radians.
    pub phi_rad: f64,
    /// OB = rho cos(phi): distance to drive along the heading to reach B, metres.
    pub ob_m: f64,
    /// CB = rho |sin(phi)|: the landmark's distance from the path, metres.
    pub cb_m: f64,
    /// Which side ray will see the landmark.
    pub side: Side,
    /// Point B in the world frame: O + OB (cos theta, sin theta).
    pub point_b: WorldPoint,
    /// The landmark C in the world frame.
    pub landmark: WorldPoint,
}

/// Builds the triangles for a landmark at `landmark_range_m`, `landmark_bearing_rad` from
/// `pose` (paper Fig. 3).
///
/// ```
/// use localiser::{triangle, Side};
/// use scan_types::Pose2;
/// // A landmark 2 m away, 30 deg to the left of a robot at the origin facing +x.
/// let t = triangle(&Pose2::new(0.0, 0.0, 0.0), 2.0, 30f64.to_radians());
/// assert!((t.ob_m - 3f64.sqrt()).abs() < 1e-12); // 2 cos 30
/// assert!((t.cb_m - 1.0).abs() < 1e-12); // 2 sin 30
/// assert_eq!(t.side, Side::Left);
/// assert!((t.point_b.x_m() - 3f64.sqrt()).abs() < 1e-12 && t.point_b.y_m().abs() < 1e-12);
/// ```
pub fn triangle(pose: &Pose2, landmark_range_m: f64, landmark_bearing_rad: f64) -> Triangle {
    let phi = normalize_angle_rad(landmark_bearing_rad);
    let rho = landmark_range_m;
    let ob = rho * phi.cos();
    let cb = rho * phi.sin();
    let (c, s) = (pose.theta_rad.cos(), pose.theta_rad.sin());
    // Triangle OAB: the projections of OB on the world axes.
    let point_b = WorldPoint::new(pose.x_m + ob * c, pose.y_m + ob * s);
    // C lies CB to the side of B.
    let landmark = WorldPoint::new(point_b.x_m() - cb * s, point_b.y_m() + cb * c);
    Triangle {
        origin: *pose,
        rho_m: rho,
        phi_rad: phi,
        ob_m: ob,
        cb_m: cb.abs(),
        side: if cb >= 0.0 { Side::Left } else { Side::Right },
        point_b,
        landmark,
    }
}

/// Distance driven when the landmark, first seen at (rho, phi), is now seen at (rho', beta)
/// (paper Fig. 6): `rho cos(phi) - rho' cos(beta)`.
///
/// ```
/// // Seen 2 m ahead-left at 60 deg, later at 1.8 m and 105 deg.
/// let d = localiser::travelled_from_fallback(2.0, 60f64.to_radians(), 1.8, 105f64.to_radians());
/// assert!((d - (1.0 + 1.8 * 15f64.to_radians().sin())).abs() < 1e-12);
/// ```
pub fn travelled_from_fallback(rho_m: f64, phi_rad: f64, rho2_m: f64, beta_rad: f64) -> f64 {
    rho_m * phi_rad.cos() - rho2_m * beta_rad.cos()
}

/// How arrival at B is decided and the pose estimated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ArrivalRule {
    /// The paper: the side ray sees the landmark at a range close to CB: the robot is at B.
    /// If the side ray misses it, the first scan that sees it beyond 90 deg gives the
    /// distance by Fig. 6.
    SideRay,
    /// goalseek: as soon as the landmark reaches the side ray (or lies beyond it), the
    /// travelled distance is `rho cos(phi) - rho' cos(beta)` from the measured bearing
    /// (exact at any bearing, so the side ray's 0.35 deg quantisation does not matter).
    Measured,
}

/// Parameters of the arrival decision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArrivalParams {
    /// The rule.
    pub rule: ArrivalRule,
    /// The side ray's range must lie within this of CB (`SideRay`), metres.
    pub cb_tolerance_m: f64,
    /// `Measured` declares arrival once |bearing| >= 90 deg minus this, radians.
    pub bearing_tolerance_rad: f64,
}

impl Default for ArrivalParams {
    /// goalseek: `Measured`, within half a degree of the side ray, 0.1 m on CB.
    fn default() -> Self {
        Self {
            rule: ArrivalRule::Measured,
            cb_tolerance_m: 0.1,
            bearing_tolerance_rad: 0.5f64.to_radians(),
        }
    }
}

impl ArrivalParams {
    /// The paper's rule with a 0.1 m tolerance on CB.
    pub fn paper() -> Self {
        Self {
            rule: ArrivalRule::SideRay,
            ..Self::default()
        }
    }
}

/// How an arrival was established.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ArrivalHow {
    /// The side ray saw the landmark at ~CB: the robot is at B.
    SideRay,
    /// A ray beyond the side ray saw it (Fig. 6).
    Fallback,
    /// The measured bearing and range gave the distance (`ArrivalRule::Measured`).
    Measured,
}

/// The robot has reached (or passed) B.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrival {
    /// The estimated pose (heading unchanged since O).
    pub pose: Pose2,
    /// Distance driven from O, metres.
    pub travelled_m: f64,
    /// Which rule fired.
    pub how: ArrivalHow,
}

/// Decides from the tracked landmark's current bearing and range whether the robot has
/// reached B, and where it is. `None`: keep driving.
///
/// The side ray is the ray of `geometry` nearest to +-90 deg; "the side ray sees the
/// landmark" means the landmark's bearing rounds to that ray.
pub fn check_arrival(
    tri: &Triangle,
    geometry: &ScanGeometry,
    landmark_range_m: f64,
    landmark_bearing_rad: f64,
    params: &ArrivalParams,
) -> Option<Arrival> {
    if !(landmark_range_m.is_finite() && landmark_bearing_rad.is_finite()) {
        return None;
    }
    let beta = normalize_angle_rad(landmark_bearing_rad);
    let sign = match tri.side {
        Side::Left => 1.0,
        Side::Right => -1.0,
    };
    // Bearing on the landmark's side, positive: 90 deg = abeam.
    let b = sign * beta;
    let at = |travelled: f64, how| Arrival {
        pose: tri.origin.advanced(travelled),
        travelled_m: travelled,
        how,
    };
    let fallback = || travelled_from_fallback(tri.rho_m, tri.phi_rad, landmark_range_m, beta);
    match params.rule {
        ArrivalRule::Measured => (b >= std::f64::consts::FRAC_PI_2 - params.bearing_tolerance_rad)
            .then(|| at(fallback(), ArrivalHow::Measured)),
        ArrivalRule::SideRay => {
            let side_index = geometry.nearest_index(tri.side.side_bearing_rad());
            let half = 0.5 * geometry.increment_rad.abs();
            let side_bearing = side_index
                .map(|i| sign * geometry.bearing_rad(i))
                .unwrap_or(std::f64::consts::FRAC_PI_2);
            if (b - side_bearing).abs() <= half + 1e-12 {
                // The side ray sees it: at B if the range agrees with CB.
                ((landmark_range_m - tri.cb_m).abs() <= params.cb_tolerance_m)
                    .then(|| at(tri.ob_m, ArrivalHow::SideRay))
            } else if b > side_bearing {
                Some(at(fallback(), ArrivalHow::Fallback))
            } else {
                None
            }
        }
    }
}
