//! The direction of a scan's straight walls modulo 90 deg. In a rectilinear building (most
//! offices, labs and hospitals) every long wall runs along one of two perpendicular axes, so
//! the walls in view measure the robot's heading against the building's axes, whichever wall
//! it is.

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

use scan_types::{Scan, ScanGeometry};
use serde::{Deserialize, Serialize};

/// How [`wall_axes`] finds the walls of a scan.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct AxesParams {
    /// A hit's neighbours along the scan within this of it lie on its surface, metres.
    pub surface_m: f64,
    /// A hit's surface must span at least this to count as a wall, metres.
    pub min_span_m: f64,
    /// The surface is straight when its variance across is at most this share of its
    /// variance along.
    pub line_scatter: f64,
    /// Wall fits within this of the scan's axes (modulo 90 deg) agree with them, degrees.
    pub inlier_deg: f64,
    /// Fewest agreeing wall fits for an answer (one per second hit) ...
    pub min_points: usize,
    /// ... and their least share of all the wall fits (0..1).
    pub min_share: f64,
}

impl Default for AxesParams {
    fn default() -> Self {
        Self {
            surface_m: 0.3,
            min_span_m: 0.4,
            line_scatter: 0.01,
            inlier_deg: 3.0,
            min_points: 15,
            min_share: 0.7,
        }
    }
}

/// What a scan's straight walls say of the axes they run along.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WallAxes {
    /// The axes' direction in the robot frame, modulo 90 deg: in (-45, 45] deg, radians.
    pub angle_rad: f64,
    /// Wall fits (one per second hit) that agree with it.
    pub points: usize,
    /// Their share of all the wall fits (1: every wall of the scan runs along the axes).
    pub share: f64,
}

/// `angle` wrapped into (-45, 45] deg: the difference between two directions modulo 90 deg.
pub fn wrap_quarter_rad(angle_rad: f64) -> f64 {
    let w = angle_rad - FRAC_PI_2 * (angle_rad / FRAC_PI_2).round();
    if w <= -FRAC_PI_4 { w + FRAC_PI_2 } else { w }
}

/// The direction, modulo 90 deg, of the straight walls of `scan` in the robot frame; `None`
/// when too few wall fits agree on one.
pub fn wall_axes(geometry: &ScanGeometry, scan: &Scan, params: &AxesParams) -> Option<WallAxes> {
    let hits: Vec<[f64; 2]> = scan
        .robot_hits(geometry)
        .map(|(_, p)| [p.x_m(), p.y_m()])
        .collect();
    let reach2 = params.surface_m * params.surface_m;
    let near = |a: [f64; 2], b: [f64; 2]| (a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) <= reach2;
    // Running sums of x, y, x^2, y^2 and xy: any run of hits' moments in constant time.
    let mut sums = Vec::with_capacity(hits.len() + 1);
    sums.push([0.0; 5]);
    for p in &hits {
        let s: [f64; 5] = *sums.last().expect("one entry at least");
        sums.push([
            s[0] + p[0],
            s[1] + p[1],
            s[2] + p[0] * p[0],
            s[3] + p[1] * p[1],
            s[4] + p[0] * p[1],
        ]);
    }
    let mut dirs = Vec::with_capacity(hits.len() / STRIDE + 1);
    for i in (0..hits.len()).step_by(STRIDE) {
        let p = hits[i];
        // The hit's surface: its neighbours in scan order, each within reach of the hit.
        let mut lo = i;
        while lo > 0 && near(hits[lo - 1], p) {
            lo -= 1;
        }
        let mut hi = i;
        while hi + 1 < hits.len() && near(hits[hi + 1], p) {
            hi += 1;
        }
        if hi - lo + 1 < 5 || !span_at_least(hits[lo], hits[hi], params.min_span_m) {
            continue;
        }
        let (a, b) = (sums[lo], sums[hi + 1]);
        let m: [f64; 5] = std::array::from_fn(|k| b[k] - a[k]);
        if let Some(d) = line_direction(&m, (hi - lo + 1) as f64, params.line_scatter) {
            dirs.push(d);
        }
    }
    if dirs.is_empty() || dirs.len() < params.min_points {
        return None;
    }
    // The densest window of directions modulo 90 deg, 2 x `inlier_deg` wide; the answer is
    // the mean of the directions within `inlier_deg` of its middle.
    let inlier = params.inlier_deg.to_radians();
    let mut folded: Vec<f64> = dirs.iter().map(|&d| wrap_quarter_rad(d)).collect();
    folded.sort_by(f64::total_cmp);
    let n = folded.len();
    let at = |k: usize| folded[k % n] + if k >= n { FRAC_PI_2 } else { 0.0 };
    let (mut best, mut best_start, mut end) = (0, 0, 0);
    for start in 0..n {
        end = end.max(start);
        while end + 1 < start + n && at(end + 1) - at(start) <= 2.0 * inlier {
            end += 1;
        }
        if end + 1 - start > best {
            (best, best_start) = (end + 1 - start, start);
        }
    }
    let middle = 0.5 * (at(best_start) + at(best_start + best - 1));
    let offsets: Vec<f64> = dirs
        .iter()
        .map(|d| wrap_quarter_rad(d - middle))
        .filter(|o| o.abs() <= inlier)
        .collect();
    let share = offsets.len() as f64 / n as f64;
    if offsets.len() < params.min_points || share < params.min_share {
        return None;
    }
    let mean = offsets.iter().sum::<f64>() / offsets.len() as f64;
    Some(WallAxes {
        angle_rad: wrap_quarter_rad(middle + mean),
        points: offsets.len(),
        share,
    })
}

/// Every this-many-th hit's surface is fitted (its neighbours' overlap makes the others
/// nearly the same fit).
const STRIDE: usize = 2;

fn span_at_least(a: [f64; 2], b: [f64; 2], span_m: f64) -> bool {
    (a[0] - b[0]).hypot(a[1] - b[1]) >= span_m
}

/// The direction of the line through `n` points of moments `m` (sums of x, y, x^2, y^2, xy;
/// radians), when their variance across it is at most `scatter` of their variance along it.
fn line_direction(m: &[f64; 5], n: f64, scatter: f64) -> Option<f64> {
    let (mx, my) = (m[0] / n, m[1] / n);
    let sxx = m[2] / n - mx * mx;
    let syy = m[3] / n - my * my;
    let sxy = m[4] / n - mx * my;
    let half_diff = 0.5 * (sxx - syy);
    let root = half_diff.hypot(sxy);
    let mid = 0.5 * (sxx + syy);
    let (along, across) = (mid + root, mid - root);
    (along > 0.0 && across <= scatter * along).then(|| 0.5 * (2.0 * sxy).atan2(sxx - syy))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quarter_wrap_folds_every_direction_into_45_deg() {
        for (a, w) in [
            (0.0, 0.0),
            (50.0, -40.0),
            (-50.0, 40.0),
            (91.0, 1.0),
            (45.0, 45.0),
        ] {
            let got = wrap_quarter_rad(f64::to_radians(a)).to_degrees();
            assert!((got - w).abs() < 1e-9, "{a} -> {got}, not {w}");
        }
    }

    fn moments(s: &[[f64; 2]]) -> [f64; 5] {
        s.iter().fold([0.0; 5], |m, p| {
            [
                m[0] + p[0],
                m[1] + p[1],
                m[2] + p[0] * p[0],
                m[3] + p[1] * p[1],
                m[4] + p[0] * p[1],
            ]
        })
    }

    #[test]
    fn a_lines_direction_is_that_of_its_points() {
        let s: Vec<[f64; 2]> = (0..10)
            .map(|i| {
                let t = f64::from(i) * 0.05;
                [1.0 + t * 0.5f64.cos(), 2.0 + t * 0.5f64.sin()]
            })
            .collect();
        let d = line_direction(&moments(&s), 10.0, 0.01).expect("straight");
        assert!((d - 0.5).abs() < 1e-9, "{d}");
        // Bent by a right angle halfway: no line.
        let bent: Vec<[f64; 2]> = (0..10)
            .map(|i| {
                let t = f64::from(i) * 0.05;
                if i < 5 { [t, 0.0] } else { [0.2, t - 0.2] }
            })
            .collect();
        assert!(line_direction(&moments(&bent), 10.0, 0.01).is_none());
    }
}
