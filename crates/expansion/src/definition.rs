//! The definitions shared by both kernels: which rays are obstacles, each ray's own free
//! length, and the first entry of a ray into one expanded disc.

use scan_types::{RayStatus, Scan, ScanGeometry};

/// The disc centre of ray `index`: its range if the ray is a usable hit.
///
/// A hit is an obstacle when its range is finite and >= 0; anything else (max-range misses,
/// error codes, a `Hit` carrying NaN or a negative range) is never an obstacle.
#[inline]
pub(crate) fn obstacle_range_m(scan: &Scan, index: usize) -> Option<f64> {
    match (scan.status.get(index), scan.ranges_m.get(index)) {
        (Some(RayStatus::Hit), Some(&r)) if r.is_finite() && r >= 0.0 => Some(r),
        _ => None,
    }
}

/// The free length of ray `index` before any expansion, metres.
///
/// - a hit: its range (the obstacle itself);
/// - a max-range miss (the paper's set A): the maximum range;
/// - an error reading, a malformed entry, or a ray the scan does not have: 0, because
///   goalseek never drives along a direction it has not measured.
///
/// ```
/// use expansion::free_length_m;
/// use scan_types::{Scan, ScanGeometry};
/// let g = ScanGeometry::centred(3, 1.0, 0.0, 4.0).unwrap();
/// let s = Scan::from_ranges(&g, &[1.5, 4.0, f64::NAN], 0.0);
/// assert_eq!(free_length_m(&g, &s, 0), 1.5);
/// assert_eq!(free_length_m(&g, &s, 1), 4.0);
/// assert_eq!(free_length_m(&g, &s, 2), 0.0);
/// assert_eq!(free_length_m(&g, &s, 3), 0.0);
/// ```
#[inline]
pub fn free_length_m(geometry: &ScanGeometry, scan: &Scan, index: usize) -> f64 {
    match scan.status.get(index) {
        Some(RayStatus::MaxRange) => geometry.max_range_m,
        Some(RayStatus::Hit) => obstacle_range_m(scan, index).unwrap_or(0.0),
        _ => 0.0,
    }
}

/// The radius the kernels use: a negative, NaN or infinite radius counts as 0.
#[inline]
pub(crate) fn effective_radius_m(radius_m: f64) -> f64 {
    if radius_m.is_finite() && radius_m > 0.0 {
        radius_m
    } else {
        0.0
    }
}

/// Where a ray from the robot centre along the unit vector `(ux, uy)` first enters the
/// closed disc of radius `radius_m` around `(cx, cy)` (robot frame), metres; `None` if never.
///
/// Points on the ray are `t * u`, `t >= 0`; they lie in the disc where
/// `t^2 - 2 t (u.c) + |c|^2 - r^2 <= 0`. With `tm = u.c` and `D = tm^2 - |c|^2 + r^2`:
/// - `D < 0`: the line misses the disc; `D = 0`: tangent, the ray touches it at `tm`
///   (touching counts as contact);
/// - `tm <= 0`: moving along the ray never brings the robot closer to the centre, so the
///   disc never blocks it (it lies behind, or the robot is inside and leaving it);
/// - otherwise the entry is `max(tm - sqrt(D), 0)`: 0 when the robot is already inside
///   the disc (or on its edge) and the ray leads deeper in.
///
/// ```
/// use expansion::ray_disc_entry_m;
/// // Disc of radius 0.5 at (2, 0.5): the x axis is tangent to it at x = 2.
/// assert_eq!(ray_disc_entry_m(1.0, 0.0, 2.0, 0.5, 0.5), Some(2.0));
/// // Straight at a disc of radius 1 at (3, 0): entry at 2.
/// assert_eq!(ray_disc_entry_m(1.0, 0.0, 3.0, 0.0, 1.0), Some(2.0));
/// // Away from it: never.
/// assert_eq!(ray_disc_entry_m(-1.0, 0.0, 3.0, 0.0, 1.0), None);
/// // Inside it (centre 0.1 m ahead, radius 0.3): blocked at once when heading toward it...
/// assert_eq!(ray_disc_entry_m(1.0, 0.0, 0.1, 0.0, 0.3), Some(0.0));
/// // ... and free when heading away.
/// assert_eq!(ray_disc_entry_m(-1.0, 0.0, 0.1, 0.0, 0.3), None);
/// ```
pub fn ray_disc_entry_m(ux: f64, uy: f64, cx: f64, cy: f64, radius_m: f64) -> Option<f64> {
    let tm = ux * cx + uy * cy;
    let perp = ux * cy - uy * cx;
    let disc = radius_m * radius_m - perp * perp;
    if disc < 0.0 || tm <= 0.0 {
        return None;
    }
    Some((tm - disc.sqrt()).max(0.0))
}
