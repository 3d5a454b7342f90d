//! 2D poses and points tagged with the frame they live in.

use nalgebra::{Isometry2, Point2, Vector2};

use crate::normalize_angle_rad;

/// A point in the robot frame: x ahead, y to the left, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RobotPoint(pub Point2<f64>);

/// A point in the world frame: x right, y up, metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WorldPoint(pub Point2<f64>);

macro_rules! point_impl {
    ($t:ident) => {
        impl $t {
            /// Builds the point from its coordinates in metres.
            pub fn new(x_m: f64, y_m: f64) -> Self {
                Self(Point2::new(x_m, y_m))
            }
            /// The x coordinate, metres.
            pub fn x_m(&self) -> f64 {
                self.0.x
            }
            /// The y coordinate, metres.
            pub fn y_m(&self) -> f64 {
                self.0.y
            }
            /// Euclidean distance to another point of the same frame, metres.
            pub fn distance_m(&self, other: &Self) -> f64 {
                nalgebra::distance(&self.0, &other.0)
            }
        }
    };
}
point_impl!(RobotPoint);
point_impl!(WorldPoint);

impl RobotPoint {
    /// Distance from the robot centre, metres.
    pub fn range_m(&self) -> f64 {
        self.0.coords.norm()
    }
    /// Bearing from the heading, radians in (-pi, pi].
    pub fn bearing_rad(&self) -> f64 {
        normalize_angle_rad(self.0.y.atan2(self.0.x))
    }
}

/// A robot pose in the world frame: position in metres, heading in radians.
///
/// ```
/// use scan_types::{Pose2, RobotPoint};
/// use std::f64::consts::FRAC_PI_2;
/// let a = Pose2::new(1.0, 0.0, FRAC_PI_2);
/// let b = Pose2::new(2.0, 0.0, 0.0);
/// // Driving 2 m "ahead" from a pose that faces +y ends at (1, 2).
/// let c = a.compose(&b);
/// assert!((c.x_m - 1.0).abs() < 1e-12 && (c.y_m - 2.0).abs() < 1e-12);
/// // Composing with the inverse gives the identity.
/// let id = a.compose(&a.inverse());
/// assert!(id.x_m.abs() < 1e-12 && id.y_m.abs() < 1e-12 && id.theta_rad.abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Pose2 {
    /// x position, metres.
    pub x_m: f64,
    /// y position, metres.
    pub y_m: f64,
    /// Heading, radians, normalised to (-pi, pi].
    pub theta_rad: f64,
}

impl Pose2 {
    /// Builds a pose, normalising the heading.
    pub fn new(x_m: f64, y_m: f64, theta_rad: f64) -> Self {
        Self {
            x_m,
            y_m,
            theta_rad: normalize_angle_rad(theta_rad),
        }
    }

    /// The position as a world point.
    pub fn position(&self) -> WorldPoint {
        WorldPoint::new(self.x_m, self.y_m)
    }

    /// Unit vector along the heading.
    pub fn heading_vector(&self) -> Vector2<f64> {
        Vector2::new(self.theta_rad.cos(), self.theta_rad.sin())
    }

    /// The pose as a nalgebra isometry (robot frame to world frame).
    pub fn to_isometry(&self) -> Isometry2<f64> {
        Isometry2::new(Vector2::new(self.x_m, self.y_m), self.theta_rad)
    }

    /// The pose of a nalgebra isometry.
    pub fn from_isometry(iso: &Isometry2<f64>) -> Self {
        Self::new(iso.translation.x, iso.translation.y, iso.rotation.angle())
    }

    /// `self` followed by `other` expressed in `self`'s frame.
    pub fn compose(&self, other: &Pose2) -> Pose2 {
        Self::from_isometry(&(self.to_isometry() * other.to_isometry()))
    }

    /// The inverse transform: the world origin seen from this pose.
    pub fn inverse(&self) -> Pose2 {
        Self::from_isometry(&self.to_isometry().inverse())
    }

    /// A robot-frame point expressed in the world frame.
    pub fn transform_point(&self, p: RobotPoint) -> WorldPoint {
        WorldPoint(self.to_isometry() * p.0)
    }

    /// A world-frame point expressed in this pose's robot frame.
    pub fn inverse_transform_point(&self, p: WorldPoint) -> RobotPoint {
        RobotPoint(self.to_isometry().inverse_transform_point(&p.0))
    }

    /// The pose reached by driving `distance_m` straight along the heading.
    pub fn advanced(&self, distance_m: f64) -> Pose2 {
        Pose2::new(
            self.x_m + distance_m * self.theta_rad.cos(),
            self.y_m + distance_m * self.theta_rad.sin(),
            self.theta_rad,
        )
    }

    /// The pose after rotating in place by `angle_rad`.
    pub fn rotated(&self, angle_rad: f64) -> Pose2 {
        Pose2::new(self.x_m, self.y_m, self.theta_rad + angle_rad)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn assert_pose(p: Pose2, x: f64, y: f64, t: f64) {
        assert_abs_diff_eq!(p.x_m, x, epsilon = 1e-12);
        assert_abs_diff_eq!(p.y_m, y, epsilon = 1e-12);
        assert_abs_diff_eq!(crate::angle_diff_rad(p.theta_rad, t), 0.0, epsilon = 1e-12);
    }

    #[test]
    fn new_normalises_heading() {
        assert_eq!(Pose2::new(0.0, 0.0, -PI).theta_rad, PI);
        assert_abs_diff_eq!(
            Pose2::new(0.0, 0.0, 3.0 * FRAC_PI_2).theta_rad,
            -FRAC_PI_2,
            epsilon = 1e-12
        );
    }

    #[test]
    fn composition_by_hand() {
        // From (1, 2, 90 deg), moving (3, 0) in the robot frame goes to (1, 5), then turn 90 deg.
        let a = Pose2::new(1.0, 2.0, FRAC_PI_2);
        let b = Pose2::new(3.0, 0.0, FRAC_PI_2);
        assert_pose(a.compose(&b), 1.0, 5.0, PI);
        // Moving (0, 1) (to the left) from a heading of 90 deg goes toward -x.
        assert_pose(a.compose(&Pose2::new(0.0, 1.0, 0.0)), 0.0, 2.0, FRAC_PI_2);
    }

    #[test]
    fn inverse_by_hand() {
        // The world origin seen from (1, 0) facing +y is at (0, 1) in the robot frame, heading -90 deg.
        let a = Pose2::new(1.0, 0.0, FRAC_PI_2);
        assert_pose(a.inverse(), 0.0, 1.0, -FRAC_PI_2);
        assert_pose(a.inverse().compose(&a), 0.0, 0.0, 0.0);
    }

    #[test]
    fn composition_is_associative() {
        let a = Pose2::new(1.0, -2.0, 0.7);
        let b = Pose2::new(-0.5, 3.0, -2.9);
        let c = Pose2::new(4.0, 0.1, 3.1);
        let l = a.compose(&b).compose(&c);
        let r = a.compose(&b.compose(&c));
        assert_pose(l, r.x_m, r.y_m, r.theta_rad);
    }

    #[test]
    fn world_point_of_ray_at_pose() {
        // Robot at (-3.92, -4.26) heading 45 deg; a point 2 m ahead.
        let pose = Pose2::new(-3.92, -4.26, PI / 4.0);
        let w = pose.transform_point(RobotPoint::new(2.0, 0.0));
        assert_abs_diff_eq!(w.x_m(), -3.92 + 2.0_f64.sqrt(), epsilon = 1e-12);
        assert_abs_diff_eq!(w.y_m(), -4.26 + 2.0_f64.sqrt(), epsilon = 1e-12);
        // And back.
        let r = pose.inverse_transform_point(w);
        assert_abs_diff_eq!(r.x_m(), 2.0, epsilon = 1e-12);
        assert_abs_diff_eq!(r.y_m(), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(r.range_m(), 2.0, epsilon = 1e-12);
        assert_abs_diff_eq!(r.bearing_rad(), 0.0, epsilon = 1e-12);
    }

    #[test]
    fn advance_and_rotate() {
        let p = Pose2::new(0.0, 0.0, PI).rotated(FRAC_PI_2);
        assert_pose(p, 0.0, 0.0, -FRAC_PI_2);
        assert_pose(p.advanced(2.0), 0.0, -2.0, -FRAC_PI_2);
    }

    #[test]
    fn points_measure_distance() {
        let a = WorldPoint::new(0.0, 0.0);
        let b = WorldPoint::new(3.0, 4.0);
        assert_eq!(a.distance_m(&b), 5.0);
        assert_abs_diff_eq!(
            RobotPoint::new(0.0, -1.0).bearing_rad(),
            -FRAC_PI_2,
            epsilon = 1e-12
        );
    }
}
