//! Detection parameters, the paper's and permissive presets, and their validation.

use scan_types::ScanGeometry;

use crate::LandmarksError;

/// Every rule of landmark detection; see `docs/landmarks.md`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectParams {
    /// The paper's `n`: ray `x` in A and ray `x + n` or `x - n` a hit makes a landmark.
    pub neighbour_n: usize,
    /// Detect the paper's max-range jumps.
    pub max_range_jumps: bool,
    /// Detect occlusion edges (range jumps between two hits).
    pub occlusion_edges: bool,
    /// Smallest range difference between neighbouring hits that is a jump, metres.
    pub occlusion_jump_m: f64,
    /// Detect corners.
    pub corners: bool,
    /// Length of surface used on each side of a feature (support, line fits), metres.
    pub arm_m: f64,
    /// Smallest turn between the two arms of a corner (0 = straight wall), radians.
    pub corner_min_angle_rad: f64,
    /// Largest RMS distance of an arm's hits from its fitted line, metres.
    pub corner_max_residual_m: f64,
    /// Fewest hits on each arm of a corner, besides the corner ray.
    pub corner_min_arm_rays: usize,
    /// Place an edge half a ray toward the open side, on its fitted surface line (the true
    /// end lies anywhere between the edge ray and the open ray: the middle halves the error).
    pub edge_refine: bool,
    /// Place a corner where its two fitted arms intersect instead of at the corner ray's hit.
    pub corner_refine: bool,
    /// A hit this close to the maximum range is flagged `near_range_limit`, metres ...
    pub range_limit_margin_m: f64,
    /// ... or this many range gaps between neighbouring hits on a wall 1 m to the side at the
    /// maximum range (r_max^2 times the ray spacing, per metre), when that is more: a
    /// longer-ranged scanner's last hit on a receding wall lies farther inside its limit (0:
    /// the margin alone; a margin of 0 keeps the flag off).
    pub range_limit_gaps: f64,
    /// Drop landmarks flagged `near_range_limit`.
    pub reject_near_range_limit: bool,
    /// Drop edges whose surface continues past them (`surface_continues`).
    pub reject_surface_continues: bool,
    /// Drop landmarks flagged `hidden_at_side`.
    pub reject_hidden_at_side: bool,
    /// Drop landmarks with fewer supporting hits than this (1 keeps a lone hit).
    pub min_support_rays: usize,
    /// Fewest max-range rays in a row next to a jump edge (1 = the paper: a single miss in a
    /// wall makes two landmarks).
    pub min_open_rays: usize,
    /// An open run bounded by hits on both sides is open space only if those two hits lie at
    /// least this far apart, metres; a narrower run is a dropout (dark, glossy or glancing
    /// surface) or a gap nothing fits through (0 = the paper: every run counts).
    pub min_gap_width_m: f64,
    /// Drop a jump whose open run is narrower than `dropout_max_width_m` and whose surface,
    /// extended across the run, meets the hit on the run's far side (within 0.1 m + 5 %):
    /// the surface continues through the run, a sensor dropout (a real URG-04LX reads no
    /// return on dark or glossy surfaces) or a slot too narrow for the robot.
    pub reject_bridged_dropouts: bool,
    /// Widest open run `reject_bridged_dropouts` treats as a dropout, metres (a door in a
    /// straight wall is bridged too, but wider than this).
    pub dropout_max_width_m: f64,
    /// Invalid (error) rays skipped between two valid rays; a longer gap splits the scan.
    pub max_skipped_errors: usize,
}

impl Default for DetectParams {
    /// goalseek's defaults: all kinds, range-limit and continuing-surface edges rejected.
    fn default() -> Self {
        Self {
            neighbour_n: 1,
            max_range_jumps: true,
            occlusion_edges: true,
            occlusion_jump_m: 0.3,
            corners: true,
            arm_m: 0.2,
            corner_min_angle_rad: 40f64.to_radians(),
            corner_max_residual_m: 0.02,
            corner_min_arm_rays: 3,
            corner_refine: true,
            edge_refine: true,
            range_limit_margin_m: 0.1,
            range_limit_gaps: 0.0,
            reject_near_range_limit: true,
            reject_surface_continues: true,
            reject_hidden_at_side: false,
            min_support_rays: 2,
            min_open_rays: 3,
            min_gap_width_m: 0.25,
            reject_bridged_dropouts: true,
            dropout_max_width_m: 0.7,
            max_skipped_errors: 3,
        }
    }
}

impl DetectParams {
    /// The paper as written: max-range jumps with `n = 1`, nothing rejected (the stability
    /// flags are still computed, with goalseek's margins, for inspection).
    pub fn paper() -> Self {
        Self {
            neighbour_n: 1,
            max_range_jumps: true,
            occlusion_edges: false,
            corners: false,
            edge_refine: false,
            reject_near_range_limit: false,
            reject_surface_continues: false,
            reject_hidden_at_side: false,
            min_support_rays: 1,
            min_open_rays: 1,
            min_gap_width_m: 0.0,
            reject_bridged_dropouts: false,
            ..Self::default()
        }
    }

    /// The range-limit margin for a scanner of `geometry`: `range_limit_margin_m`, grown to
    /// `range_limit_gaps` of its range gaps when that is more, metres.
    pub fn range_limit_margin_for(&self, geometry: &ScanGeometry) -> f64 {
        if self.range_limit_margin_m <= 0.0 {
            return self.range_limit_margin_m;
        }
        let gap_m = geometry.max_range_m.powi(2) * geometry.increment_rad.abs();
        self.range_limit_margin_m.max(self.range_limit_gaps * gap_m)
    }

    /// Every kind detected and nothing rejected (flags still set): what a tracker
    /// re-identifies against.
    pub fn permissive(&self) -> Self {
        Self {
            max_range_jumps: true,
            occlusion_edges: true,
            corners: true,
            reject_near_range_limit: false,
            reject_surface_continues: false,
            reject_hidden_at_side: false,
            min_support_rays: 1,
            min_open_rays: 1,
            min_gap_width_m: 0.0,
            reject_bridged_dropouts: false,
            ..*self
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), LandmarksError> {
        let bad = |field, value, why| Err(LandmarksError::InvalidParam { field, value, why });
        if self.neighbour_n == 0 {
            return bad("neighbour_n", 0.0, "must be at least 1");
        }
        let positive = [
            ("occlusion_jump_m", self.occlusion_jump_m),
            ("arm_m", self.arm_m),
            ("corner_max_residual_m", self.corner_max_residual_m),
        ];
        for (field, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return bad(field, v, "must be finite and > 0");
            }
        }
        if !(self.range_limit_margin_m.is_finite() && self.range_limit_margin_m >= 0.0) {
            return bad(
                "range_limit_margin_m",
                self.range_limit_margin_m,
                "must be finite and >= 0",
            );
        }
        if !(self.range_limit_gaps.is_finite() && self.range_limit_gaps >= 0.0) {
            return bad(
                "range_limit_gaps",
                self.range_limit_gaps,
                "must be finite and >= 0",
            );
        }
        let a = self.corner_min_angle_rad;
        if !(a.is_finite() && a > 0.0 && a < std::f64::consts::PI) {
            return bad("corner_min_angle_rad", a, "must lie in (0, pi)");
        }
        Ok(())
    }
}
