//! The emulator's default ranges: a fixed scan of a small room.

use scan_types::{LaserSource, RayStatus, Scan, ScanGeometry};

/// A fixed `LaserSource`: the default ranges of the emulator.
#[derive(Debug, Clone)]
pub struct FixedSource {
    geometry: ScanGeometry,
    scan: Scan,
}

impl FixedSource {
    /// A fixed scan in `geometry` as seen from a sensor in a 4.5 m x 4.5 m room: walls at
    /// x = 3.0 and x = -1.5, y = 2.5 and y = -2.0 (metres, sensor frame), an open door
    /// (nothing within range) at bearings 60..70 deg, and one error ray (code 7) at -90 deg.
    pub fn room(geometry: ScanGeometry) -> Self {
        let mut ranges = Vec::with_capacity(geometry.ray_count);
        let mut status = Vec::with_capacity(geometry.ray_count);
        for i in 0..geometry.ray_count {
            let b = geometry.bearing_rad(i);
            let (c, s) = (b.cos(), b.sin());
            let mut d = f64::INFINITY;
            if c > 1e-12 {
                d = d.min(3.0 / c);
            }
            if c < -1e-12 {
                d = d.min(-1.5 / c);
            }
            if s > 1e-12 {
                d = d.min(2.5 / s);
            }
            if s < -1e-12 {
                d = d.min(-2.0 / s);
            }
            let deg = b.to_degrees();
            if (60.0..70.0).contains(&deg) || d >= geometry.max_range_m {
                ranges.push(geometry.max_range_m);
                status.push(RayStatus::MaxRange);
            } else if (deg + 90.0).abs() < geometry.increment_rad.to_degrees() / 2.0 {
                ranges.push(f64::NAN);
                status.push(RayStatus::Error(7));
            } else {
                ranges.push(d);
                status.push(RayStatus::Hit);
            }
        }
        let scan = Scan {
            ranges_m: ranges,
            status,
            intensities: None,
            sensor_time_ms: None,
            host_time_s: 0.0,
        };
        FixedSource { geometry, scan }
    }

    /// A source that always returns `scan`.
    pub fn new(geometry: ScanGeometry, scan: Scan) -> Self {
        FixedSource { geometry, scan }
    }
}

impl LaserSource for FixedSource {
    type Error = std::convert::Infallible;
    fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }
    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        Ok(self.scan.clone())
    }
}
