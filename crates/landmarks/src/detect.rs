//! Landmark detection: max-range jumps (the paper), occlusion edges and corners, with
//! stability flags.

use scan_types::{RayStatus, RobotPoint, Scan, ScanGeometry};

use crate::LandmarksError;

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
    /// A hit this close to the maximum range is flagged `near_range_limit`, metres.
    pub range_limit_margin_m: f64,
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
        let a = self.corner_min_angle_rad;
        if !(a.is_finite() && a > 0.0 && a < std::f64::consts::PI) {
            return bad("corner_min_angle_rad", a, "must lie in (0, pi)");
        }
        Ok(())
    }
}

/// One usable ray: its index and, for a hit, its range and point (origin for a miss).
#[derive(Debug, Clone, Copy)]
struct Ray {
    index: usize,
    hit: Option<f64>,
    pt: RobotPoint,
}

/// `dist(a, b) > limit`, with the square root only when the squares are too close to tell.
fn beyond(a: &RobotPoint, b: &RobotPoint, limit: f64) -> bool {
    let (dx, dy) = (b.x_m() - a.x_m(), b.y_m() - a.y_m());
    exceeds(dx * dx + dy * dy, limit)
}

/// `d2.sqrt() > limit`, with the square root only when the squares are too close to tell.
fn exceeds(d2: f64, limit: f64) -> bool {
    let l2 = limit * limit;
    if limit.is_nan() || limit < 0.0 {
        d2.sqrt() > limit
    } else if d2 > l2 * (1.0 + 1e-9) {
        true
    } else if d2 < l2 * (1.0 - 1e-9) {
        false
    } else {
        d2.sqrt() > limit
    }
}

/// Distance between two points (as `RobotPoint::distance_m`, inlined).
fn dist(a: &RobotPoint, b: &RobotPoint) -> f64 {
    let (dx, dy) = (b.x_m() - a.x_m(), b.y_m() - a.y_m());
    (dx * dx + dy * dy).sqrt()
}

/// Finds the landmarks of `scan`, sorted by ray index.
///
/// Error rays are never in A and never hits: they are skipped (up to `max_skipped_errors` in
/// a row; a longer gap splits the scan). A scan whose length differs from the geometry's is
/// read up to the shorter of the two.
pub fn detect(geometry: &ScanGeometry, scan: &Scan, params: &DetectParams) -> Vec<Landmark> {
    detect_in(geometry, scan, params, None)
}

/// The landmarks of [`detect`] whose point lies within `radius_m` of `centre` (the same
/// values, in the same order), with corners sought only near `centre`.
pub fn detect_near(
    geometry: &ScanGeometry,
    scan: &Scan,
    params: &DetectParams,
    centre: RobotPoint,
    radius_m: f64,
) -> Vec<Landmark> {
    let reach = radius_m + corner_shift_bound(params);
    let mut out = detect_in(geometry, scan, params, Some((centre, reach)));
    out.retain(|l| l.robot_point().distance_m(&centre) <= radius_m);
    out
}

/// How far a corner's refined point can lie from its ray's hit, metres: each arm's line
/// passes through its centroid, within `arm_m` of the hit, and two lines turning by `t`
/// that pass within `a` and `b` of a point meet within `(a + b) / sin t` of it (1 % margin
/// for rounding; infinite when corners may turn by almost nothing).
fn corner_shift_bound(params: &DetectParams) -> f64 {
    if !params.corner_refine {
        return 0.0;
    }
    let t = params.corner_min_angle_rad.min(std::f64::consts::FRAC_PI_2);
    let s = t.sin();
    if s.is_finite() && s > 1e-3 && params.arm_m.is_finite() {
        2.02 * params.arm_m / s + 1e-6
    } else {
        f64::INFINITY
    }
}

/// [`detect`], with corners only where a hit lies within `reach` of a point (when given):
/// every corner whose refined point can lie within `reach - corner_shift_bound` of it.
fn detect_in(
    geometry: &ScanGeometry,
    scan: &Scan,
    params: &DetectParams,
    near: Option<(RobotPoint, f64)>,
) -> Vec<Landmark> {
    let mut out = Vec::new();
    for segment in segments(geometry, scan, params.max_skipped_errors) {
        let mut found = Vec::new();
        if params.max_range_jumps {
            jumps(geometry, &segment, params, &mut found);
        }
        if params.occlusion_edges {
            occlusions(geometry, &segment, params, &mut found);
        }
        if params.corners {
            corners(geometry, &segment, params, near, &mut found);
        }
        out.extend(found);
    }
    out.retain(|l| {
        !(params.reject_near_range_limit && l.near_range_limit
            || params.reject_surface_continues && l.surface_continues
            || params.reject_hidden_at_side && l.hidden_at_side
            || l.support_rays < params.min_support_rays)
    });
    out.sort_by_key(|l| l.index);
    out.dedup_by_key(|l| l.index);
    out
}

/// Runs of usable rays, split where more than `max_gap` error rays follow each other.
fn segments(geometry: &ScanGeometry, scan: &Scan, max_gap: usize) -> Vec<Vec<Ray>> {
    let n = geometry
        .ray_count
        .min(scan.ranges_m.len())
        .min(scan.status.len());
    let mut out = Vec::new();
    let mut current: Vec<Ray> = Vec::new();
    let dirs = geometry.directions();
    let mut gap = 0usize;
    for i in 0..n {
        let r = scan.ranges_m[i];
        let ray = match scan.status[i] {
            RayStatus::Hit if r.is_finite() && r > 0.0 => Ray {
                index: i,
                hit: Some(r),
                pt: RobotPoint::new(r * dirs[i][0], r * dirs[i][1]),
            },
            RayStatus::MaxRange => Ray {
                index: i,
                hit: None,
                pt: RobotPoint::new(0.0, 0.0),
            },
            _ => {
                gap += 1;
                if gap > max_gap && !current.is_empty() {
                    out.push(std::mem::take(&mut current));
                }
                continue;
            }
        };
        gap = 0;
        current.push(ray);
    }
    if !current.is_empty() {
        out.push(current);
    }
    out
}

/// The paper's rule on one segment.
fn jumps(geometry: &ScanGeometry, seg: &[Ray], params: &DetectParams, out: &mut Vec<Landmark>) {
    let n = params.neighbour_n as isize;
    let len = seg.len() as isize;
    // Edge position in the segment -> open sides seen.
    let mut edges: Vec<(usize, bool, bool)> = Vec::new(); // (pos, open below, open above)
    for p in 0..len {
        if seg[p as usize].hit.is_some() {
            continue;
        }
        for dir in [-1isize, 1] {
            let q = p + dir * n;
            if q < 0 || q >= len || seg[q as usize].hit.is_none() {
                continue;
            }
            let mut j = p + dir;
            while seg[j as usize].hit.is_none() {
                j += dir;
            }
            // The open run next to the edge must be long enough.
            let mut open = 0usize;
            let mut k = j - dir;
            while k >= 0 && k < len && seg[k as usize].hit.is_none() {
                open += 1;
                k -= dir;
            }
            if open < params.min_open_rays {
                continue;
            }
            // The hit bounding the open run on its far side, if any.
            if params.min_gap_width_m > 0.0
                && k >= 0
                && k < len
                && seg[j as usize].hit.is_some()
                && seg[k as usize].hit.is_some()
            {
                let (a, b) = (seg[j as usize].pt, seg[k as usize].pt);
                if dist(&a, &b) < params.min_gap_width_m {
                    continue;
                }
            }
            if params.reject_bridged_dropouts
                && k >= 0
                && k < len
                && seg[j as usize].hit.is_some()
                && let Some(r1) = seg[k as usize].hit
            {
                let (a, b) = (seg[j as usize].pt, seg[k as usize].pt);
                let mut pts = vec![a];
                arm_into(seg, j as usize, dir, params, &mut pts);
                if dist(&a, &b) < params.dropout_max_width_m
                    && pts.len() >= 3
                    && let Some((c, d, _)) = fit_line(&pts)
                    && let Some(t) =
                        line_range_on_ray(c, d, geometry.bearing_rad(seg[k as usize].index))
                    && (t - r1).abs() < 0.1 + 0.05 * r1
                {
                    continue;
                }
            }
            let j = j as usize;
            // Open space lies toward p: below j when dir = +1.
            match edges.iter_mut().find(|e| e.0 == j) {
                Some(e) => {
                    e.1 |= dir > 0;
                    e.2 |= dir < 0;
                }
                None => edges.push((j, dir > 0, dir < 0)),
            }
        }
    }
    for (j, below, above) in edges {
        let side = match (below, above) {
            (true, true) => OpenSide::Both,
            (true, false) => OpenSide::Lower,
            _ => OpenSide::Higher,
        };
        let limit = geometry.max_range_m;
        out.push(edge_landmark(
            geometry,
            seg,
            j,
            side,
            limit,
            LandmarkKind::MaxRangeJump,
            params,
        ));
    }
}

/// Occlusion edges on one segment: the nearer of two neighbouring hits far apart in range.
fn occlusions(
    geometry: &ScanGeometry,
    seg: &[Ray],
    params: &DetectParams,
    out: &mut Vec<Landmark>,
) {
    for p in 0..seg.len().saturating_sub(1) {
        let (Some(a), Some(b)) = (seg[p].hit, seg[p + 1].hit) else {
            continue;
        };
        if (a - b).abs() <= params.occlusion_jump_m {
            continue;
        }
        let (pos, side, far) = if a < b {
            (p, OpenSide::Higher, b)
        } else {
            (p + 1, OpenSide::Lower, a)
        };
        out.push(edge_landmark(
            geometry,
            seg,
            pos,
            side,
            far,
            LandmarkKind::OcclusionEdge,
            params,
        ));
    }
}

/// Appends to `out` the hits continuing the surface from `pos` in direction `dir` (excluding
/// `pos`), within `arm_m` of the hit at `pos` and without range jumps; returns how many.
fn arm_into(
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
fn arm_len(seg: &[Ray], pos: usize, dir: isize, params: &DetectParams) -> usize {
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
fn prefix_moments(seg: &[Ray]) -> Vec<Moments> {
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
fn fit_line(points: &[RobotPoint]) -> Option<([f64; 2], [f64; 2], f64)> {
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
struct Moments {
    n: f64,
    sx: f64,
    sy: f64,
    sxx: f64,
    syy: f64,
    sxy: f64,
}

impl Moments {
    /// Adds the point at `(dx, dy)` from the reference point.
    fn add(&mut self, dx: f64, dy: f64) {
        self.n += 1.0;
        self.sx += dx;
        self.sy += dy;
        self.sxx += dx * dx;
        self.syy += dy * dy;
        self.sxy += dx * dy;
    }

    /// The moments of the run `lo..=hi` from the running sums of [`prefix_moments`].
    fn window(prefix: &[Moments], lo: usize, hi: usize) -> Self {
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
    fn of(points: &[RobotPoint]) -> Self {
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
    fn doubled_axis(&self) -> Option<[f64; 2]> {
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
fn cos2_between_axes(a: &Moments, b: &Moments) -> Option<f64> {
    let (u, v) = (a.doubled_axis()?, b.doubled_axis()?);
    let norms2 = (u[0] * u[0] + u[1] * u[1]) * (v[0] * v[0] + v[1] * v[1]);
    let cos_2t = (u[0] * v[0] + u[1] * v[1]) / norms2.sqrt();
    cos_2t.is_finite().then_some(0.5 * (1.0 + cos_2t))
}

/// Range at which the ray at `bearing` meets the line (centroid c, direction d), if ahead.
fn line_range_on_ray(c: [f64; 2], d: [f64; 2], bearing: f64) -> Option<f64> {
    let u = [bearing.cos(), bearing.sin()];
    let den = d[0] * u[1] - d[1] * u[0];
    if den.abs() < 1e-12 {
        return None;
    }
    let t = (d[0] * c[1] - d[1] * c[0]) / den;
    (t > 0.0).then_some(t)
}

/// Builds an edge landmark at segment position `pos` with its stability flags.
/// `far_range_m` is the range on the open side (the maximum range for a jump).
fn edge_landmark(
    geometry: &ScanGeometry,
    seg: &[Ray],
    pos: usize,
    side: OpenSide,
    far_range_m: f64,
    kind: LandmarkKind,
    params: &DetectParams,
) -> Landmark {
    let ray = seg[pos];
    let range = ray.hit.unwrap_or(geometry.max_range_m);
    let bearing = geometry.bearing_rad(ray.index);
    // The surface lies away from the open side.
    let (surface_dirs, open_dirs): (&[isize], &[isize]) = match side {
        OpenSide::Lower => (&[1], &[-1]),
        OpenSide::Higher => (&[-1], &[1]),
        OpenSide::Both => (&[], &[-1, 1]),
    };
    let l = match ray.hit {
        Some(_) => ray.pt,
        None => geometry.robot_point(ray.index, range),
    };
    let mut support = vec![l];
    for &d in surface_dirs {
        arm_into(seg, pos, d, params, &mut support);
    }
    let near_range_limit = range >= geometry.max_range_m - params.range_limit_margin_m;
    // Extrapolate the surface onto the open neighbour ray.
    let mut surface_continues = false;
    if let Some((c, d, _)) = fit_line(&support) {
        for &od in open_dirs {
            let q = pos as isize + od;
            if q < 0 || q as usize >= seg.len() {
                continue;
            }
            let b = geometry.bearing_rad(seg[q as usize].index);
            let reach = line_range_on_ray(c, d, b);
            let limit = far_range_m - params.range_limit_margin_m.max(0.02);
            if reach.is_none_or(|t| t >= limit) {
                surface_continues = true;
            }
        }
    }
    let (mut range_out, mut bearing_out) = (range, bearing);
    if params.edge_refine && support.len() >= 3 && side != OpenSide::Both {
        let od = open_dirs[0];
        let q = pos as isize + od;
        if q >= 0 && (q as usize) < seg.len() {
            let b_mid = 0.5 * (bearing + geometry.bearing_rad(seg[q as usize].index));
            if let Some((c, d, _)) = fit_line(&support)
                && let Some(t) = line_range_on_ray(c, d, b_mid)
                && (t - range).abs() < 0.5 * params.occlusion_jump_m
            {
                range_out = t;
                bearing_out = b_mid;
            }
        }
    }
    let tol = 0.05;
    let hidden_at_side = support.iter().skip(1).any(|q| {
        q.x_m() > l.x_m() - tol
            && q.y_m().abs() < l.y_m().abs() - tol
            && q.y_m().signum() == l.y_m().signum()
    });
    let support_rays = support.len();
    let mut lm = Landmark {
        index: ray.index,
        range_m: range_out,
        bearing_rad: bearing_out,
        kind,
        open_side: Some(side),
        near_range_limit,
        surface_continues,
        hidden_at_side,
        support_rays,
        score: 1.0,
    };
    lm.score = score(&lm, params);
    lm
}

/// Stability score: each raised flag multiplies it down.
fn score(l: &Landmark, params: &DetectParams) -> f64 {
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

/// Tests one segment position after another for a corner, with scratch space for the arms.
struct CornerFinder<'a> {
    seg: &'a [Ray],
    params: &'a DetectParams,
    /// Squared cosine of the smallest corner turn plus a rounding margin, when below 90 deg.
    straight_cos2: Option<f64>,
    prefix: Vec<Moments>,
    lo: Vec<RobotPoint>,
    hi: Vec<RobotPoint>,
}

impl<'a> CornerFinder<'a> {
    fn new(seg: &'a [Ray], params: &'a DetectParams) -> Self {
        // Arms whose fitted lines' angle has a larger squared cosine turn less than the
        // smallest corner.
        let a = params.corner_min_angle_rad;
        let straight_cos2 =
            (a > 0.0 && a < std::f64::consts::FRAC_PI_2).then(|| a.cos().powi(2) + 1e-7);
        Self {
            seg,
            params,
            straight_cos2,
            prefix: prefix_moments(seg),
            lo: Vec::new(),
            hi: Vec::new(),
        }
    }

    /// The turn and refined point of a corner at segment position `pos`, if it is one.
    fn candidate(&mut self, pos: usize) -> Option<(f64, RobotPoint)> {
        let (seg, params) = (self.seg, self.params);
        seg[pos].hit?;
        let p = seg[pos].pt;
        let min_len = 0.5 * params.arm_m;
        // An arm of `k` hits ending at segment position `end`, the corner point included.
        let long_enough = |k: usize, end: usize| {
            k >= 1 && k + 1 > params.corner_min_arm_rays && dist(&p, &seg[end].pt) >= min_len
        };
        // The arms' extents and moments first; their points only for the line fits.
        let n_lo = arm_len(seg, pos, -1, params);
        if !long_enough(n_lo, pos.wrapping_sub(n_lo)) {
            return None;
        }
        let n_hi = arm_len(seg, pos, 1, params);
        if !long_enough(n_hi, pos + n_hi) {
            return None;
        }
        // Most hits lie on straight walls: rule them out without trigonometry.
        if let Some(c) = self.straight_cos2
            && cos2_between_axes(
                &Moments::window(&self.prefix, pos - n_lo, pos),
                &Moments::window(&self.prefix, pos, pos + n_hi),
            )
            .is_some_and(|x| x > c)
        {
            return None;
        }
        let (lo, hi) = (&mut self.lo, &mut self.hi);
        lo.clear();
        lo.push(p);
        lo.extend((1..=n_lo).map(|t| seg[pos - t].pt));
        hi.clear();
        hi.push(p);
        hi.extend((1..=n_hi).map(|t| seg[pos + t].pt));
        let (c1, d1, e1) = fit_line(lo)?;
        let (c2, d2, e2) = fit_line(hi)?;
        if e1 > params.corner_max_residual_m || e2 > params.corner_max_residual_m {
            return None;
        }
        // Angle between the two lines (undirected), 0 = straight.
        let dot = (d1[0] * d2[0] + d1[1] * d2[1]).abs().min(1.0);
        let turn = dot.acos();
        if turn < params.corner_min_angle_rad {
            return None;
        }
        let refined = if params.corner_refine {
            intersect(c1, d1, c2, d2).unwrap_or(p)
        } else {
            p
        };
        Some((turn, refined))
    }
}

/// Corners on one segment, one per bend (the sharpest candidate of a run). With `near =
/// (c, reach)`, candidates are tried only at hits within `reach` of `c` and along the runs
/// of candidates they start, which yields the same corners wherever a run reaches that far.
fn corners(
    geometry: &ScanGeometry,
    seg: &[Ray],
    params: &DetectParams,
    near: Option<(RobotPoint, f64)>,
    out: &mut Vec<Landmark>,
) {
    let mut finder = CornerFinder::new(seg, params);
    // (pos, turn angle, refined point)
    let mut cands: Vec<(usize, f64, RobotPoint)> = Vec::new();
    match near {
        None => {
            for pos in 0..seg.len() {
                if let Some((turn, pt)) = finder.candidate(pos) {
                    cands.push((pos, turn, pt));
                }
            }
        }
        Some((c, reach)) => {
            let mut tried = vec![false; seg.len()];
            let mut found: Vec<Option<(f64, RobotPoint)>> = vec![None; seg.len()];
            for pos in 0..seg.len() {
                if seg[pos].hit.is_some() && !beyond(&c, &seg[pos].pt, reach) {
                    tried[pos] = true;
                    found[pos] = finder.candidate(pos);
                }
            }
            // Follow each run of candidates to its ends, up then down.
            for pos in 0..seg.len() {
                let k = pos + 1;
                if found[pos].is_some() && k < seg.len() && !tried[k] {
                    tried[k] = true;
                    found[k] = finder.candidate(k);
                }
            }
            for pos in (1..seg.len()).rev() {
                let k = pos - 1;
                if found[pos].is_some() && !tried[k] {
                    tried[k] = true;
                    found[k] = finder.candidate(k);
                }
            }
            cands.extend(
                found
                    .iter()
                    .enumerate()
                    .filter_map(|(pos, f)| f.map(|(turn, pt)| (pos, turn, pt))),
            );
        }
    }
    // Keep the sharpest candidate of each run of neighbouring candidates.
    let mut i = 0;
    while i < cands.len() {
        let mut j = i;
        let mut best = i;
        while j + 1 < cands.len() && cands[j + 1].0 == cands[j].0 + 1 {
            j += 1;
            if cands[j].1 > cands[best].1 {
                best = j;
            }
        }
        let (pos, _, pt) = cands[best];
        let mut scratch = Vec::new();
        let mut support = arm_into(seg, pos, -1, params, &mut scratch)
            + arm_into(seg, pos, 1, params, &mut scratch)
            + 1;
        support = support.max(1);
        let range = pt.range_m();
        let mut lm = Landmark {
            index: seg[pos].index,
            range_m: range,
            bearing_rad: pt.bearing_rad(),
            kind: LandmarkKind::Corner,
            open_side: None,
            near_range_limit: range >= geometry.max_range_m - params.range_limit_margin_m,
            surface_continues: false,
            hidden_at_side: false,
            support_rays: support,
            score: 1.0,
        };
        lm.score = score(&lm, params);
        out.push(lm);
        i = j + 1;
    }
}

/// Intersection of two lines given as (point, direction).
fn intersect(c1: [f64; 2], d1: [f64; 2], c2: [f64; 2], d2: [f64; 2]) -> Option<RobotPoint> {
    let den = d1[0] * d2[1] - d1[1] * d2[0];
    if den.abs() < 1e-9 {
        return None;
    }
    let t = ((c2[0] - c1[0]) * d2[1] - (c2[1] - c1[1]) * d2[0]) / den;
    Some(RobotPoint::new(c1[0] + t * d1[0], c1[1] + t * d1[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

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
    fn beyond_is_the_distance_test() {
        let o = RobotPoint::new(0.5, -0.25);
        for (x, y) in [
            (0.5, -0.05),
            (0.5 + 0.2, -0.25),
            (0.62, -0.09),
            (0.3, -0.25),
            (2.0, 1.0),
        ] {
            let p = RobotPoint::new(x, y);
            for limit in [
                -1.0,
                0.0,
                0.1,
                0.2,
                0.2 + 1e-12,
                0.25,
                f64::NAN,
                f64::INFINITY,
            ] {
                assert_eq!(
                    beyond(&o, &p, limit),
                    dist(&o, &p) > limit,
                    "{x} {y} {limit}"
                );
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
