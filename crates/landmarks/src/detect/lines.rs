//! Line fits along the arms of a landmark: arm walks, running moments and line geometry.

use scan_types::RobotPoint;

use super::{DetectParams, Ray, exceeds};

/// Appends to `out` the hits continuing the surface from `pos` in direction `dir` (excluding
/// `pos`), within `arm_m` of the hit at `pos` and without range jumps; returns how many.
pub(super) fn arm_into(
    seg: &[Ray],
    pos: usize,
    dir: isize,
    params: &DetectParams,
    out: &mut Vec<RobotPoint>,
) -> usize {
    let n = arm_len(seg, pos, dir, params);
    out.extend((1..=n as isize).map(|j| seg[(pos as isize + dir * j) as usize].pt));
    n
}

/// How many hits [`arm_into`] would append from `pos` in direction `dir`.
pub(super) fn arm_len(seg: &[Ray], pos: usize, dir: isize, params: &DetectParams) -> usize {
    let Some(r0) = seg[pos].hit else {
        return 0;
    };
    let origin = seg[pos].pt;
    let mut prev = r0;
    let mut count = 0;
    let mut k = pos as isize + dir;
    while k >= 0 && (k as usize) < seg.len() {
        let ray = &seg[k as usize];
        let Some(r) = ray.hit else { break };
        if (r - prev).abs() > params.occlusion_jump_m {
            break;
        }
        let (dx, dy) = (ray.pt.x_m() - origin.x_m(), ray.pt.y_m() - origin.y_m());
        if exceeds(dx * dx + dy * dy, params.arm_m) {
            break;
        }
        count += 1;
        prev = r;
        k += dir;
    }
    count
}

/// Running sums of a segment's hit points: entry `k` holds the [`Moments`] of positions
/// `0..k` (misses add nothing), so any run's moments cost one subtraction.
pub(super) fn prefix_moments(seg: &[Ray]) -> Vec<Moments> {
    let mut out = Vec::with_capacity(seg.len() + 1);
    let mut m = Moments::default();
    out.push(m);
    for ray in seg {
        if ray.hit.is_some() {
            m.add(ray.pt.x_m(), ray.pt.y_m());
        }
        out.push(m);
    }
    out
}

/// Least-squares line through points: (centroid, unit direction, RMS residual).
pub(super) fn fit_line(points: &[RobotPoint]) -> Option<([f64; 2], [f64; 2], f64)> {
    if points.len() < 2 {
        return None;
    }
    let n = points.len() as f64;
    let cx = points.iter().map(|p| p.x_m()).sum::<f64>() / n;
    let cy = points.iter().map(|p| p.y_m()).sum::<f64>() / n;
    let (mut sxx, mut syy, mut sxy) = (0.0, 0.0, 0.0);
    for p in points {
        let (dx, dy) = (p.x_m() - cx, p.y_m() - cy);
        sxx += dx * dx;
        syy += dy * dy;
        sxy += dx * dy;
    }
    let angle = 0.5 * (2.0 * sxy).atan2(sxx - syy);
    let d = [angle.cos(), angle.sin()];
    let ss: f64 = points
        .iter()
        .map(|p| {
            let (dx, dy) = (p.x_m() - cx, p.y_m() - cy);
            let off = dx * d[1] - dy * d[0];
            off * off
        })
        .sum();
    Some(([cx, cy], d, (ss / n).sqrt()))
}

/// Sums over a point set of the coordinates relative to one point of it (a few decimetres
/// away at most), for its principal axis without storing the points.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Moments {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
}

impl Moments {
    /// Adds the point at `(dx, dy)` from the reference point.
    pub(super) fn add(&mut self, dx: f64, dy: f64) {
        self.n += 1.0;
        self.sx += dx;
        self.sy += dy;
        self.sxx += dx * dx;
        self.syy += dy * dy;
        self.sxy += dx * dy;
    }

    /// The moments of the run `lo..=hi` from the running sums of [`prefix_moments`].
    pub(super) fn window(prefix: &[Moments], lo: usize, hi: usize) -> Self {
        let (a, b) = (&prefix[lo], &prefix[hi + 1]);
        Self {
            n: b.n - a.n,
            sx: b.sx - a.sx,
            sy: b.sy - a.sy,
            sxx: b.sxx - a.sxx,
            syy: b.syy - a.syy,
            sxy: b.sxy - a.sxy,
        }
    }

    /// The moments of `points` relative to the first.
    #[cfg(test)]
    pub(super) fn of(points: &[RobotPoint]) -> Self {
        let mut m = Self::default();
        if let Some(o) = points.first() {
            for p in points {
                m.add(p.x_m() - o.x_m(), p.y_m() - o.y_m());
            }
        }
        m
    }

    /// `(sxx - syy, 2 sxy)` of the centred scatter matrix: the principal axis lies at half
    /// its angle. `None` when the axis is poorly defined (a round blob of points): rounding
    /// leaves it within about 1e-9 of the scatter's trace (running sums over a scan).
    pub(super) fn doubled_axis(&self) -> Option<[f64; 2]> {
        let n = self.n;
        let cxx = self.sxx - self.sx * self.sx / n;
        let cyy = self.syy - self.sy * self.sy / n;
        let cxy = self.sxy - self.sx * self.sy / n;
        let u = [cxx - cyy, 2.0 * cxy];
        let tolerance = 1e-6 * (cxx + cyy);
        (u[0] * u[0] + u[1] * u[1] > tolerance * tolerance).then_some(u)
    }
}

/// The squared cosine of the angle between the principal axes of two point sets (as
/// [`fit_line`] fits them), from their moments without trigonometry: `cos^2 t = (1 + cos
/// 2t) / 2`. Accurate to about 1e-8; `None` when an axis is poorly defined.
pub(super) fn cos2_between_axes(a: &Moments, b: &Moments) -> Option<f64> {
    let (u, v) = (a.doubled_axis()?, b.doubled_axis()?);
    let norms2 = (u[0] * u[0] + u[1] * u[1]) * (v[0] * v[0] + v[1] * v[1]);
    let cos_2t = (u[0] * v[0] + u[1] * v[1]) / norms2.sqrt();
    cos_2t.is_finite().then_some(0.5 * (1.0 + cos_2t))
}

/// Range at which the ray at `bearing` meets the line (centroid c, direction d), if ahead.
pub(super) fn line_range_on_ray(c: [f64; 2], d: [f64; 2], bearing: f64) -> Option<f64> {
    let u = [bearing.cos(), bearing.sin()];
    let den = d[0] * u[1] - d[1] * u[0];
    if den.abs() < 1e-12 {
        return None;
    }
    let t = (d[0] * c[1] - d[1] * c[0]) / den;
    (t > 0.0).then_some(t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::segments;
    use scan_types::{RayStatus, Scan, ScanGeometry};

    /// `k` points from `from` along `angle_deg`, 1 cm apart.
    fn arm_at(from: [f64; 2], angle_deg: f64, k: usize) -> Vec<RobotPoint> {
        let (s, c) = angle_deg.to_radians().sin_cos();
        (0..k)
            .map(|i| RobotPoint::new(from[0] + 0.01 * i as f64 * c, from[1] + 0.01 * i as f64 * s))
            .collect()
    }

    #[test]
    fn arm_len_and_running_moments_match_the_arm() {
        // A box corner, a wall, a jump and a max-range run, with error rays.
        let g = ScanGeometry::paper();
        let ranges: Vec<f64> = (0..g.ray_count)
            .map(|i| match i {
                0..=199 => 1.0 / g.bearing_rad(i).cos().abs().max(0.3),
                200..=299 => 0.8 + 0.002 * (i - 200) as f64,
                300..=359 => g.max_range_m,
                _ => 1.5 + 0.001 * ((i * 7) % 13) as f64,
            })
            .collect();
        let mut scan = Scan::from_ranges(&g, &ranges, 0.0);
        for k in [50, 51, 420] {
            scan.status[k] = RayStatus::Error(1);
            scan.ranges_m[k] = f64::NAN;
        }
        let params = DetectParams::default();
        for seg in segments(&g, &scan, params.max_skipped_errors) {
            let prefix = prefix_moments(&seg);
            for pos in 0..seg.len() {
                for dir in [-1, 1] {
                    let mut pts = Vec::new();
                    let n = arm_into(&seg, pos, dir, &params, &mut pts);
                    assert_eq!(arm_len(&seg, pos, dir, &params), n, "{pos} {dir}");
                    for (t, q) in pts.iter().enumerate() {
                        let at = (pos as isize + dir * (t as isize + 1)) as usize;
                        assert_eq!(*q, seg[at].pt);
                    }
                    // The running sums give the arm's scatter (with its hit) as the points do
                    // (for arms of three points or more, as corners use them).
                    if seg[pos].hit.is_none() || n < 2 {
                        continue;
                    }
                    let (lo, hi) = if dir < 0 {
                        (pos - n, pos)
                    } else {
                        (pos, pos + n)
                    };
                    let m = Moments::window(&prefix, lo, hi);
                    assert_eq!(m.n, n as f64 + 1.0);
                    pts.insert(0, seg[pos].pt);
                    let want = Moments::of(&pts);
                    match (m.doubled_axis(), want.doubled_axis()) {
                        (Some(a), Some(b)) => {
                            // Within 1e-11 m^2: a corner's arms (0.1 m or longer) scatter
                            // by 5e-3 m^2 or more, so their axes' cosine moves by < 1e-8.
                            for t in 0..2 {
                                assert!((a[t] - b[t]).abs() <= 1e-11, "{pos} {dir} {a:?} {b:?}");
                            }
                        }
                        (a, b) => assert_eq!(a.is_some(), b.is_some(), "{pos} {dir}"),
                    }
                }
            }
        }
    }

    #[test]
    fn axes_cosine_without_trigonometry() {
        // Two arms from one point at known angles: cos^2 of the angle between them.
        for (deg, want) in [
            (0.0, 1.0),
            (30.0, 0.75),
            (45.0, 0.5),
            (90.0, 0.0),
            (150.0, 0.75),
        ] {
            let a = arm_at([1.0, 0.5], 10.0, 12);
            let b = arm_at([1.0, 0.5], 10.0 + deg, 9);
            let got = cos2_between_axes(&Moments::of(&a), &Moments::of(&b)).unwrap();
            assert!((got - want).abs() < 1e-12, "{deg}: {got}");
            // The same as the fitted lines' directions give.
            let (_, d1, _) = fit_line(&a).unwrap();
            let (_, d2, _) = fit_line(&b).unwrap();
            let dot = d1[0] * d2[0] + d1[1] * d2[1];
            assert!((got - dot * dot).abs() < 1e-12, "{deg}");
        }
        // A single repeated point, or a round blob, has no axis.
        let p = vec![RobotPoint::new(1.0, 1.0); 4];
        let line = Moments::of(&arm_at([0.0, 0.0], 0.0, 5));
        assert_eq!(cos2_between_axes(&Moments::of(&p), &line), None);
        let square =
            [(0.0, 0.0), (0.1, 0.0), (0.1, 0.1), (0.0, 0.1)].map(|(x, y)| RobotPoint::new(x, y));
        assert_eq!(cos2_between_axes(&Moments::of(&square), &line), None);
    }
}
