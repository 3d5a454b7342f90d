//! Corner landmarks: where the scan's surface turns sharply between two straight arms.

use scan_types::{RobotPoint, ScanGeometry};

use super::landmark::score;
use super::lines::{Moments, arm_into, arm_len, cos2_between_axes, fit_line, prefix_moments};
use super::{DetectParams, Landmark, LandmarkKind, Ray, beyond, dist};

/// Tests one segment position after another for a corner, with scratch space for the arms.
pub(super) struct CornerFinder<'a> {
    seg: &'a [Ray],
    params: &'a DetectParams,
    /// Squared cosine of the smallest corner turn plus a rounding margin, when below 90 deg.
    straight_cos2: Option<f64>,
    prefix: Vec<Moments>,
    lo: Vec<RobotPoint>,
    hi: Vec<RobotPoint>,
}

impl<'a> CornerFinder<'a> {
    pub(super) fn new(seg: &'a [Ray], params: &'a DetectParams) -> Self {
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
    pub(super) fn candidate(&mut self, pos: usize) -> Option<(f64, RobotPoint)> {
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
pub(super) fn corners(
    geometry: &ScanGeometry,
    seg: &[Ray],
    params: &DetectParams,
    near: Option<(RobotPoint, f64)>,
    out: &mut Vec<Landmark>,
) {
    let cands = corner_candidates(seg, params, near);
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
        out.push(corner_landmark(geometry, seg, params, pos, pt));
        i = j + 1;
    }
}

/// The corner candidates of `seg` as (pos, turn angle, refined point): at every ray, or with
/// `near`, at hits within reach of it and along the runs of candidates they start.
fn corner_candidates(
    seg: &[Ray],
    params: &DetectParams,
    near: Option<(RobotPoint, f64)>,
) -> Vec<(usize, f64, RobotPoint)> {
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
    cands
}

/// The corner landmark at `pos`, refined to `pt`, with its arms as support.
fn corner_landmark(
    geometry: &ScanGeometry,
    seg: &[Ray],
    params: &DetectParams,
    pos: usize,
    pt: RobotPoint,
) -> Landmark {
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
        near_range_limit: range >= geometry.max_range_m - params.range_limit_margin_for(geometry),
        surface_continues: false,
        hidden_at_side: false,
        support_rays: support,
        score: 1.0,
    };
    lm.score = score(&lm, params);
    lm
}

/// Intersection of two lines given as (point, direction).
pub(super) fn intersect(
    c1: [f64; 2],
    d1: [f64; 2],
    c2: [f64; 2],
    d2: [f64; 2],
) -> Option<RobotPoint> {
    let den = d1[0] * d2[1] - d1[1] * d2[0];
    if den.abs() < 1e-9 {
        return None;
    }
    let t = ((c2[0] - c1[0]) * d2[1] - (c2[1] - c1[1]) * d2[0]) / den;
    Some(RobotPoint::new(c1[0] + t * d1[0], c1[1] + t * d1[1]))
}
