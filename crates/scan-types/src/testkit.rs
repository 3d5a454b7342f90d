//! Scans of hand-made segment worlds, for tests whose expected values are checked by hand
//! (feature `testkit`; dev-only).

use crate::{RayStatus, Scan, ScanGeometry};

/// A wall from (x0, y0) to (x1, y1), metres.
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

/// The four walls of the axis-aligned box from (x0, y0) to (x1, y1).
pub fn boxed(x0: f64, y0: f64, x1: f64, y1: f64) -> Vec<Seg> {
    vec![
        ((x0, y0), (x1, y0)),
        ((x1, y0), (x1, y1)),
        ((x1, y1), (x0, y1)),
        ((x0, y1), (x0, y0)),
    ]
}

/// Deterministic pseudo-Gaussian noise (sum of 12 uniforms from a linear congruential generator).
pub struct Noise(u64);

impl Noise {
    /// A generator for `seed`.
    pub fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(6364136223846793005).wrapping_add(1))
    }

    /// One sample uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }

    /// One sample of zero mean and standard deviation `sigma`.
    pub fn gauss(&mut self, sigma: f64) -> f64 {
        let s: f64 = (0..12).map(|_| self.uniform()).sum();
        (s - 6.0) * sigma
    }
}

/// `scan` with Gaussian noise of `sigma` on its hits (misses and errors stay as they are).
pub fn noisy(g: &ScanGeometry, scan: &Scan, sigma: f64, seed: u64) -> Scan {
    let mut n = Noise::new(seed);
    let ranges: Vec<f64> = scan
        .ranges_m
        .iter()
        .zip(&scan.status)
        .map(|(&r, s)| match s {
            RayStatus::Hit => (r + n.gauss(sigma)).min(g.max_range_m - 1e-6),
            _ => r,
        })
        .collect();
    let mut out = Scan::from_ranges(g, &ranges, 0.0);
    out.status = scan.status.clone();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_seen_from_its_centre() {
        // From the centre of a 4 m x 2 m box: 2 m to the side walls, 1 m up and down, and
        // sqrt(2) m along 45 deg (it meets the top wall at x = 1).
        let walls = boxed(-2.0, -1.0, 2.0, 1.0);
        let at = |deg: f64| raycast(&walls, 0.0, 0.0, deg.to_radians()).unwrap();
        assert!((at(0.0) - 2.0).abs() < 1e-12);
        assert!((at(90.0) - 1.0).abs() < 1e-12);
        assert!((at(180.0) - 2.0).abs() < 1e-12);
        assert!((at(45.0) - 2f64.sqrt()).abs() < 1e-12);
        assert_eq!(raycast(&walls[..1], 0.0, 0.0, 0.5), None);
    }

    #[test]
    fn noise_is_seeded_and_centred() {
        let mut a = Noise::new(3);
        let mut b = Noise::new(3);
        let xs: Vec<f64> = (0..4000).map(|_| a.gauss(0.01)).collect();
        assert!(
            xs.iter()
                .zip((0..4000).map(|_| b.gauss(0.01)))
                .all(|(x, y)| *x == y)
        );
        let mean = xs.iter().sum::<f64>() / xs.len() as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / xs.len() as f64;
        // Mean within 3 sigma / sqrt(n) of 0, standard deviation within 10 % of 0.01.
        assert!(mean.abs() < 3.0 * 0.01 / 4000f64.sqrt());
        assert!((var.sqrt() - 0.01).abs() < 0.001);
    }
}
