//! Helpers shared by the expansion tests.

#![allow(dead_code)]

use expansion::{Expander, clearances_reference};
use scan_types::{Scan, ScanGeometry};

/// Both kernels on one scan: (reference, fast).
pub fn both(g: &ScanGeometry, scan: &Scan, r: f64) -> (Vec<f64>, Vec<f64>) {
    let mut slow = vec![f64::NAN; g.ray_count];
    let mut fast = vec![f64::NAN; g.ray_count];
    clearances_reference(g, scan, r, &mut slow);
    Expander::new(g).clearances(scan, r, &mut fast);
    (slow, fast)
}

/// Index of the first ray where the kernels differ by more than `tol`.
pub fn first_difference(a: &[f64], b: &[f64], tol: f64) -> Option<usize> {
    a.iter()
        .zip(b)
        .position(|(x, y)| (x - y).abs().is_nan() || (x - y).abs() > tol)
}

/// A scan of all max-range rays except `hits` (index, range).
pub fn scan_with_hits(g: &ScanGeometry, hits: &[(usize, f64)]) -> Scan {
    let mut ranges = vec![g.max_range_m; g.ray_count];
    for &(i, r) in hits {
        ranges[i] = r;
    }
    Scan::from_ranges(g, &ranges, 0.0)
}
