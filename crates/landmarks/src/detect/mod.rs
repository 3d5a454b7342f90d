//! Landmark detection: max-range jumps (the paper), occlusion edges and corners, with
//! stability flags.

mod corners;
mod edges;
mod landmark;
mod lines;
mod params;

use scan_types::{RayStatus, RobotPoint, Scan, ScanGeometry};

use corners::corners;
use edges::{jumps, occlusions};
pub use landmark::{Landmark, LandmarkKind, OpenSide};
pub use params::DetectParams;

/// One usable ray: its index and, for a hit, its range and point (origin for a miss).
#[derive(Debug, Clone, Copy)]
struct Ray {
    index: usize,
    hit: Option<f64>,
    pt: RobotPoint,
}

/// `dist(a, b) > limit`, with the square root only when the squares are too close to tell.
pub(super) fn beyond(a: &RobotPoint, b: &RobotPoint, limit: f64) -> bool {
    let (dx, dy) = (b.x_m() - a.x_m(), b.y_m() - a.y_m());
    exceeds(dx * dx + dy * dy, limit)
}

/// `d2.sqrt() > limit`, with the square root only when the squares are too close to tell.
pub(super) fn exceeds(d2: f64, limit: f64) -> bool {
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
pub(super) fn dist(a: &RobotPoint, b: &RobotPoint) -> f64 {
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
