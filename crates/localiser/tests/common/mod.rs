//! A tiny hand-written ray caster over line segments, for building scans whose landmarks
//! can be checked by hand.
#![allow(dead_code)]

use scan_types::{Scan, ScanGeometry};

/// A wall from (x0, y0) to (x1, y1), metres, in the robot's starting frame.
pub type Seg = ((f64, f64), (f64, f64));

/// Distance from (ox, oy) along `angle` to the nearest segment, if any.
pub fn raycast(segs: &[Seg], ox: f64, oy: f64, angle: f64) -> Option<f64> {
    let (ux, uy) = (angle.cos(), angle.sin());
    let mut best: Option<f64> = None;
    for &((x0, y0), (x1, y1)) in segs {
        let (ex, ey) = (x1 - x0, y1 - y0);
        let den = ux * ey - uy * ex;
        if den.abs() < 1e-12 {
            continue;
        }
        let (wx, wy) = (x0 - ox, y0 - oy);
        let t = (wx * ey - wy * ex) / den;
        let s = (wx * uy - wy * ux) / den;
        if t > 1e-9 && (-1e-12..=1.0 + 1e-12).contains(&s) && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    }
    best
}

/// The scan seen from (x, y) heading `theta`: misses read +inf (max range).
pub fn scan_at(g: &ScanGeometry, segs: &[Seg], x: f64, y: f64, theta: f64) -> Scan {
    let ranges: Vec<f64> = (0..g.ray_count)
        .map(|i| raycast(segs, x, y, theta + g.bearing_rad(i)).unwrap_or(f64::INFINITY))
        .collect();
    Scan::from_ranges(g, &ranges, 0.0)
}

/// The four walls of an axis-aligned box.
pub fn boxed(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Seg> {
    vec![
        ((x0, y0), (x1, y0)),
        ((x1, y0), (x1, y1)),
        ((x1, y1), (x0, y1)),
        ((x0, y1), (x0, y0)),
    ]
}
