//! Scan matching parameters and the result of a match.

use scan_types::Pose2;

/// Tuning of [`MatchTarget::align`](crate::MatchTarget::align).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MatchParams {
    /// Most Gauss-Newton iterations.
    pub max_iterations: usize,
    /// Correspondence gate of the first iteration, metres (covers the guess's error).
    pub initial_gate_m: f64,
    /// The gate shrinks by this factor per iteration down to `final_gate_m`.
    pub gate_shrink: f64,
    /// Correspondence gate once converged, metres.
    pub final_gate_m: f64,
    /// Scale of the Cauchy weight of a point-to-line residual, metres.
    pub robust_scale_m: f64,
    /// Standard deviation of one point-to-line residual, metres (weights data against the prior).
    pub point_sigma_m: f64,
    /// Standard deviation of the guess's position, metres.
    pub prior_sigma_m: f64,
    /// Standard deviation of the guess's heading, radians.
    pub prior_sigma_rad: f64,
    /// Fewest matched points (within the final gate) for a result.
    pub min_pairs: usize,
    /// Largest RMS point-to-line residual of the matched points, metres.
    pub max_rms_m: f64,
    /// Neighbouring hits within this of each other lie on one surface, metres.
    pub surface_m: f64,
    /// Far hits: neighbours within this many ray spacings at the hit's range (range times
    /// the angular increment) also lie on one surface, and the fit spans as many; 0 keeps
    /// the fixed `surface_m` and `normal_half_length_m`.
    pub surface_spacings: f64,
    /// A hit's surface line is fitted over the hits of its surface within this distance of
    /// it on each side, metres.
    pub normal_half_length_m: f64,
    /// At most this many rays on each side enter the fit.
    pub normal_rays: usize,
    /// A hit's fit is a line when the members' variance across it is at most this share of
    /// their variance along it (members around a corner or a round post spread both ways).
    pub max_line_scatter: f64,
    /// Matched normals must agree within this angle, radians (front and back of a thin wall).
    pub max_normal_angle_rad: f64,
    /// Every `stride`-th hit of the scan being aligned enters the fit, weighted `stride`
    /// times (neighbouring hits on one surface say almost the same); the target keeps all.
    pub stride: usize,
}

impl Default for MatchParams {
    /// 40 iterations, gate 0.3 m shrinking by 0.7 to 0.06 m, 2 cm Cauchy scale and point
    /// sigma, prior 0.1 m / 2 deg, 40 pairs, RMS at most 3 cm, each hit's surface line fitted
    /// over +-0.1 m (at most 30 rays a side, neighbours within 0.15 m, variance across at most
    /// 0.1 of that along), normals within 60 deg,
    /// every second hit of the aligned scan.
    fn default() -> Self {
        Self {
            max_iterations: 40,
            initial_gate_m: 0.3,
            gate_shrink: 0.7,
            final_gate_m: 0.06,
            robust_scale_m: 0.02,
            point_sigma_m: 0.02,
            prior_sigma_m: 0.1,
            prior_sigma_rad: 2f64.to_radians(),
            min_pairs: 40,
            max_rms_m: 0.03,
            surface_m: 0.15,
            surface_spacings: 0.0,
            normal_half_length_m: 0.1,
            normal_rays: 30,
            max_line_scatter: 0.1,
            max_normal_angle_rad: 60f64.to_radians(),
            stride: 2,
        }
    }
}

/// The result of a match.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanMatch {
    /// The pose of the matched scan in the target's frame.
    pub pose: Pose2,
    /// RMS point-to-line residual of the matched points, metres.
    pub rms_m: f64,
    /// Hits matched within the final gate (each used point counts `stride` times).
    pub pairs: usize,
    /// Standard deviation of the position along its worst-constrained direction (data and
    /// prior together), metres: near `prior_sigma_m` in a featureless corridor.
    pub worst_sigma_m: f64,
    /// Standard deviation of the position along its worst-constrained direction from the
    /// data alone, metres (infinite when the data leave a direction free).
    pub data_worst_sigma_m: f64,
    /// Information matrix of (x, y, heading) from the data alone (no prior, no robust
    /// weights), in the target's frame.
    pub data_information: [[f64; 3]; 3],
    /// Iterations run.
    pub iterations: usize,
}

impl ScanMatch {
    /// The unit direction in which the data constrain the position least, and the
    /// standard deviation along it (infinite when the data leave it free).
    pub fn worst_direction(&self) -> ([f64; 2], f64) {
        worst_position_direction(&self.data_information)
    }
}

/// The least-constrained position direction of an information matrix `h` (x, y, heading)
/// once the heading is marginalised, and the standard deviation along it.
pub(crate) fn worst_position_direction(h: &[[f64; 3]; 3]) -> ([f64; 2], f64) {
    // Marginal information of (x, y): the Schur complement of the heading entry.
    let hth = h[2][2];
    let (a, b, d) = if hth > 0.0 {
        (
            h[0][0] - h[0][2] * h[2][0] / hth,
            h[0][1] - h[0][2] * h[2][1] / hth,
            h[1][1] - h[1][2] * h[2][1] / hth,
        )
    } else {
        (h[0][0], h[0][1], h[1][1])
    };
    // Smallest eigenvalue of [[a, b], [b, d]] and its eigenvector.
    let mean = 0.5 * (a + d);
    let rad = (0.25 * (a - d).powi(2) + b * b).sqrt();
    let lmin = mean - rad;
    let v = if b.abs() > 1e-12 * (a.abs() + d.abs()).max(1e-300) {
        [b, lmin - a]
    } else if a <= d {
        [1.0, 0.0]
    } else {
        [0.0, 1.0]
    };
    let n = v[0].hypot(v[1]);
    let dir = if n > 0.0 && n.is_finite() {
        [v[0] / n, v[1] / n]
    } else {
        [1.0, 0.0]
    };
    let sigma = if lmin > 1e-12 {
        1.0 / lmin.sqrt()
    } else {
        f64::INFINITY
    };
    (dir, sigma)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn worst_direction_of_a_diagonal_corridor() {
        // Walls along 45 deg: only their normal n = (-1, 1) / sqrt 2 is measured, 100 times
        // with information 1 each: h = 100 n n^T, heading independent.
        let h = [[50.0, -50.0, 0.0], [-50.0, 50.0, 0.0], [0.0, 0.0, 1.0]];
        let (dir, sigma) = worst_position_direction(&h);
        let half = std::f64::consts::FRAC_1_SQRT_2;
        assert!((dir[0].abs() - half).abs() < 1e-9 && (dir[0] - dir[1]).abs() < 1e-9);
        assert!(sigma.is_infinite());
        // Add information 4 along the corridor: sigma 1 / sqrt 4 = 0.5 along (1, 1) / sqrt 2.
        let h = [[52.0, -48.0, 0.0], [-48.0, 52.0, 0.0], [0.0, 0.0, 1.0]];
        let (dir, sigma) = worst_position_direction(&h);
        assert!((dir[0] - dir[1]).abs() < 1e-9 && (sigma - 0.5).abs() < 1e-9);
    }
}
