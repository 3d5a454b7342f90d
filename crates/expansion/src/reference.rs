//! The reference kernel: the paper's section 3 (eqs. 1-5) as written, every hit against
//! every ray. It is slow (rays x hits) and meant to be read as the definition of the result.

use scan_types::{Scan, ScanGeometry};

use crate::definition::{effective_radius_m, free_length_m, obstacle_range_m};

/// Clearance of every ray after growing every hit into a disc of `radius_m`, computed the
/// paper's way; writes `out[i]` for ray `i` (metres, >= 0).
///
/// For each ray (a line through the robot R and the ray's end point, eq. 2, slope eq. 3)
/// and each hit point C = (h, k) (the disc of eq. 1), substitute the line into the circle
/// (eq. 4) and solve the quadratic (eq. 5). Discriminant < 0: no contact; = 0: tangent
/// (counts as contact); > 0: the ray enters the disc at the nearer root in front of the
/// robot. The clearance is the nearest entry over all discs, capped by the ray's own free
/// length ([`crate::free_length_m`]). The rules for a robot already inside a disc are those
/// of [`crate::ray_disc_entry_m`].
///
/// The only departure from the paper: a line steeper than 45 deg is written `x = m y + b`
/// instead of `y = m x + b`, so that vertical rays need no special case.
///
/// `out` should have `geometry.ray_count` entries; rays the scan lacks count as invalid,
/// entries of `out` beyond the geometry's rays are set to 0. It never panics.
///
/// ```
/// use expansion::clearances_reference;
/// use scan_types::{Scan, ScanGeometry};
/// // Three rays at -90, 0, +90 deg; one hit 2 m straight ahead, r = 0.5.
/// let g = ScanGeometry::centred(3, std::f64::consts::PI, 0.0, 4.0).unwrap();
/// let s = Scan::from_ranges(&g, &[4.0, 2.0, 4.0], 0.0);
/// let mut out = [0.0; 3];
/// clearances_reference(&g, &s, 0.5, &mut out);
/// assert_eq!(out, [4.0, 1.5, 4.0]);
/// ```
pub fn clearances_reference(geometry: &ScanGeometry, scan: &Scan, radius_m: f64, out: &mut [f64]) {
    let r = effective_radius_m(radius_m);
    let n = geometry.ray_count.min(out.len());
    // The robot, in the robot frame.
    let (rx, ry) = (0.0_f64, 0.0_f64);
    for (i, slot) in out.iter_mut().enumerate().take(n) {
        let mut clearance = free_length_m(geometry, scan, i);
        let bearing = geometry.bearing_rad(i);
        // The ray's end point (at maximum range) fixes the line through R (eq. 3).
        let (ex, ey) = (
            rx + geometry.max_range_m * bearing.cos(),
            ry + geometry.max_range_m * bearing.sin(),
        );
        for j in 0..n {
            let Some(range_m) = obstacle_range_m(scan, j) else {
                continue;
            };
            // Eq. 1: the circle around the hit point C = (h, k).
            let hit_bearing = geometry.bearing_rad(j);
            let (h, k) = (
                rx + range_m * hit_bearing.cos(),
                ry + range_m * hit_bearing.sin(),
            );
            if let Some(t) = paper_entry(rx, ry, ex, ey, h, k, r) {
                clearance = clearance.min(t);
            }
        }
        *slot = clearance;
    }
    for slot in out.iter_mut().skip(n) {
        *slot = 0.0;
    }
}

/// Distance from R along the ray R -> E to its first entry into the disc of radius `r`
/// around (h, k), by eqs. 2-5; `None` when the ray never enters it.
fn paper_entry(rx: f64, ry: f64, ex: f64, ey: f64, h: f64, k: f64, r: f64) -> Option<f64> {
    let (dx, dy) = (ex - rx, ey - ry);
    let length = dx.hypot(dy);
    // Work with (p, q) = (x, y) for shallow lines and (y, x) for steep ones, so that the
    // line is always q = m p + b with |m| <= 1.
    let (rp, rq, dp, dq, hp, hq) = if dx.abs() >= dy.abs() {
        (rx, ry, dx, dy, h, k)
    } else {
        (ry, rx, dy, dx, k, h)
    };
    // Eq. 3: the slope; eq. 2: q = m p + b through R.
    let m = dq / dp;
    let b = rq - m * rp;
    // Eq. 4: (p - hp)^2 + (m p + b - hq)^2 = r^2, i.e. eq. 5: a p^2 + bb p + c = 0.
    let a = 1.0 + m * m;
    let bb = 2.0 * (m * (b - hq) - hp);
    let c = hp * hp + (b - hq) * (b - hq) - r * r;
    let discriminant = bb * bb - 4.0 * a * c;
    if discriminant < 0.0 {
        return None; // the line misses the disc
    }
    // Distance from R along the ray to the point of the line with coordinate p.
    let along = |p: f64| (p - rp) / dp * length;
    // The middle of the chord: if it is not in front of R, moving along the ray never
    // approaches the hit point (the disc is behind, or R is inside and leaving it).
    if along(-bb / (2.0 * a)) <= 0.0 {
        return None;
    }
    let root = discriminant.sqrt();
    let t1 = along((-bb - root) / (2.0 * a));
    let t2 = along((-bb + root) / (2.0 * a));
    // The nearer crossing; negative when R is already inside the disc: blocked at once.
    Some(t1.min(t2).max(0.0))
}
