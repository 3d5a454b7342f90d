//! Edge landmarks: max-range jumps (the paper) and occlusion edges, with their support and
//! surface checks.

use scan_types::{RobotPoint, ScanGeometry};

use super::landmark::score;
use super::lines::{arm_into, fit_line, line_range_on_ray};
use super::{DetectParams, Landmark, LandmarkKind, OpenSide, Ray, dist};

/// The paper's rule on one segment.
pub(super) fn jumps(
    geometry: &ScanGeometry,
    seg: &[Ray],
    params: &DetectParams,
    out: &mut Vec<Landmark>,
) {
    let len = seg.len() as isize;
    // Edge position in the segment -> open sides seen.
    let mut edges: Vec<(usize, bool, bool)> = Vec::new(); // (pos, open below, open above)
    for p in 0..len {
        if seg[p as usize].hit.is_some() {
            continue;
        }
        for dir in [-1isize, 1] {
            let Some(j) = jump_edge(geometry, seg, p, dir, params) else {
                continue;
            };
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

/// The edge seen from open ray `p` looking `dir`: the first hit that way, if the ray
/// `neighbour_n` away is a hit and the open run is long and wide enough and no bridged dropout.
fn jump_edge(
    geometry: &ScanGeometry,
    seg: &[Ray],
    p: isize,
    dir: isize,
    params: &DetectParams,
) -> Option<isize> {
    let n = params.neighbour_n as isize;
    let len = seg.len() as isize;
    let q = p + dir * n;
    if q < 0 || q >= len || seg[q as usize].hit.is_none() {
        return None;
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
        return None;
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
            return None;
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
            && let Some(t) = line_range_on_ray(c, d, geometry.bearing_rad(seg[k as usize].index))
            && (t - r1).abs() < 0.1 + 0.05 * r1
        {
            return None;
        }
    }
    Some(j)
}

/// Occlusion edges on one segment: the nearer of two neighbouring hits far apart in range.
pub(super) fn occlusions(
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

/// Builds an edge landmark at segment position `pos` with its stability flags.
/// `far_range_m` is the range on the open side (the maximum range for a jump).
pub(super) fn edge_landmark(
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
    let near_range_limit = range >= geometry.max_range_m - params.range_limit_margin_for(geometry);
    // Extrapolate the surface onto the open neighbour ray.
    let surface_continues =
        surface_continues(geometry, seg, pos, open_dirs, &support, far_range_m, params);
    let (range_out, bearing_out) = refined_edge(
        geometry, seg, pos, side, open_dirs, &support, range, bearing, params,
    );
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

/// Whether the line fitted to `support` reaches an open neighbour ray only at or beyond
/// `far_range_m` (less the margin), or not at all.
fn surface_continues(
    geometry: &ScanGeometry,
    seg: &[Ray],
    pos: usize,
    open_dirs: &[isize],
    support: &[RobotPoint],
    far_range_m: f64,
    params: &DetectParams,
) -> bool {
    let mut surface_continues = false;
    if let Some((c, d, _)) = fit_line(support) {
        for &od in open_dirs {
            let q = pos as isize + od;
            if q < 0 || q as usize >= seg.len() {
                continue;
            }
            let b = geometry.bearing_rad(seg[q as usize].index);
            let reach = line_range_on_ray(c, d, b);
            let limit = far_range_m - params.range_limit_margin_for(geometry).max(0.02);
            if reach.is_none_or(|t| t >= limit) {
                surface_continues = true;
            }
        }
    }
    surface_continues
}

/// With `edge_refine`, the edge moved to where the supporting line meets the bearing half way
/// to the open neighbour (when that is close to `range`); else (`range`, `bearing`).
#[allow(clippy::too_many_arguments)]
fn refined_edge(
    geometry: &ScanGeometry,
    seg: &[Ray],
    pos: usize,
    side: OpenSide,
    open_dirs: &[isize],
    support: &[RobotPoint],
    range: f64,
    bearing: f64,
    params: &DetectParams,
) -> (f64, f64) {
    let (mut range_out, mut bearing_out) = (range, bearing);
    if params.edge_refine && support.len() >= 3 && side != OpenSide::Both {
        let od = open_dirs[0];
        let q = pos as isize + od;
        if q >= 0 && (q as usize) < seg.len() {
            let b_mid = 0.5 * (bearing + geometry.bearing_rad(seg[q as usize].index));
            if let Some((c, d, _)) = fit_line(support)
                && let Some(t) = line_range_on_ray(c, d, b_mid)
                && (t - range).abs() < 0.5 * params.occlusion_jump_m
            {
                range_out = t;
                bearing_out = b_mid;
            }
        }
    }
    (range_out, bearing_out)
}
