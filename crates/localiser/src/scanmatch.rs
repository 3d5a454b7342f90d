//! Scan matching: the pose of a scan relative to reference scans, by point-to-line ICP with a
//! prior that holds the directions the geometry does not constrain (a corridor's length) at
//! the initial guess.

use scan_types::{Pose2, RobotPoint, Scan, ScanGeometry, normalize_angle_rad};

/// Tuning of [`MatchTarget::align`].
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
    /// A hit's surface line is fitted over the hits of its surface within this distance of
    /// it on each side, metres.
    pub normal_half_length_m: f64,
    /// At most this many rays on each side enter the fit.
    pub normal_rays: usize,
    /// Matched normals must agree within this angle, radians (front and back of a thin wall).
    pub max_normal_angle_rad: f64,
    /// Every `stride`-th hit of the scan being aligned enters the fit, weighted `stride`
    /// times (neighbouring hits on one surface say almost the same); the target keeps all.
    pub stride: usize,
}

impl Default for MatchParams {
    /// 40 iterations, gate 0.3 m shrinking by 0.7 to 0.06 m, 2 cm Cauchy scale and point
    /// sigma, prior 0.1 m / 2 deg, 40 pairs, RMS at most 3 cm, each hit's surface line fitted
    /// over +-0.1 m (at most 30 rays a side, neighbours within 0.15 m), normals within 60 deg,
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
            normal_half_length_m: 0.1,
            normal_rays: 30,
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
    /// Iterations run.
    pub iterations: usize,
}

/// A hit point with its surface normal (unit, pointing toward the sensor that saw it).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Oriented {
    p: [f64; 2],
    n: [f64; 2],
}

/// Side of a cell of the nearest-neighbour index, metres.
const CELL_M: f64 = 0.04;

/// Radius of the first, narrow nearest-neighbour search, metres.
const NEAR_M: f64 = 0.02;

/// Reference points (hits with surface normals) in one frame, indexed for nearest-neighbour
/// search.
#[derive(Debug, Clone)]
pub struct MatchTarget {
    points: Vec<Oriented>,
    /// Lower-left corner of cell (0, 0) and the grid size.
    origin: [f64; 2],
    width: usize,
    height: usize,
    /// Cell start offsets into `sorted` (width * height + 1 entries).
    starts: Vec<u32>,
    /// The points sorted by cell (by index within a cell).
    sorted: Vec<Oriented>,
    dirty: bool,
}

impl Default for MatchTarget {
    fn default() -> Self {
        Self::new()
    }
}

impl MatchTarget {
    /// An empty target.
    pub fn new() -> Self {
        Self {
            points: Vec::new(),
            origin: [0.0, 0.0],
            width: 0,
            height: 0,
            starts: Vec::new(),
            sorted: Vec::new(),
            dirty: false,
        }
    }

    /// A target holding one scan, in that scan's own frame.
    pub fn from_scan(geometry: &ScanGeometry, scan: &Scan, params: &MatchParams) -> Self {
        let mut t = Self::new();
        t.add_scan(&Pose2::default(), geometry, scan, params);
        t
    }

    /// Number of reference points (hits with a fitted normal).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the target holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Adds the hits of `scan` taken at `pose` (in the target's frame) that have a surface normal.
    pub fn add_scan(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        scan: &Scan,
        params: &MatchParams,
    ) {
        let (s, c) = pose.theta_rad.sin_cos();
        for o in oriented_hits(geometry, scan, params, 1) {
            self.points.push(Oriented {
                p: [
                    pose.x_m + c * o.p[0] - s * o.p[1],
                    pose.y_m + s * o.p[0] + c * o.p[1],
                ],
                n: [c * o.n[0] - s * o.n[1], s * o.n[0] + c * o.n[1]],
            });
        }
        self.dirty = true;
    }

    fn index(&mut self) {
        if !self.dirty {
            return;
        }
        self.dirty = false;
        self.sorted.clear();
        self.starts.clear();
        // Non-finite points can never match: leave them out of the index.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for o in self.points.iter().filter(|o| is_finite2(o.p)) {
            for k in 0..2 {
                lo[k] = lo[k].min(o.p[k]);
                hi[k] = hi[k].max(o.p[k]);
            }
        }
        if lo[0] > hi[0] {
            self.width = 0;
            self.height = 0;
            return;
        }
        self.origin = lo;
        self.width = floor_nonneg((hi[0] - lo[0]) / CELL_M) + 1;
        self.height = floor_nonneg((hi[1] - lo[1]) / CELL_M) + 1;
        let cells = self.width * self.height;
        // Counting sort: points per cell, then each cell's end, then filled from the back.
        let mut starts = vec![0u32; cells + 1];
        let cell_of: Vec<Option<usize>> = self
            .points
            .iter()
            .map(|o| is_finite2(o.p).then(|| self.cell(o.p)))
            .collect();
        for &c in cell_of.iter().flatten() {
            starts[c] += 1;
        }
        let mut end = 0u32;
        for v in &mut starts {
            end += *v;
            *v = end;
        }
        let placeholder = Oriented {
            p: [0.0; 2],
            n: [0.0; 2],
        };
        self.sorted = vec![placeholder; end as usize];
        for (o, c) in self.points.iter().zip(&cell_of).rev() {
            if let Some(c) = *c {
                starts[c] -= 1;
                self.sorted[starts[c] as usize] = *o;
            }
        }
        // Now `starts[c]` is where cell c begins and `starts[cells]` the total.
        self.starts = starts;
    }

    fn cell(&self, p: [f64; 2]) -> usize {
        let cx = floor_nonneg((p[0] - self.origin[0]) / CELL_M).min(self.width - 1);
        let cy = floor_nonneg((p[1] - self.origin[1]) / CELL_M).min(self.height - 1);
        cy * self.width + cx
    }

    /// The reference point nearest `q` within `gate` whose normal agrees with `n`, as an
    /// index into `sorted`, given the index of a point `hint` that is probably near `q` (the
    /// match of the previous iteration).
    ///
    /// First searches the cells within `min(gate, NEAR_M, distance to the hint)` of `q`: a
    /// point found there nearer than that radius is the nearest overall (every point
    /// outside those cells lies farther away). Otherwise searches every cell within `gate`.
    fn nearest_hinted(
        &self,
        q: [f64; 2],
        n: [f64; 2],
        gate: f64,
        min_cos: f64,
        hint: Option<usize>,
    ) -> Option<usize> {
        if self.width == 0 || !is_finite2(q) || gate.is_nan() || gate < 0.0 {
            return None;
        }
        let mut near = gate.min(NEAR_M);
        if let Some(o) = hint.and_then(|k| self.sorted.get(k)) {
            let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
            if d2 <= gate * gate && o.n[0] * n[0] + o.n[1] * n[1] >= min_cos {
                // The hint lies within this radius with room for the margin below.
                near = near.min(d2.sqrt() + 2e-9);
            }
        }
        if let Some((d2, k)) = self.nearest_in(q, n, near, gate, min_cos) {
            // Margin for the rounding of cell assignment.
            let sure = (near - 1e-9).max(0.0);
            if d2 < sure * sure || near >= gate {
                return Some(k);
            }
        } else if near >= gate {
            return None;
        }
        self.nearest_in(q, n, gate, gate, min_cos).map(|(_, k)| k)
    }

    /// The nearest point within `gate` (squared distance and index into `sorted`) among the
    /// cells within `reach` of `q`.
    fn nearest_in(
        &self,
        q: [f64; 2],
        n: [f64; 2],
        reach: f64,
        gate: f64,
        min_cos: f64,
    ) -> Option<(f64, usize)> {
        let fx = (q[0] - self.origin[0]) / CELL_M;
        let fy = (q[1] - self.origin[1]) / CELL_M;
        let r = reach / CELL_M;
        let (wmax, hmax) = ((self.width - 1) as f64, (self.height - 1) as f64);
        let x1 = floor(fx + r);
        let y1 = floor(fy + r);
        if x1 < 0.0 || y1 < 0.0 {
            return None;
        }
        let x0 = floor(fx - r).max(0.0);
        let y0 = floor(fy - r).max(0.0);
        if x0 > wmax || y0 > hmax {
            return None;
        }
        let (x0, x1) = (x0 as usize, x1.min(wmax) as usize);
        let (y0, y1) = (y0 as usize, y1.min(hmax) as usize);
        let g2 = gate * gate;
        let mut best: Option<(f64, usize)> = None;
        for cy in y0..=y1 {
            let row = cy * self.width;
            // The cells of one row are contiguous in `sorted`.
            let first = self.starts[row + x0] as usize;
            let span = first..self.starts[row + x1 + 1] as usize;
            for (k, o) in self.sorted[span].iter().enumerate() {
                let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
                if d2 > g2 || o.n[0] * n[0] + o.n[1] * n[1] < min_cos {
                    continue;
                }
                if best.is_none_or(|(b, _)| d2 < b) {
                    best = Some((d2, first + k));
                }
            }
        }
        best
    }

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
        // Each point's match in the previous iteration (a hint for the next search).
        let mut matched: Vec<Option<usize>> = vec![None; cur.len()];
        for it in 0..params.max_iterations.max(1) {
            iterations = it + 1;
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
                *hint = self.nearest_hinted(q, n_cur, gate, min_cos, *hint);
                let Some(m) = hint.map(|k| &self.sorted[k]) else {
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
        let (h, h_data, sq, used) = last?;
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
            iterations,
        })
    }
}

/// True when both coordinates are finite.
fn is_finite2(p: [f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// `x.floor()` for finite `x` of magnitude below 2^52 without a libm call (the baseline
/// x86-64 target has no rounding instruction).
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

/// `floor(x)` as an index, for finite `x >= 0`.
fn floor_nonneg(x: f64) -> usize {
    x as usize
}

/// Standard deviation along the worst direction of the position block of the covariance
/// `h^-1` (3 x 3 information matrix: x, y, theta).
fn worst_position_sigma(h: &[[f64; 3]; 3]) -> f64 {
    // Marginal covariance of (x, y): the top-left block of h^-1, from the Schur complement
    // of the heading entry.
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
    // Smallest eigenvalue of the 2 x 2 information block [[a, b], [b, d]].
    let mean = 0.5 * (a + d);
    let rad = (0.25 * (a - d).powi(2) + b * b).sqrt();
    let lmin = mean - rad;
    if lmin > 1e-12 {
        1.0 / lmin.sqrt()
    } else {
        f64::INFINITY
    }
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

/// The hits of `scan` (robot frame) with a surface normal fitted over their neighbours on the
/// same surface; hits without a clear line through their neighbours are left out.
fn oriented_hits(
    geometry: &ScanGeometry,
    scan: &Scan,
    params: &MatchParams,
    stride: usize,
) -> Vec<Oriented> {
    let n = geometry.ray_count.min(scan.len());
    let dirs = geometry.directions();
    let pts: Vec<Option<RobotPoint>> = (0..n)
        .map(|i| {
            scan.hit_range_m(i)
                .filter(|r| r.is_finite() && *r > 0.0)
                .map(|r| RobotPoint::new(r * dirs[i][0], r * dirs[i][1]))
        })
        .collect();
    let k = params.normal_rays.max(1);
    let mut out = Vec::with_capacity(n);
    // Squared thresholds: no square root per neighbour.
    let surface2 = params.surface_m * params.surface_m;
    let half2 = params.normal_half_length_m * params.normal_half_length_m;
    for i in (0..n).step_by(stride.max(1)) {
        let Some(p) = pts[i] else { continue };
        let (px, py) = (p.x_m(), p.y_m());
        // Walk outwards on each side while the hits stay on the surface, summing the members'
        // coordinates relative to the hit (one pass, nothing stored).
        let (mut m, mut sx, mut sy, mut sxx, mut syy, mut sxy) = (1.0, 0.0, 0.0, 0.0, 0.0, 0.0);
        for dir in [-1i64, 1] {
            let mut prev = (px, py);
            for step in 1..=k as i64 {
                let j = i as i64 + dir * step;
                if j < 0 || j >= n as i64 {
                    break;
                }
                let Some(q) = pts[j as usize] else { break };
                let q = (q.x_m(), q.y_m());
                if (q.0 - prev.0).powi(2) + (q.1 - prev.1).powi(2) > surface2
                    || (q.0 - px).powi(2) + (q.1 - py).powi(2) > half2
                {
                    break;
                }
                let (dx, dy) = (q.0 - px, q.1 - py);
                m += 1.0;
                sx += dx;
                sy += dy;
                sxx += dx * dx;
                syy += dy * dy;
                sxy += dx * dy;
                prev = q;
            }
        }
        if m < 3.0 {
            continue;
        }
        // The members' mean relative to the hit, and their scatter about it.
        let (mx, my) = (sx / m, sy / m);
        let sxx = sxx - sx * mx;
        let syy = syy - sy * my;
        let sxy = sxy - sx * my;
        let mean = 0.5 * (sxx + syy);
        let rad = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
        let (lmax, lmin) = (mean + rad, mean - rad);
        // Not a line: scattered points (a corner's tip or noise as large as the spread).
        if lmax <= 0.0 || lmin > 0.1 * lmax {
            continue;
        }
        // Direction of the fitted line: the principal axis, at half the angle a2 of (sxx -
        // syy, 2 sxy) (length r = 2 rad > 0 here); the normal is perpendicular. Half-angle
        // formulas instead of trigonometry, each in its well-conditioned half.
        let (w, v, r) = (sxx - syy, 2.0 * sxy, 2.0 * rad);
        let (c, s) = if w >= 0.0 {
            let c = ((r + w) / (2.0 * r)).sqrt();
            (c, v / (2.0 * r * c))
        } else {
            let s = ((r - w) / (2.0 * r)).sqrt().copysign(v);
            (v / (2.0 * r * s), s)
        };
        let mut nrm = [-s, c];
        // Point the normal toward the sensor.
        if nrm[0] * px + nrm[1] * py > 0.0 {
            nrm = [-nrm[0], -nrm[1]];
        }
        // The point on the fitted line nearest the hit (removes the range noise across it).
        let off = -mx * nrm[0] - my * nrm[1];
        out.push(Oriented {
            p: [px - off * nrm[0], py - off * nrm[1]],
            n: nrm,
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ray-casts `segments` from `pose` with the paper's geometry (no noise unless `noise`).
    fn cast(segments: &[[f64; 4]], pose: Pose2, noise: Option<u64>) -> Scan {
        let g = ScanGeometry::paper();
        let walls: Vec<scan_types::testkit::Seg> = segments
            .iter()
            .map(|s| ((s[0], s[1]), (s[2], s[3])))
            .collect();
        let mut rng = scan_types::testkit::Noise::new(noise.unwrap_or(0));
        let ranges: Vec<f64> = (0..g.ray_count)
            .map(|i| {
                let a = pose.theta_rad + g.bearing_rad(i);
                let best = scan_types::testkit::raycast(&walls, pose.x_m, pose.y_m, a)
                    .map_or(g.max_range_m, |t| t.min(g.max_range_m));
                if noise.is_some() && best < g.max_range_m {
                    // Uniform noise of standard deviation 1 cm.
                    best + (rng.uniform() - 0.5) * 0.01 * 12f64.sqrt()
                } else {
                    best
                }
            })
            .collect();
        Scan::from_ranges(&g, &ranges, 0.0)
    }

    /// A 6 m x 4 m room centred on the origin with a 0.6 m box at (1.5, 1.0).
    fn room() -> Vec<[f64; 4]> {
        vec![
            [-3.0, -2.0, 3.0, -2.0],
            [3.0, -2.0, 3.0, 2.0],
            [3.0, 2.0, -3.0, 2.0],
            [-3.0, 2.0, -3.0, -2.0],
            [1.2, 0.7, 1.8, 0.7],
            [1.8, 0.7, 1.8, 1.3],
            [1.8, 1.3, 1.2, 1.3],
            [1.2, 1.3, 1.2, 0.7],
        ]
    }

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
    fn normals_of_straight_walls() {
        // A long wall through (1.5, 0.2) at each direction: every normal is perpendicular to
        // it and points at the sensor, every point lies on it.
        let g = ScanGeometry::paper();
        let p = MatchParams::default();
        for deg in [
            0.0f64, 30.0, 45.0, 60.0, 89.0, 90.0, 91.0, 120.0, 135.0, 179.0,
        ] {
            let (s, c) = deg.to_radians().sin_cos();
            let wall = [[
                1.5 - 20.0 * c,
                0.2 - 20.0 * s,
                1.5 + 20.0 * c,
                0.2 + 20.0 * s,
            ]];
            let scan = cast(&wall, Pose2::default(), None);
            let hits = oriented_hits(&g, &scan, &p, 1);
            assert!(hits.len() > 100, "{deg}: {}", hits.len());
            // The unit normal toward the origin: the origin lies on its side of the wall.
            let mut want = [-s, c];
            if want[0] * 1.5 + want[1] * 0.2 > 0.0 {
                want = [-want[0], -want[1]];
            }
            for h in &hits {
                assert!((h.n[0] - want[0]).abs() < 1e-9, "{deg}: {:?} {want:?}", h.n);
                assert!((h.n[1] - want[1]).abs() < 1e-9, "{deg}: {:?} {want:?}", h.n);
                let off = (h.p[0] - 1.5) * want[0] + (h.p[1] - 0.2) * want[1];
                assert!(off.abs() < 1e-9, "{deg}: {off}");
            }
        }
    }

    #[test]
    fn index_finds_the_brute_force_nearest() {
        // Points on a few hand-placed segments (normals up or right) plus scattered ones.
        let mut t = MatchTarget::new();
        for k in 0..200 {
            let u = k as f64 * 0.01;
            t.points.push(Oriented {
                p: [-1.0 + u, 0.5],
                n: [0.0, 1.0],
            });
            t.points.push(Oriented {
                p: [0.7, -1.0 + 0.013 * k as f64],
                n: [1.0, 0.0],
            });
        }
        let mut noise = scan_types::testkit::Noise::new(12345);
        let mut uniform = || noise.uniform();
        for _ in 0..100 {
            let a = uniform() * std::f64::consts::TAU;
            t.points.push(Oriented {
                p: [uniform() * 3.0 - 1.5, uniform() * 3.0 - 1.5],
                n: [a.cos(), a.sin()],
            });
        }
        t.dirty = true;
        t.index();
        let min_cos = 0.5;
        for _ in 0..2000 {
            let q = [uniform() * 4.0 - 2.0, uniform() * 4.0 - 2.0];
            let a = uniform() * std::f64::consts::TAU;
            let n = [a.cos(), a.sin()];
            for gate in [0.01, 0.05, 0.06, 0.12, 0.3, 1.0] {
                // Brute force: the first point of least squared distance within the gate.
                let mut want: Option<(f64, &Oriented)> = None;
                for o in &t.points {
                    let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
                    if d2 <= gate * gate
                        && o.n[0] * n[0] + o.n[1] * n[1] >= min_cos
                        && want.is_none_or(|(b, _)| d2 < b)
                    {
                        want = Some((d2, o));
                    }
                }
                // Without a hint, with a random one and with the answer as the hint.
                let some = Some((uniform() * t.len() as f64) as usize);
                let right = t.nearest_hinted(q, n, gate, min_cos, None);
                for hint in [None, some, right] {
                    let got = t.nearest_hinted(q, n, gate, min_cos, hint);
                    assert_eq!(got.map(|k| &t.sorted[k]), want.map(|w| w.1), "{q:?} {gate}");
                }
            }
        }
        assert_eq!(
            t.nearest_hinted([f64::NAN, 0.0], [1.0, 0.0], 0.3, 0.5, Some(0)),
            None
        );
    }

    #[test]
    fn floor_matches_std() {
        for x in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.5,
            1.0,
            3.999,
            1e15 + 0.5,
        ] {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
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
