//! The per-ray clearance table `robot-app expand` prints: one CSV row per ray.

use std::io::Write;

use scan_types::{RayStatus, ScanGeometry};

use crate::is_blocked;

/// Writes the per-ray clearance table (`index,bearing_rad,range_m,clearance_m,blocked`, an
/// error ray's range NaN) of `robot-app expand`; returns how many rays are blocked.
pub fn write_clearance_csv<W: Write>(
    mut w: W,
    geometry: &ScanGeometry,
    ranges_m: &[f64],
    status: &[RayStatus],
    clearance_m: &[f64],
    travel_m: f64,
) -> std::io::Result<usize> {
    writeln!(w, "index,bearing_rad,range_m,clearance_m,blocked")?;
    let mut blocked_count = 0;
    for (i, &c) in clearance_m.iter().enumerate() {
        let range = match status.get(i) {
            Some(RayStatus::Error(_)) | None => f64::NAN,
            _ => ranges_m[i],
        };
        let blocked = is_blocked(c, travel_m);
        blocked_count += usize::from(blocked);
        writeln!(
            w,
            "{i},{:.9},{:.6},{:.6},{}",
            geometry.bearing_rad(i),
            range,
            c,
            u8::from(blocked)
        )?;
    }
    Ok(blocked_count)
}
