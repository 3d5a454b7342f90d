//! Scan geometry: where each ray of a scan points and what ranges it can report.

use std::cell::RefCell;
use std::rc::Rc;

use crate::{RobotPoint, ScanTypesError};

/// A geometry's ray directions: first bearing, increment, ray count, `[cos, sin]` per ray.
type Directions = (f64, f64, usize, Rc<[[f64; 2]]>);

thread_local! {
    /// The ray directions of the last geometry asked on this thread.
    static DIRECTIONS: RefCell<Option<Directions>> = const { RefCell::new(None) };
}

/// The fixed geometry of a scan: bearings of its rays and its range limits.
///
/// Ray `i` points at `first_bearing_rad + i * increment_rad` relative to the
/// robot's heading (counter-clockwise positive).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ScanGeometry {
    /// Bearing of ray 0 relative to the heading, radians.
    pub first_bearing_rad: f64,
    /// Angle between neighbouring rays, radians (positive: rays sweep counter-clockwise).
    pub increment_rad: f64,
    /// Number of rays in a scan.
    pub ray_count: usize,
    /// Smallest range the sensor reports as a distance, metres.
    pub min_range_m: f64,
    /// Largest range; a ray that hits nothing reads exactly this, metres.
    pub max_range_m: f64,
}

impl ScanGeometry {
    /// Builds a geometry, checking every field.
    ///
    /// ```
    /// use scan_types::ScanGeometry;
    /// assert!(ScanGeometry::new(0.0, 0.01, 0, 0.0, 4.0).is_err());
    /// assert!(ScanGeometry::new(-1.0, 0.01, 201, 0.02, 4.0).is_ok());
    /// ```
    pub fn new(
        first_bearing_rad: f64,
        increment_rad: f64,
        ray_count: usize,
        min_range_m: f64,
        max_range_m: f64,
    ) -> Result<Self, ScanTypesError> {
        let bad = |field, value, why| Err(ScanTypesError::InvalidGeometry { field, value, why });
        if !first_bearing_rad.is_finite() {
            return bad("first_bearing_rad", first_bearing_rad, "must be finite");
        }
        if !increment_rad.is_finite() || increment_rad == 0.0 {
            return bad(
                "increment_rad",
                increment_rad,
                "must be finite and non-zero",
            );
        }
        if ray_count == 0 {
            return bad("ray_count", 0.0, "must be at least 1");
        }
        // No scanner sweeps more than a full turn (and a geometry that did would make the
        // kernels that wrap bearings around allocate a turn's worth of rays per turn).
        let turn = std::f64::consts::TAU * (1.0 + 1e-9);
        if increment_rad.abs() > turn || increment_rad.abs() * (ray_count - 1) as f64 > turn {
            return bad(
                "increment_rad",
                increment_rad,
                "spans more than a full turn from the first ray to the last",
            );
        }
        if !(min_range_m.is_finite() && min_range_m >= 0.0) {
            return bad("min_range_m", min_range_m, "must be finite and >= 0");
        }
        if !(max_range_m.is_finite() && max_range_m > min_range_m) {
            return bad(
                "max_range_m",
                max_range_m,
                "must be finite and > min_range_m",
            );
        }
        Ok(Self {
            first_bearing_rad,
            increment_rad,
            ray_count,
            min_range_m,
            max_range_m,
        })
    }

    /// A geometry of `ray_count` rays spread evenly over `fov_rad`, centred on the heading.
    ///
    /// ```
    /// use scan_types::ScanGeometry;
    /// let g = ScanGeometry::centred(3, std::f64::consts::PI, 0.0, 10.0).unwrap();
    /// assert!((g.bearing_rad(0) + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    /// assert!((g.bearing_rad(2) - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
    /// ```
    pub fn centred(
        ray_count: usize,
        fov_rad: f64,
        min_range_m: f64,
        max_range_m: f64,
    ) -> Result<Self, ScanTypesError> {
        if ray_count < 2 {
            return Self::new(
                0.0,
                fov_rad.max(f64::MIN_POSITIVE),
                ray_count,
                min_range_m,
                max_range_m,
            );
        }
        let increment_rad = fov_rad / (ray_count - 1) as f64;
        Self::new(
            -fov_rad / 2.0,
            increment_rad,
            ray_count,
            min_range_m,
            max_range_m,
        )
    }

    /// The paper's sensor: 685 rays over 240 deg, 4.0 m maximum range.
    pub fn paper() -> Self {
        Self::centred(685, 240f64.to_radians(), 0.0, 4.0).expect("constant geometry is valid")
    }

    /// Bearing of ray `index` relative to the heading, radians (not normalised).
    pub fn bearing_rad(&self, index: usize) -> f64 {
        self.first_bearing_rad + index as f64 * self.increment_rad
    }

    /// Bearing of the last ray, radians.
    pub fn last_bearing_rad(&self) -> f64 {
        self.bearing_rad(self.ray_count - 1)
    }

    /// The angle covered from the first to the last ray, radians.
    pub fn fov_rad(&self) -> f64 {
        (self.ray_count - 1) as f64 * self.increment_rad.abs()
    }

    /// Fractional ray index at `bearing_rad`; may lie outside `0..ray_count`.
    ///
    /// ```
    /// use scan_types::ScanGeometry;
    /// let g = ScanGeometry::paper();
    /// assert!((g.fractional_index(0.0) - 342.0).abs() < 1e-9);
    /// ```
    pub fn fractional_index(&self, bearing_rad: f64) -> f64 {
        (bearing_rad - self.first_bearing_rad) / self.increment_rad
    }

    /// The ray nearest to `bearing_rad`, or `None` when it lies outside the field of view
    /// by more than half an increment.
    pub fn nearest_index(&self, bearing_rad: f64) -> Option<usize> {
        let f = self.fractional_index(bearing_rad).round();
        if f.is_finite() && f >= 0.0 && f <= (self.ray_count - 1) as f64 {
            Some(f as usize)
        } else {
            None
        }
    }

    /// The point in the robot frame at `range_m` along ray `index`.
    pub fn robot_point(&self, index: usize, range_m: f64) -> RobotPoint {
        let b = self.bearing_rad(index);
        RobotPoint::new(range_m * b.cos(), range_m * b.sin())
    }

    /// `[cos, sin]` of every ray's bearing: `range * d[0], range * d[1]` is exactly
    /// [`Self::robot_point`]. Computed once per thread for the last geometry asked, so the
    /// points of each scan need no trigonometry.
    pub fn directions(&self) -> Rc<[[f64; 2]]> {
        let key = (self.first_bearing_rad, self.increment_rad, self.ray_count);
        DIRECTIONS.with(|cell| {
            let mut cached = cell.borrow_mut();
            if let Some((f, i, n, d)) = cached.as_ref()
                && (*f, *i, *n) == key
            {
                return Rc::clone(d);
            }
            let d: Rc<[[f64; 2]]> = (0..self.ray_count)
                .map(|k| {
                    let b = self.bearing_rad(k);
                    [b.cos(), b.sin()]
                })
                .collect();
            *cached = Some((key.0, key.1, key.2, Rc::clone(&d)));
            d
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use std::f64::consts::{FRAC_PI_2, PI};

    #[test]
    fn paper_geometry_matches_the_paper() {
        let g = ScanGeometry::paper();
        assert_eq!(g.ray_count, 685);
        assert_abs_diff_eq!(g.first_bearing_rad, -120f64.to_radians(), epsilon = 1e-12);
        assert_abs_diff_eq!(g.last_bearing_rad(), 120f64.to_radians(), epsilon = 1e-12);
        // 240 deg / 684 gaps = 0.3509 deg, the paper's "0.35 deg".
        assert_abs_diff_eq!(g.increment_rad.to_degrees(), 240.0 / 684.0, epsilon = 1e-12);
        assert_eq!(g.max_range_m, 4.0);
    }

    #[test]
    fn bearing_of_ray_i() {
        let g = ScanGeometry::new(-1.0, 0.25, 9, 0.0, 5.0).unwrap();
        assert_eq!(g.bearing_rad(0), -1.0);
        assert_eq!(g.bearing_rad(4), 0.0);
        assert_eq!(g.bearing_rad(8), 1.0);
        assert_eq!(g.fov_rad(), 2.0);
        assert_eq!(g.fractional_index(0.125), 4.5);
        assert_eq!(g.nearest_index(0.26), Some(5));
        assert_eq!(g.nearest_index(1.2), None);
        assert_eq!(g.nearest_index(-1.1), Some(0));
    }

    #[test]
    fn urg_04lx_step_geometry() {
        // URG-04LX PP: step s at (s - 384) * 2 pi / 1024; steps 44..=725.
        let inc = 2.0 * PI / 1024.0;
        let g = ScanGeometry::new((44.0 - 384.0) * inc, inc, 682, 0.02, 5.6).unwrap();
        assert_abs_diff_eq!(g.bearing_rad(340), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(g.first_bearing_rad, -2.0862, epsilon = 1e-4);
        assert_abs_diff_eq!(g.last_bearing_rad(), 2.0923, epsilon = 1e-4);
    }

    #[test]
    fn directions_give_robot_points() {
        let a = ScanGeometry::paper();
        let b = ScanGeometry::centred(5, PI, 0.0, 10.0).unwrap();
        // Alternate geometries: the cache follows the one asked.
        for g in [a, b, a] {
            let d = g.directions();
            assert_eq!(d.len(), g.ray_count);
            for (i, dir) in d.iter().enumerate() {
                let p = g.robot_point(i, 2.5);
                assert_eq!(RobotPoint::new(2.5 * dir[0], 2.5 * dir[1]), p);
            }
        }
        assert_abs_diff_eq!(b.directions()[4][1], 1.0, epsilon = 1e-12);
    }

    #[test]
    fn robot_point_of_ray() {
        let g = ScanGeometry::centred(3, PI, 0.0, 10.0).unwrap();
        let left = g.robot_point(2, 2.0);
        assert_abs_diff_eq!(left.x_m(), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(left.y_m(), 2.0, epsilon = 1e-12);
        let ahead = g.robot_point(1, 3.0);
        assert_abs_diff_eq!(ahead.x_m(), 3.0, epsilon = 1e-12);
        assert_abs_diff_eq!(g.bearing_rad(0), -FRAC_PI_2, epsilon = 1e-12);
    }

    #[test]
    fn rejects_bad_fields() {
        assert!(ScanGeometry::new(f64::NAN, 0.1, 3, 0.0, 1.0).is_err());
        assert!(ScanGeometry::new(0.0, 0.0, 3, 0.0, 1.0).is_err());
        assert!(ScanGeometry::new(0.0, 0.1, 3, -1.0, 1.0).is_err());
        assert!(ScanGeometry::new(0.0, 0.1, 3, 1.0, 1.0).is_err());
        assert!(ScanGeometry::new(0.0, 0.1, 3, 0.0, f64::INFINITY).is_err());
        let e = ScanGeometry::new(0.0, 0.1, 0, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("ray_count"), "{e}");
        // More than a full turn: 1e6 rad between rays, or 361 rays a degree apart.
        let e = ScanGeometry::new(0.0, 1e6, 2, 0.0, 1.0).unwrap_err();
        assert!(e.to_string().contains("increment_rad"), "{e}");
        assert!(ScanGeometry::new(0.0, 1f64.to_radians(), 362, 0.0, 1.0).is_err());
        // A full turn itself is a scanner's (360 rays a degree apart: 359 deg first to last).
        assert!(ScanGeometry::centred(361, 2.0 * PI, 0.0, 1.0).is_ok());
    }

    #[test]
    fn single_ray_geometry() {
        let g = ScanGeometry::centred(1, 0.0, 0.0, 1.0).unwrap();
        assert_eq!(g.bearing_rad(0), 0.0);
        assert_eq!(g.nearest_index(0.0), Some(0));
    }
}
