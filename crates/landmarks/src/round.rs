//! Round objects: the centre of the post or pillar whose edge a landmark is.
//!
//! Where the rays graze a round object, the edge hit slides around it as the robot passes, so
//! a travel measured on that hit comes out short or long by up to the radius. The centre stays
//! put.

use scan_types::{RobotPoint, Scan, ScanGeometry};

use crate::{Landmark, OpenSide};

/// Rules for recognising a round object and fitting its centre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoundParams {
    /// Fewest hits on the object for recognising it as round.
    pub min_points: usize,
    /// Fewest hits for fitting the centre of an object whose radius is known.
    pub min_points_known_radius: usize,
    /// Smallest radius of a round object, metres.
    pub min_radius_m: f64,
    /// Largest radius of a round object, metres.
    pub max_radius_m: f64,
    /// Range noise at short range: sigma is `max(noise_m, noise_share * range)`, metres.
    pub noise_m: f64,
    /// Range noise as a share of the range.
    pub noise_share: f64,
    /// Largest RMS residual of the fitted circle, in range-noise sigmas.
    pub max_rms_sigmas: f64,
    /// The best fit of one or two straight faces must leave at least this many times the
    /// circle's RMS residual (1: no better).
    pub min_line_ratio: f64,
    /// Two neighbouring hits farther apart than this lie on different objects, metres.
    pub max_gap_m: f64,
}

impl Default for RoundParams {
    /// 8 hits (5 with a known radius), radius 0.03-0.5 m, the URG-04LX's noise (10 mm, 1 %
    /// of the range), RMS within 2 sigmas, straight faces fitting no better, 0.3 m gap (grazing
    /// hits lie far apart).
    fn default() -> Self {
        Self {
            min_points: 8,
            min_points_known_radius: 5,
            min_radius_m: 0.03,
            max_radius_m: 0.5,
            noise_m: 0.01,
            noise_share: 0.01,
            max_rms_sigmas: 2.0,
            min_line_ratio: 1.0,
            max_gap_m: 0.3,
        }
    }
}

/// A circle fitted to the hits of one object, in the robot frame of its scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Circle {
    /// Centre.
    pub centre: RobotPoint,
    /// Radius, metres.
    pub radius_m: f64,
    /// RMS distance of the hits from the circle, metres.
    pub rms_m: f64,
    /// Hits fitted.
    pub points: usize,
}

/// The circle of the object whose edge `landmark` is, when that object is round: a circle
/// within the radius bounds fits its hits to the range noise, and one or two straight faces
/// fit them no better. `None` for anything else, or a lone hit.
pub fn round_object(
    geometry: &ScanGeometry,
    scan: &Scan,
    landmark: &Landmark,
    params: &RoundParams,
) -> Option<Circle> {
    let pts = object_hits(geometry, scan, landmark, params)?;
    if pts.len() < params.min_points.max(3) {
        return None;
    }
    let (c, r) = algebraic_circle(&pts)?;
    if r.is_nan() || r > 10.0 * params.max_radius_m {
        return None;
    }
    let (c, r, rms) = refine(&pts, c, r, false)?;
    let fit = accept(&pts, landmark, c, r, rms, params)?;
    (straight_faces_rms(&pts) >= params.min_line_ratio * rms).then_some(fit)
}

/// The centre of the object whose edge `landmark` is, given its radius (from
/// [`round_object`] on another scan): fitted to this scan's hits of it, `None` when they do
/// not fit a circle of that radius.
pub fn round_centre(
    geometry: &ScanGeometry,
    scan: &Scan,
    landmark: &Landmark,
    radius_m: f64,
    params: &RoundParams,
) -> Option<Circle> {
    let pts = object_hits(geometry, scan, landmark, params)?;
    if pts.len() < params.min_points_known_radius.max(2) || radius_m.is_nan() || radius_m <= 0.0 {
        return None;
    }
    // The centroid of a visible arc lies about 0.6 r in front of the centre.
    let n = pts.len() as f64;
    let m = pts
        .iter()
        .fold([0.0; 2], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    let d = m[0].hypot(m[1]);
    if d.is_nan() || d <= 0.0 {
        return None;
    }
    let c0 = [
        m[0] * (1.0 + 0.6 * radius_m / d),
        m[1] * (1.0 + 0.6 * radius_m / d),
    ];
    let (c, r, rms) = refine(&pts, c0, radius_m, true)?;
    accept(&pts, landmark, c, r, rms, params)
}

/// The circle, when its radius, residual and side agree with a round object seen from the
/// robot.
fn accept(
    pts: &[[f64; 2]],
    landmark: &Landmark,
    c: [f64; 2],
    r: f64,
    rms: f64,
    params: &RoundParams,
) -> Option<Circle> {
    let sigma = params.noise_m.max(params.noise_share * landmark.range_m);
    let ok = r >= params.min_radius_m
        && r <= params.max_radius_m
        && rms <= params.max_rms_sigmas * sigma
        // Convex toward the robot: the centre lies beyond the surface.
        && c[0].hypot(c[1]) > landmark.range_m;
    ok.then(|| Circle {
        centre: RobotPoint::new(c[0], c[1]),
        radius_m: r,
        rms_m: rms,
        points: pts.len(),
    })
}

/// The hits of the object at the landmark: from its ray into the object, while each hit lies
/// within `max_gap_m` of the last and the object stays within a largest circle's width.
fn object_hits(
    geometry: &ScanGeometry,
    scan: &Scan,
    landmark: &Landmark,
    params: &RoundParams,
) -> Option<Vec<[f64; 2]>> {
    let step: isize = match landmark.open_side? {
        OpenSide::Lower => 1,
        OpenSide::Higher => -1,
        OpenSide::Both => return None,
    };
    let n = geometry.ray_count.min(scan.len()) as isize;
    let extent = 2.0 * params.max_radius_m + params.max_gap_m;
    let mut out: Vec<[f64; 2]> = Vec::new();
    let mut i = landmark.index as isize;
    while (0..n).contains(&i) {
        let Some(range) = scan.hit_range_m(i as usize).filter(|r| r.is_finite()) else {
            break;
        };
        let p = geometry.robot_point(i as usize, range);
        let p = [p.x_m(), p.y_m()];
        if let Some(last) = out.last()
            && (p[0] - last[0]).hypot(p[1] - last[1]) > params.max_gap_m
        {
            break;
        }
        if let Some(first) = out.first()
            && (p[0] - first[0]).hypot(p[1] - first[1]) > extent
        {
            break;
        }
        out.push(p);
        i += step;
    }
    Some(out)
}

/// The algebraic (Kasa) circle through `pts`: centre and radius.
fn algebraic_circle(pts: &[[f64; 2]]) -> Option<([f64; 2], f64)> {
    let n = pts.len() as f64;
    let m = pts
        .iter()
        .fold([0.0; 2], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    // About the centroid: x^2 + y^2 + D x + E y + F = 0 with sums of x and y zero.
    let (mut sxx, mut sxy, mut syy, mut sxz, mut syz, mut sz) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for p in pts {
        let (x, y) = (p[0] - m[0], p[1] - m[1]);
        let z = x * x + y * y;
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
        sxz += x * z;
        syz += y * z;
        sz += z;
    }
    let det = sxx * syy - sxy * sxy;
    if det.is_nan() || det.abs() <= 1e-18 {
        return None;
    }
    let d = -(sxz * syy - syz * sxy) / det;
    let e = -(sxx * syz - sxy * sxz) / det;
    let f = -sz / n;
    let r2 = 0.25 * (d * d + e * e) - f;
    (r2 > 0.0).then(|| ([m[0] - 0.5 * d, m[1] - 0.5 * e], r2.sqrt()))
}

/// Gauss-Newton on the geometric distances `|p - c| - r` (the radius held when `fixed`):
/// centre, radius and RMS residual.
fn refine(
    pts: &[[f64; 2]],
    mut c: [f64; 2],
    mut r: f64,
    fixed: bool,
) -> Option<([f64; 2], f64, f64)> {
    for _ in 0..20 {
        // Normal equations of the residuals' Jacobian [-ux, -uy, -1].
        let mut a = [[0.0; 3]; 3];
        let mut b = [0.0; 3];
        for p in pts {
            let (dx, dy) = (p[0] - c[0], p[1] - c[1]);
            let d = dx.hypot(dy);
            if d.is_nan() || d <= 1e-12 {
                return None;
            }
            let j = [-dx / d, -dy / d, -1.0];
            let f = d - r;
            for (k, row) in a.iter_mut().enumerate() {
                for (l, v) in row.iter_mut().enumerate() {
                    *v += j[k] * j[l];
                }
                b[k] -= j[k] * f;
            }
        }
        let step = if fixed {
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            if det.is_nan() || det.abs() <= 1e-18 {
                return None;
            }
            [
                (b[0] * a[1][1] - a[0][1] * b[1]) / det,
                (a[0][0] * b[1] - b[0] * a[1][0]) / det,
                0.0,
            ]
        } else {
            solve3(a, b)?
        };
        c = [c[0] + step[0], c[1] + step[1]];
        r += step[2];
        if !(c[0].is_finite() && c[1].is_finite() && r.is_finite()) {
            return None;
        }
        if step.iter().map(|s| s.abs()).fold(0.0, f64::max) < 1e-9 {
            break;
        }
    }
    let ss: f64 = pts
        .iter()
        .map(|p| ((p[0] - c[0]).hypot(p[1] - c[1]) - r).powi(2))
        .sum();
    Some((c, r, (ss / pts.len() as f64).sqrt()))
}

/// `a x = b` by Cramer's rule.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let det = det3(a);
    if det.is_nan() || det.abs() <= 1e-18 {
        return None;
    }
    let mut x = [0.0; 3];
    for (k, v) in x.iter_mut().enumerate() {
        let mut m = a;
        for (row, bv) in m.iter_mut().zip(b) {
            row[k] = bv;
        }
        *v = det3(m) / det;
    }
    Some(x)
}

/// RMS distance of `pts` from their best fit by one straight line or by two (split where
/// fits best, at least three points on each).
fn straight_faces_rms(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len();
    let mut best = line_ss(pts);
    for k in 3..n.saturating_sub(2) {
        best = best.min(line_ss(&pts[..k]) + line_ss(&pts[k..]));
    }
    (best / n as f64).sqrt()
}

/// Sum of squared distances of `pts` from their total-least-squares line.
fn line_ss(pts: &[[f64; 2]]) -> f64 {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return 0.0;
    }
    let m = pts
        .iter()
        .fold([0.0; 2], |a, p| [a[0] + p[0] / n, a[1] + p[1] / n]);
    let (mut sxx, mut sxy, mut syy) = (0.0, 0.0, 0.0);
    for p in pts {
        let (x, y) = (p[0] - m[0], p[1] - m[1]);
        sxx += x * x;
        sxy += x * y;
        syy += y * y;
    }
    // The smaller eigenvalue of the scatter matrix.
    (0.5 * (sxx + syy) - (0.25 * (sxx - syy).powi(2) + sxy * sxy).sqrt()).max(0.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{DetectParams, detect};
    use scan_types::testkit::{Seg, boxed, noisy, scan_at};

    /// A disc as a 720-sided polygon (its sides lie within 2 micrometres of the circle).
    fn disc(cx: f64, cy: f64, r: f64) -> Vec<Seg> {
        let at = |k: usize| {
            let a = k as f64 * std::f64::consts::TAU / 720.0;
            (cx + r * a.cos(), cy + r * a.sin())
        };
        (0..720).map(|k| (at(k), at(k + 1))).collect()
    }

    /// The edge landmarks of `scan` within `within` of the robot-frame point `p`.
    fn edges_near(g: &ScanGeometry, scan: &Scan, p: [f64; 2], within: f64) -> Vec<Landmark> {
        detect(g, scan, &DetectParams::default())
            .into_iter()
            .filter(|l| {
                l.open_side.is_some() && {
                    let q = l.robot_point();
                    (q.x_m() - p[0]).hypot(q.y_m() - p[1]) < within
                }
            })
            .collect()
    }

    #[test]
    fn a_post_is_round_and_its_centre_stays_put_while_its_edge_slides() {
        let g = ScanGeometry::paper();
        let post = disc(3.0, 1.0, 0.15);
        let p = RoundParams::default();
        // Both edges' along-track distances (right-hand first), from x = 0 and from x = 2.
        let mut edge_x = Vec::new();
        for x in [0.0, 2.0] {
            let scan = scan_at(&g, &post, x, 0.0, 0.0);
            let found = edges_near(&g, &scan, [3.0 - x, 1.0], 0.3);
            assert_eq!(
                found.len(),
                2,
                "both sides of the post from x = {x}: {found:#?}"
            );
            for l in &found {
                let c = round_object(&g, &scan, l, &p).expect("round");
                assert!((c.centre.x_m() - (3.0 - x)).abs() < 1e-3, "{c:?}");
                assert!((c.centre.y_m() - 1.0).abs() < 1e-3, "{c:?}");
                assert!((c.radius_m - 0.15).abs() < 1e-3, "{c:?}");
                let k = round_centre(&g, &scan, l, 0.15, &p).expect("centre");
                assert!((k.centre.x_m() - (3.0 - x)).abs() < 1e-3, "{k:?}");
            }
            let mut xs: Vec<(f64, f64)> = found
                .iter()
                .map(|l| (l.bearing_rad, l.robot_point().x_m()))
                .collect();
            xs.sort_by(|a, b| a.0.total_cmp(&b.0));
            edge_x.push([xs[0].1, xs[1].1]);
        }
        // Tangent points at x = sqrt(d^2 - r^2) cos(atan2(cy, cx) -+ asin(r / d)): from the
        // origin 3.041 and 2.946, from x = 2 1.094 and 0.883. For 2 m driven the right-hand
        // edge measures 1.946 m, the left-hand 2.063 m.
        let short = 2.0 - (edge_x[0][0] - edge_x[1][0]);
        assert!(short > 0.03, "right-hand edge's travel short by {short}");
        let long = (edge_x[0][1] - edge_x[1][1]) - 2.0;
        assert!(long > 0.03, "left-hand edge's travel long by {long}");
    }

    #[test]
    fn flat_faces_and_corners_are_not_round() {
        let g = ScanGeometry::paper();
        let p = RoundParams::default();
        // A 0.4 m box showing two faces, and a 2 m wall seen at an angle.
        let mut world = boxed(2.5, 0.6, 2.9, 1.0);
        world.push(((1.0, -2.0), (2.5, -1.2)));
        for seed in 0..20 {
            let clean = scan_at(&g, &world, 0.0, 0.0, 0.0);
            let scan = if seed == 0 {
                clean
            } else {
                noisy(&g, &clean, 0.02, seed)
            };
            let found = detect(&g, &scan, &DetectParams::default());
            assert!(found.len() >= 3, "seed {seed}: {found:?}");
            for l in &found {
                assert_eq!(round_object(&g, &scan, l, &p), None, "seed {seed}: {l:?}");
            }
        }
    }

    #[test]
    fn a_noisy_post_keeps_its_centre() {
        let g = ScanGeometry::paper();
        let p = RoundParams::default();
        let post = disc(2.0, 0.6, 0.15);
        let clean = scan_at(&g, &post, 0.0, 0.0, 0.0);
        for seed in 1..=20 {
            // 2 cm: the URG-04LX's 1 % of the post's 2.1 m range.
            let scan = noisy(&g, &clean, 0.021, seed);
            let found = edges_near(&g, &scan, [2.0, 0.6], 0.3);
            assert_eq!(found.len(), 2, "seed {seed}: {found:#?}");
            for l in found {
                let c = round_centre(&g, &scan, &l, 0.15, &p).unwrap_or_else(|| {
                    panic!("seed {seed}: {l:?} {:?}", object_hits(&g, &scan, &l, &p))
                });
                // The post spans 2 asin(0.15 / 2.09) = 8.2 deg, about 23 rays at 0.35 deg.
                assert!((20..=25).contains(&c.points), "seed {seed}: {c:?}");
                // n hits of 2.1 cm noise: within 2.1 / sqrt(n) cm per axis, 3 sigma.
                let off = (c.centre.x_m() - 2.0).hypot(c.centre.y_m() - 0.6);
                let n = c.points as f64;
                assert!(off < 3.0 * 0.021 * (2.0 / n).sqrt(), "seed {seed}: {off}");
            }
        }
        // Near, where the arc bends well clear of the 1 cm noise, it is recognised every time.
        let near = disc(1.0, 0.5, 0.15);
        let clean = scan_at(&g, &near, 0.0, 0.0, 0.0);
        for seed in 1..=20 {
            let scan = noisy(&g, &clean, 0.01, seed);
            let found = edges_near(&g, &scan, [1.0, 0.5], 0.3);
            assert_eq!(found.len(), 2, "seed {seed}");
            for l in found {
                let c = round_object(&g, &scan, &l, &p).expect("round");
                assert!((c.radius_m - 0.15).abs() < 0.01, "seed {seed}: {c:?}");
            }
        }
    }
}
