//! Surface fitting: the scan's hits with the normals of the surfaces they lie on.

use scan_types::{RobotPoint, Scan, ScanGeometry};

use super::MatchParams;

/// A hit point with its surface normal (unit, pointing toward the sensor that saw it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Oriented {
    pub(super) p: [f64; 2],
    pub(super) n: [f64; 2],
}

/// The hits of `scan` (robot frame) with a surface normal fitted over their neighbours on the
/// same surface; hits without a clear line through their neighbours are left out.
pub(super) fn oriented_hits(
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
    let spacing = params.surface_spacings * geometry.increment_rad.abs();
    for i in (0..n).step_by(stride.max(1)) {
        let Some(p) = pts[i] else { continue };
        let (px, py) = (p.x_m(), p.y_m());
        // Far hits lie farther apart: the gates grow with the ray spacing at this range.
        let gap = spacing * p.range_m();
        let (surface2, half2) = if gap * gap > surface2 {
            (gap * gap, half2.max(gap * gap))
        } else {
            (surface2, half2)
        };
        let sums = surface_sums(&pts, i, (px, py), k, surface2, half2);
        if sums.0 < 3.0 {
            continue;
        }
        if let Some(o) = fitted_surface(px, py, sums, params.max_line_scatter) {
            out.push(o);
        }
    }
    out
}

/// The surface members around hit `i` at (`px`, `py`) (itself included): walking outwards on each side while
/// the hits stay on the surface, their count and the sums of their coordinates relative to
/// the hit (m, sx, sy, sxx, syy, sxy), in one pass with nothing stored.
fn surface_sums(
    pts: &[Option<RobotPoint>],
    i: usize,
    (px, py): (f64, f64),
    k: usize,
    surface2: f64,
    half2: f64,
) -> (f64, f64, f64, f64, f64, f64) {
    let n = pts.len();
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
    (m, sx, sy, sxx, syy, sxy)
}

/// The hit at (`px`, `py`) moved onto the line fitted to its surface members (from their
/// sums), with the line's normal toward the sensor; `None` when they do not form a line (their
/// variance across it above `max_scatter` times that along it).
fn fitted_surface(
    px: f64,
    py: f64,
    (m, sx, sy, sxx, syy, sxy): (f64, f64, f64, f64, f64, f64),
    max_scatter: f64,
) -> Option<Oriented> {
    // The members' mean relative to the hit, and their scatter about it.
    let (mx, my) = (sx / m, sy / m);
    let sxx = sxx - sx * mx;
    let syy = syy - sy * my;
    let sxy = sxy - sx * my;
    let mean = 0.5 * (sxx + syy);
    let rad = (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt();
    let (lmax, lmin) = (mean + rad, mean - rad);
    // Not a line: scattered points (a corner's tip or noise as large as the spread).
    if lmax <= 0.0 || lmin > max_scatter * lmax {
        return None;
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
    Some(Oriented {
        p: [px - off * nrm[0], py - off * nrm[1]],
        n: nrm,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scanmatch::fixtures::cast;
    use scan_types::Pose2;

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
}
