//! The `GroundTruth` trait: what a simulator, or a recording of one, knows of the robot.

use crate::Pose2;

/// Read-only access to the robot's true pose and collisions, for evaluation only: the
/// goal-seeking loop never receives it.
pub trait GroundTruth {
    /// The true pose now.
    fn true_pose(&self) -> Pose2;
    /// Collisions so far (none where nothing counts them).
    fn collisions(&self) -> usize {
        0
    }
}
