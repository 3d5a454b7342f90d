//! One laser scan: ranges with per-ray status, optional intensities and time stamps.

use crate::{Pose2, RobotPoint, ScanGeometry, ScanTypesError, WorldPoint};

/// What one ray of a scan reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum RayStatus {
    /// The ray hit something at its range: a real distance.
    Hit,
    /// Nothing within range (the paper's set A); the range reads exactly the maximum range.
    MaxRange,
    /// The sensor reported an error code instead of a distance; the range is NaN.
    Error(u16),
}

/// One scan in metres, with its geometry kept apart (see [`ScanGeometry`]).
///
/// Invariant (checked by [`Scan::validate`]): `ranges_m` and `status` have one entry per
/// ray; a `MaxRange` ray reads exactly `max_range_m`; an `Error` ray reads NaN.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Range of each ray, metres.
    pub ranges_m: Vec<f64>,
    /// Status of each ray.
    pub status: Vec<RayStatus>,
    /// Intensity of each ray, where the sensor reports it (sensor units).
    pub intensities: Option<Vec<f32>>,
    /// Sensor time stamp, milliseconds, unwrapped (monotonic), if the sensor has a clock.
    pub sensor_time_ms: Option<u64>,
    /// Host time of the scan, seconds since the Unix epoch (or the simulator's clock).
    pub host_time_s: f64,
}

impl Scan {
    /// Builds a scan from plain ranges: finite ranges below `max_range_m` are hits, ranges at or
    /// beyond it (or +inf) are max-range misses, NaN and negative ranges are errors (code 0).
    ///
    /// ```
    /// use scan_types::{RayStatus, Scan, ScanGeometry};
    /// let g = ScanGeometry::centred(3, 1.0, 0.0, 4.0).unwrap();
    /// let s = Scan::from_ranges(&g, &[1.5, 4.0, f64::NAN], 0.0);
    /// assert_eq!(s.status, vec![RayStatus::Hit, RayStatus::MaxRange, RayStatus::Error(0)]);
    /// assert_eq!(s.hit_range_m(0), Some(1.5));
    /// assert_eq!(s.hit_range_m(1), None);
    /// ```
    pub fn from_ranges(geometry: &ScanGeometry, ranges_m: &[f64], host_time_s: f64) -> Scan {
        let mut scan = Scan {
            ranges_m: Vec::with_capacity(ranges_m.len()),
            status: Vec::with_capacity(ranges_m.len()),
            intensities: None,
            sensor_time_ms: None,
            host_time_s,
        };
        for &r in ranges_m {
            let (range, status) = classify(geometry, r);
            scan.ranges_m.push(range);
            scan.status.push(status);
        }
        scan
    }

    /// Number of rays.
    pub fn len(&self) -> usize {
        self.ranges_m.len()
    }

    /// True when the scan has no rays.
    pub fn is_empty(&self) -> bool {
        self.ranges_m.is_empty()
    }

    /// Checks the scan against its geometry.
    pub fn validate(&self, geometry: &ScanGeometry) -> Result<(), ScanTypesError> {
        let check = |what, got| {
            if got == geometry.ray_count {
                Ok(())
            } else {
                Err(ScanTypesError::LengthMismatch {
                    what,
                    got,
                    expected: geometry.ray_count,
                })
            }
        };
        check("ranges", self.ranges_m.len())?;
        check("statuses", self.status.len())?;
        if let Some(i) = &self.intensities {
            check("intensities", i.len())?;
        }
        Ok(())
    }

    /// True when ray `index` hit something (a real distance below the maximum range).
    pub fn is_hit(&self, index: usize) -> bool {
        matches!(self.status.get(index), Some(RayStatus::Hit))
    }

    /// True when ray `index` saw nothing within range (the paper's set A).
    pub fn is_max_range(&self, index: usize) -> bool {
        matches!(self.status.get(index), Some(RayStatus::MaxRange))
    }

    /// The range of ray `index` if it is a hit.
    pub fn hit_range_m(&self, index: usize) -> Option<f64> {
        self.is_hit(index).then(|| self.ranges_m[index])
    }

    /// Hit points of the scan in the robot frame, with their ray index.
    pub fn robot_hits<'a>(
        &'a self,
        geometry: &'a ScanGeometry,
    ) -> impl Iterator<Item = (usize, RobotPoint)> + 'a {
        (0..self.len())
            .filter(|&i| self.is_hit(i))
            .map(|i| (i, geometry.robot_point(i, self.ranges_m[i])))
    }

    /// Hit points of the scan in the world frame, seen from `pose`, with their ray index.
    pub fn world_hits<'a>(
        &'a self,
        geometry: &'a ScanGeometry,
        pose: &'a Pose2,
    ) -> impl Iterator<Item = (usize, WorldPoint)> + 'a {
        self.robot_hits(geometry)
            .map(move |(i, p)| (i, pose.transform_point(p)))
    }
}

/// Status and stored range of a plain range reading.
fn classify(geometry: &ScanGeometry, r: f64) -> (f64, RayStatus) {
    if r.is_nan() || r < 0.0 {
        (f64::NAN, RayStatus::Error(0))
    } else if r >= geometry.max_range_m {
        (geometry.max_range_m, RayStatus::MaxRange)
    } else {
        (r, RayStatus::Hit)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use std::f64::consts::FRAC_PI_2;

    fn geometry() -> ScanGeometry {
        ScanGeometry::centred(3, std::f64::consts::PI, 0.0, 4.0).unwrap()
    }

    #[test]
    fn classification_keeps_errors_apart_from_misses() {
        let s = Scan::from_ranges(&geometry(), &[f64::INFINITY, -1.0, 5.0], 1.0);
        assert_eq!(s.status[0], RayStatus::MaxRange);
        assert_eq!(s.ranges_m[0], 4.0);
        assert_eq!(s.status[1], RayStatus::Error(0));
        assert!(s.ranges_m[1].is_nan());
        assert_eq!(s.status[2], RayStatus::MaxRange);
        assert!(s.is_max_range(2) && !s.is_hit(2));
        assert_eq!(s.host_time_s, 1.0);
    }

    #[test]
    fn validate_checks_lengths() {
        let g = geometry();
        let mut s = Scan::from_ranges(&g, &[1.0, 2.0, 3.0], 0.0);
        assert!(s.validate(&g).is_ok());
        s.intensities = Some(vec![1.0; 2]);
        let e = s.validate(&g).unwrap_err();
        assert_eq!(
            e,
            ScanTypesError::LengthMismatch {
                what: "intensities",
                got: 2,
                expected: 3
            }
        );
        s.intensities = None;
        s.status.pop();
        assert!(s.validate(&g).is_err());
    }

    #[test]
    fn world_hits_at_a_pose() {
        let g = geometry(); // rays at -90, 0, +90 deg
        let s = Scan::from_ranges(&g, &[1.0, 4.0, 2.0], 0.0);
        let pose = Pose2::new(1.0, 1.0, FRAC_PI_2);
        let hits: Vec<_> = s.world_hits(&g, &pose).collect();
        assert_eq!(hits.len(), 2);
        // Right ray (-90 deg) of a robot facing +y points to +x.
        assert_eq!(hits[0].0, 0);
        assert_abs_diff_eq!(hits[0].1.x_m(), 2.0, epsilon = 1e-12);
        assert_abs_diff_eq!(hits[0].1.y_m(), 1.0, epsilon = 1e-12);
        // Left ray (+90 deg) points to -x.
        assert_eq!(hits[1].0, 2);
        assert_abs_diff_eq!(hits[1].1.x_m(), -1.0, epsilon = 1e-12);
        assert_abs_diff_eq!(hits[1].1.y_m(), 1.0, epsilon = 1e-12);
    }
}
