//! Alignment: point-to-line ICP of a scan against a target, with the prior at the guess.

use scan_types::{Pose2, Scan, ScanGeometry, normalize_angle_rad};

use super::surface::{Oriented, oriented_hits};
use super::target::Hold;
use super::{MatchParams, MatchTarget, ScanMatch};

/// A 3 x 3 matrix (x, y, theta), row-major.
type Mat3 = [[f64; 3]; 3];

impl MatchTarget {
    /// The pose of `scan` in the target's frame, starting from `guess`; `None` when too few
    /// points match or they fit badly.
    pub fn align(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        guess: Pose2,
        params: &MatchParams,
    ) -> Option<ScanMatch> {
        self.index();
        let stride = params.stride.max(1);
        let cur = oriented_hits(geometry, scan, params, stride);
        if cur.len() * stride < params.min_pairs || self.points.len() < params.min_pairs {
            return None;
        }
        let min_cos = params.max_normal_angle_rad.cos();
        let w_pt = stride as f64 / params.point_sigma_m.powi(2);
        let prior = [
            1.0 / params.prior_sigma_m.powi(2),
            1.0 / params.prior_sigma_m.powi(2),
            1.0 / params.prior_sigma_rad.powi(2),
        ];
        let g0 = [guess.x_m, guess.y_m, guess.theta_rad];
        let mut x = g0;
        let mut gate = params.initial_gate_m.max(params.final_gate_m);
        let mut iterations = 0;
        let mut last = None;
        let mut prev_step = None;
        // Each point's match (or that it had none) in the previous iteration, a hint for the
        // next search, with where its search was made and how far that answer holds.
        let mut matched: Vec<Option<Held>> = vec![None; cur.len()];
        for it in 0..params.max_iterations.max(1) {
            iterations = it + 1;
            let (mut h, h_data, mut g, sq, pairs) =
                self.linearise(&cur, &mut matched, x, (gate, min_cos), w_pt, params);
            let dx = [
                x[0] - g0[0],
                x[1] - g0[1],
                normalize_angle_rad(x[2] - g0[2]),
            ];
            for a in 0..3 {
                h[a][a] += prior[a];
                g[a] += prior[a] * dx[a];
            }
            let step = solve3(&h, &[-g[0], -g[1], -g[2]])?;
            for a in 0..3 {
                x[a] += step[a];
            }
            x[2] = normalize_angle_rad(x[2]);
            last = Some((h, h_data, sq, pairs));
            let small = step[0].hypot(step[1]) < 1e-5 && step[2].abs() < 1e-5;
            if small && gate <= params.final_gate_m {
                break;
            }
            if gate <= params.final_gate_m {
                // A step that undoes the previous one: correspondences flipping back and
                // forth between two poses, which further iterations only repeat.
                if prev_step
                    .is_some_and(|p: [f64; 3]| (0..3).all(|a| (step[a] + p[a]).abs() < 1e-8))
                {
                    break;
                }
                prev_step = Some(step);
            }
            gate = (gate * params.gate_shrink).max(params.final_gate_m);
        }
        finish(last?, x, iterations, stride, params)
    }

    /// One Gauss-Newton linearisation at `x`: matches each point within the search gate
    /// (`gate`, `min_cos`), updating its hint, and sums the robust and the data-only normal
    /// equations (h, h_data, g) and the squared residuals and count of the final-gate pairs.
    fn linearise(
        &self,
        cur: &[Oriented],
        matched: &mut [Option<Held>],
        x: [f64; 3],
        (gate, min_cos): (f64, f64),
        w_pt: f64,
        params: &MatchParams,
    ) -> (Mat3, Mat3, [f64; 3], f64, usize) {
        let (s, c) = x[2].sin_cos();
        let mut h = [[0.0f64; 3]; 3];
        let mut h_data = [[0.0f64; 3]; 3];
        let mut g = [0.0f64; 3];
        let (mut sq, mut pairs) = (0.0, 0usize);
        for (o, hint) in cur.iter().zip(matched.iter_mut()) {
            let q = [
                x[0] + c * o.p[0] - s * o.p[1],
                x[1] + s * o.p[0] + c * o.p[1],
            ];
            let n_cur = [c * o.n[0] - s * o.n[1], s * o.n[0] + c * o.n[1]];
            let rechecked = hint.as_ref().and_then(|h| {
                let moved = ((q[0] - h.q[0]).powi(2) + (q[1] - h.q[1]).powi(2)).sqrt();
                let turn = normalize_angle_rad(x[2] - h.theta);
                self.recheck(&h.hold, (q, n_cur), (moved, turn), gate, min_cos)
            });
            if let (Some(k), Some(h)) = (rechecked, hint.as_mut()) {
                h.k = k;
            } else {
                *hint = self
                    .nearest_held(q, n_cur, gate, min_cos, hint.and_then(|h| h.k))
                    .map(|(k, hold)| Held {
                        k,
                        q,
                        theta: x[2],
                        hold,
                    });
            }
            let Some(m) = hint.and_then(|h| h.k).map(|k| &self.sorted[k]) else {
                continue;
            };
            let r = m.n[0] * (q[0] - m.p[0]) + m.n[1] * (q[1] - m.p[1]);
            // d q / d theta = (-s px - c py, c px - s py).
            let dq = [-s * o.p[0] - c * o.p[1], c * o.p[0] - s * o.p[1]];
            let j = [m.n[0], m.n[1], m.n[0] * dq[0] + m.n[1] * dq[1]];
            let u = r / params.robust_scale_m;
            let w = w_pt / (1.0 + u * u);
            for a in 0..3 {
                g[a] += w * j[a] * r;
                for b in 0..3 {
                    h[a][b] += w * j[a] * j[b];
                    h_data[a][b] += w_pt * j[a] * j[b];
                }
            }
            if r.abs() <= params.final_gate_m {
                sq += r * r;
                pairs += 1;
            }
        }
        (h, h_data, g, sq, pairs)
    }
}

/// A point's match (or that it has none), where the search for it was made (query point and
/// heading) and how far that answer holds: while it does, the search is not repeated.
#[derive(Debug, Clone, Copy)]
struct Held {
    k: Option<usize>,
    q: [f64; 2],
    theta: f64,
    hold: Hold,
}

/// The match from the last iteration's normal equations and fit (h, h_data, sq, used) at `x`,
/// if enough pairs fit well enough.
fn finish(
    last: (Mat3, Mat3, f64, usize),
    x: [f64; 3],
    iterations: usize,
    stride: usize,
    params: &MatchParams,
) -> Option<ScanMatch> {
    let (h, h_data, sq, used) = last;
    let rms = (sq / used as f64).sqrt();
    // Each used point stands for `stride` hits.
    let pairs = used * stride;
    if pairs < params.min_pairs {
        tracing::debug!(pairs, "scan match: too few pairs");
        return None;
    }
    if rms > params.max_rms_m {
        tracing::debug!(rms, "scan match: poor fit");
        return None;
    }
    Some(ScanMatch {
        pose: Pose2::new(x[0], x[1], x[2]),
        rms_m: rms,
        pairs,
        worst_sigma_m: worst_position_sigma(&h),
        data_worst_sigma_m: worst_position_sigma(&h_data),
        data_information: h_data,
        iterations,
    })
}

/// Standard deviation along the worst direction of the position block of the covariance
/// `h^-1` (3 x 3 information matrix: x, y, theta).
fn worst_position_sigma(h: &[[f64; 3]; 3]) -> f64 {
    super::params::worst_position_direction(h).1
}

/// Solves the 3 x 3 system `a x = b` by Gaussian elimination with partial pivoting.
fn solve3(a: &[[f64; 3]; 3], b: &[f64; 3]) -> Option<[f64; 3]> {
    let mut m = [[0.0f64; 4]; 3];
    for r in 0..3 {
        m[r][..3].copy_from_slice(&a[r]);
        m[r][3] = b[r];
    }
    for col in 0..3 {
        let piv = (col..3).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if m[piv][col].abs() < 1e-12 {
            return None;
        }
        m.swap(col, piv);
        for r in 0..3 {
            if r != col {
                let f = m[r][col] / m[col][col];
                let pivot_row = m[col];
                for (v, p) in m[r].iter_mut().zip(pivot_row).skip(col) {
                    *v -= f * p;
                }
            }
        }
    }
    let x = [m[0][3] / m[0][0], m[1][3] / m[1][1], m[2][3] / m[2][2]];
    x.iter().all(|v| v.is_finite()).then_some(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scanmatch::fixtures::{cast, room};

    #[test]
    fn recovers_a_known_motion_in_a_room() {
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        let a = Pose2::new(-1.0, -0.5, 0.3);
        let b = Pose2::new(-0.4, -0.3, 0.35);
        let rel = a.inverse().compose(&b);
        let mut t = MatchTarget::from_scan(&g, &cast(&room(), a, None), &p);
        // Guess 8 cm short and 3 cm aside, heading 1 deg off.
        let guess = Pose2::new(rel.x_m - 0.08, rel.y_m + 0.03, rel.theta_rad + 0.017);
        let m = t.align(&g, &cast(&room(), b, None), guess, &p).unwrap();
        assert!((m.pose.x_m - rel.x_m).abs() < 2e-3, "{m:?} vs {rel:?}");
        assert!((m.pose.y_m - rel.y_m).abs() < 2e-3, "{m:?} vs {rel:?}");
        assert!((m.pose.theta_rad - rel.theta_rad).abs() < 1e-3, "{m:?}");
        assert!(m.rms_m < 0.005 && m.pairs > 300, "{m:?}");
        assert!(m.data_worst_sigma_m < 0.01, "{m:?}");
    }

    #[test]
    fn every_stride_recovers_the_motion() {
        let g = ScanGeometry::paper();
        let a = Pose2::new(-1.0, -0.5, 0.3);
        let b = Pose2::new(-0.4, -0.3, 0.35);
        let rel = a.inverse().compose(&b);
        let (sa, sb) = (cast(&room(), a, Some(3)), cast(&room(), b, Some(4)));
        let guess = Pose2::new(rel.x_m - 0.05, rel.y_m + 0.02, rel.theta_rad - 0.01);
        let mut found: Vec<ScanMatch> = Vec::new();
        for stride in [1, 2, 3] {
            let p = MatchParams {
                stride,
                ..MatchParams::default()
            };
            let m = MatchTarget::from_scan(&g, &sa, &p)
                .align(&g, &sb, guess, &p)
                .unwrap();
            // Within 1 cm and 0.06 deg of the truth (1 cm range noise), and within 3 mm of
            // what every hit gives.
            assert!(
                m.pose.position().distance_m(&rel.position()) < 0.01,
                "{stride}: {m:?}"
            );
            assert!(
                (m.pose.theta_rad - rel.theta_rad).abs() < 1e-3,
                "{stride}: {m:?}"
            );
            if let Some(all) = found.first() {
                assert!(
                    m.pose.position().distance_m(&all.pose.position()) < 3e-3,
                    "{m:?}"
                );
            }
            found.push(m);
        }
        let pairs: Vec<f64> = found.iter().map(|m| m.pairs as f64).collect();
        // The pair count stands for the hits, whatever the stride.
        assert!(
            pairs.iter().all(|&p| (p / pairs[0] - 1.0).abs() < 0.05),
            "{pairs:?}"
        );
    }

    #[test]
    fn noisy_scans_match_within_millimetres() {
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        let a = Pose2::new(0.0, -1.0, 1.0);
        let b = a.advanced(1.0);
        let mut t = MatchTarget::from_scan(&g, &cast(&room(), a, Some(1)), &p);
        let m = t
            .align(
                &g,
                &cast(&room(), b, Some(2)),
                Pose2::new(0.95, 0.0, 0.0),
                &p,
            )
            .unwrap();
        assert!((m.pose.x_m - 1.0).abs() < 0.005, "{m:?}");
        assert!(m.pose.y_m.abs() < 0.005, "{m:?}");
        assert!(m.pose.theta_rad.abs() < 0.002, "{m:?}");
    }

    #[test]
    fn a_corridor_keeps_the_guess_along_its_length() {
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        // Two parallel walls 1.6 m apart, far longer than the range.
        let walls = [[-20.0, -0.8, 20.0, -0.8], [-20.0, 0.8, 20.0, 0.8]];
        let a = Pose2::new(0.0, 0.0, 0.0);
        let b = Pose2::new(0.5, 0.1, 0.0);
        let mut t = MatchTarget::from_scan(&g, &cast(&walls, a, None), &p);
        let m = t
            .align(&g, &cast(&walls, b, None), Pose2::new(0.42, 0.0, 0.0), &p)
            .unwrap();
        // Across: measured; along: the data say nothing, the guess stays.
        assert!((m.pose.y_m - 0.1).abs() < 1e-3, "{m:?}");
        assert!((m.pose.x_m - 0.42).abs() < 1e-3, "{m:?}");
        assert!(m.data_worst_sigma_m > 1.0, "{m:?}");
        assert!((m.worst_sigma_m - p.prior_sigma_m).abs() < 0.01, "{m:?}");
        // The free direction is along the walls (x).
        let (dir, sigma) = m.worst_direction();
        assert!(dir[0].abs() > 0.999 && sigma > 1.0, "{dir:?} {sigma}");
    }

    #[test]
    fn matches_against_two_scans_in_a_common_frame() {
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        let a = Pose2::new(-2.0, -1.0, 0.0);
        let b = Pose2::new(0.0, -1.0, 1.2);
        let c = Pose2::new(0.3, 0.2, 2.0);
        let mut t = MatchTarget::new();
        t.add_scan(&a, &g, &cast(&room(), a, None), &p);
        t.add_scan(&b, &g, &cast(&room(), b, None), &p);
        let guess = Pose2::new(0.36, 0.16, 2.02);
        let m = t.align(&g, &cast(&room(), c, None), guess, &p).unwrap();
        assert!(m.pose.position().distance_m(&c.position()) < 2e-3, "{m:?}");
        assert!((m.pose.theta_rad - 2.0).abs() < 1e-3, "{m:?}");
    }

    #[test]
    fn targets_placed_in_a_common_frame_match_like_their_scans() {
        // Each scan's target built once in its own frame, then placed at the scan's pose.
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        let a = Pose2::new(-2.0, -1.0, 0.0);
        let b = Pose2::new(0.0, -1.0, 1.2);
        let c = Pose2::new(0.3, 0.2, 2.0);
        let mut t = MatchTarget::new();
        for pose in [a, b] {
            t.add_target(
                &pose,
                &MatchTarget::from_scan(&g, &cast(&room(), pose, None), &p),
            );
        }
        let guess = Pose2::new(0.36, 0.16, 2.02);
        let m = t.align(&g, &cast(&room(), c, None), guess, &p).unwrap();
        assert!(m.pose.position().distance_m(&c.position()) < 2e-3, "{m:?}");
        assert!((m.pose.theta_rad - 2.0).abs() < 1e-3, "{m:?}");
    }

    #[test]
    fn nothing_to_match_is_none() {
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        let open = Scan::from_ranges(&g, &vec![g.max_range_m; g.ray_count], 0.0);
        let mut t = MatchTarget::from_scan(&g, &open, &p);
        assert!(t.is_empty());
        let s = cast(&room(), Pose2::default(), None);
        assert!(t.align(&g, &s, Pose2::default(), &p).is_none());
    }

    #[test]
    fn solves_a_small_system() {
        // 2x + y = 5, x + 3y + z = 10, y + 4z = 11 -> (2, 1, 2.5).
        let a = [[2.0, 1.0, 0.0], [1.0, 3.0, 1.0], [0.0, 1.0, 4.0]];
        let x = solve3(&a, &[5.0, 7.5, 11.0]).unwrap();
        assert!((x[0] - 2.0).abs() < 1e-12 && (x[1] - 1.0).abs() < 1e-12);
        assert!((x[2] - 2.5).abs() < 1e-12);
        assert!(
            solve3(
                &[[1.0, 0.0, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
                &[1.0; 3]
            )
            .is_none()
        );
    }
}
