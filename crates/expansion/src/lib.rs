//! The obstacle-expansion kernel of the paper (section 3, eqs. 1-5): every hit point grows
//! into a disc of the robot radius, and each ray gets its **clearance**, the distance along
//! it to its first entry into any disc, capped by the ray's own free length.
//!
//! - [`clearances_reference`]: the paper's formulation, every hit against every ray (the
//!   ray's line, the disc, the quadratic, its discriminant). The definition; slow.
//! - [`Expander`]: the fast kernel, identical results within 1e-9 m, no allocation per scan.
//! - [`is_blocked`]: a ray is not a safe path for a leg longer than its clearance.
//! - [`write_clearance_csv`]: every ray's range, clearance and blocked flag as CSV.
//!
//! Edge cases (see `docs/expansion.md`): max-range and invalid readings are never obstacles;
//! an invalid ray's own free length is 0; a tangent ray touches its disc (blocked there); a
//! robot inside a disc is blocked at 0 m along every ray that leads toward the hit point and
//! not at all along rays that lead away from it.
//!
//! ```
//! use expansion::{Expander, is_blocked};
//! use scan_types::{Scan, ScanGeometry};
//! // The paper's Fig. 4: one hit at (2, 2), r = 0.3 m.
//! let g = ScanGeometry::paper();
//! let target = std::f64::consts::FRAC_PI_4;
//! let ranges: Vec<f64> = (0..g.ray_count)
//!     .map(|i| if g.nearest_index(target) == Some(i) { 8f64.sqrt() } else { 4.0 })
//!     .collect();
//! let scan = Scan::from_ranges(&g, &ranges, 0.0);
//! let mut clearance = vec![0.0; g.ray_count];
//! Expander::new(&g).clearances(&scan, 0.3, &mut clearance);
//! let i45 = g.nearest_index(target).unwrap();
//! assert!((clearance[i45] - (8f64.sqrt() - 0.3)).abs() < 1e-9);
//! assert!(is_blocked(clearance[i45], 3.0) && !is_blocked(clearance[0], 3.0));
//! ```

mod definition;
mod error;
mod fast;
mod reference;
mod table;

pub use definition::{free_length_m, ray_disc_entry_m};
pub use error::ExpansionError;
pub use fast::Expander;
pub use reference::clearances_reference;
pub use table::write_clearance_csv;

use scan_types::{Scan, ScanGeometry};

/// True when a ray with clearance `clearance_m` is not safe for a leg of `travel_m` metres
/// (clearance below the travel distance).
///
/// ```
/// assert!(expansion::is_blocked(0.99, 1.0));
/// assert!(!expansion::is_blocked(1.0, 1.0));
/// ```
pub fn is_blocked(clearance_m: f64, travel_m: f64) -> bool {
    // A NaN on either side counts as blocked.
    !matches!(
        clearance_m.partial_cmp(&travel_m),
        Some(std::cmp::Ordering::Greater | std::cmp::Ordering::Equal)
    )
}

/// Checks that a radius, a scan and an output buffer fit a geometry; the kernels accept
/// anything without panicking, this tells a caller what would be silently adapted.
///
/// ```
/// use expansion::{ExpansionError, check_inputs};
/// use scan_types::{Scan, ScanGeometry};
/// let g = ScanGeometry::centred(3, 1.0, 0.0, 4.0).unwrap();
/// let s = Scan::from_ranges(&g, &[1.0, 2.0, 3.0], 0.0);
/// assert!(check_inputs(&g, &s, 0.3, 3).is_ok());
/// assert!(matches!(check_inputs(&g, &s, -0.3, 3), Err(ExpansionError::InvalidRadius { .. })));
/// assert!(matches!(check_inputs(&g, &s, 0.3, 2), Err(ExpansionError::LengthMismatch { .. })));
/// ```
pub fn check_inputs(
    geometry: &ScanGeometry,
    scan: &Scan,
    radius_m: f64,
    out_len: usize,
) -> Result<(), ExpansionError> {
    if !(radius_m.is_finite() && radius_m >= 0.0) {
        return Err(ExpansionError::InvalidRadius { radius_m });
    }
    let expected = geometry.ray_count;
    for (what, got) in [
        ("scan ranges", scan.ranges_m.len()),
        ("scan statuses", scan.status.len()),
        ("output buffer", out_len),
    ] {
        if got != expected {
            return Err(ExpansionError::LengthMismatch {
                what,
                got,
                expected,
            });
        }
    }
    Ok(())
}
