//! What detection finds: landmarks, their kinds and open sides, and their stability score.

use scan_types::RobotPoint;

use super::DetectParams;

/// What kind of feature a landmark is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LandmarkKind {
    /// The paper's landmark: a hit next to a max-range ray (`x` in A, `x +- n` not in A).
    MaxRangeJump,
    /// The nearer side of a range jump between two hits (an object's occluding edge).
    OcclusionEdge,
    /// Two straight arms of one surface meeting at an angle.
    Corner,
}

/// On which side of an edge landmark (in ray index order) the open or farther space lies.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OpenSide {
    /// Toward lower ray indices (clockwise, to the right of the edge).
    Lower,
    /// Toward higher ray indices (counter-clockwise, to the left of the edge).
    Higher,
    /// Both neighbours are open: a lone hit.
    Both,
}

/// A landmark found in one scan, in the robot frame of that scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Landmark {
    /// Index of the ray that sees the landmark.
    pub index: usize,
    /// Distance from the robot centre, metres.
    pub range_m: f64,
    /// Bearing from the heading (central ray), radians.
    pub bearing_rad: f64,
    /// What kind of feature it is.
    pub kind: LandmarkKind,
    /// Where the open (or farther) space lies, for edges; `None` for corners.
    pub open_side: Option<OpenSide>,
    /// The hit lies within `range_limit_margin_m` of the maximum range.
    pub near_range_limit: bool,
    /// The surface extrapolated one ray into the gap reaches the far side: a wall running out
    /// of range or seen at a grazing angle, not the end of an object.
    pub surface_continues: bool,
    /// Part of the landmark's own surface lies between it and the path ahead: the side ray
    /// will probably not see it.
    pub hidden_at_side: bool,
    /// Hits on the landmark's surface within `arm_m` (including the landmark ray).
    pub support_rays: usize,
    /// Stability score in (0, 1]: 1 for a clean feature, lower for each flag raised.
    pub score: f64,
}

impl Landmark {
    /// The landmark point in the robot frame.
    pub fn robot_point(&self) -> RobotPoint {
        RobotPoint::new(
            self.range_m * self.bearing_rad.cos(),
            self.range_m * self.bearing_rad.sin(),
        )
    }

    /// True when no stability flag is raised.
    pub fn is_stable(&self) -> bool {
        !(self.near_range_limit || self.surface_continues || self.hidden_at_side)
    }
}

/// Stability score: each raised flag multiplies it down.
pub(super) fn score(l: &Landmark, params: &DetectParams) -> f64 {
    let mut s = 1.0;
    if l.near_range_limit {
        s *= 0.2;
    }
    if l.surface_continues {
        s *= 0.2;
    }
    if l.hidden_at_side {
        s *= 0.3;
    }
    if l.support_rays < params.min_support_rays.max(3) {
        s *= 0.5;
    }
    s
}
