//! The `MotionBase` trait: a robot base that can turn in place and drive straight.

/// A robot base driven by the goal-seeking loop: the simulator, a bridged real base,
/// or a person moving the robot by hand.
///
/// Each call blocks until the move is finished (or stopped). No odometry comes back:
/// goalseek localises from the laser alone.
pub trait MotionBase {
    /// What can go wrong while moving.
    type Error: std::error::Error + Send + Sync + 'static;

    /// Rotates in place by `angle_rad` (counter-clockwise positive).
    fn rotate(&mut self, angle_rad: f64) -> Result<(), Self::Error>;

    /// Drives straight along the heading by `distance_m` (negative: backwards).
    fn forward(&mut self, distance_m: f64) -> Result<(), Self::Error>;

    /// Stops any motion.
    fn stop(&mut self) -> Result<(), Self::Error>;
}

impl<M: MotionBase + ?Sized> MotionBase for &mut M {
    type Error = M::Error;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), Self::Error> {
        (**self).rotate(angle_rad)
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), Self::Error> {
        (**self).forward(distance_m)
    }
    fn stop(&mut self) -> Result<(), Self::Error> {
        (**self).stop()
    }
}

impl<M: MotionBase + ?Sized> MotionBase for Box<M> {
    type Error = M::Error;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), Self::Error> {
        (**self).rotate(angle_rad)
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), Self::Error> {
        (**self).forward(distance_m)
    }
    fn stop(&mut self) -> Result<(), Self::Error> {
        (**self).stop()
    }
}
