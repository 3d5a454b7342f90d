//! BreezySLAM `.dat` logs of a URG-04LX: one scan a line.
//!
//! A line holds a timestamp in microseconds, an unused field, the left and right wheel
//! ticks, 20 further fields, then the ranges in millimetres. Range values below 20 mm are
//! URG-04LX error codes, not distances: code 0 ("no return") is read as
//! [`RayStatus::MaxRange`] (nothing within range), every other code as
//! [`RayStatus::Error`].

use scan_types::{RayStatus, Scan, ScanGeometry};

use crate::LogRecord;

/// Fields before the ranges on a BreezySLAM line.
pub const BREEZY_HEADER_FIELDS: usize = 24;

/// Rays in a BreezySLAM URG-04LX scan.
pub const BREEZY_RAY_COUNT: usize = 683;

/// Smallest URG-04LX distance; smaller values are error codes, millimetres.
pub const URG_DMIN_MM: u32 = 20;

/// The geometry of BreezySLAM's URG-04LX logs: 683 rays one SCIP step (360/1024 deg) apart,
/// the first at step 44 (-119.53 deg), so ray 340 (step 384) points straight ahead; 0.02 m
/// to 5.6 m (the sensor's DMIN/DMAX).
///
/// ```
/// let g = scan_log::breezy_geometry();
/// assert_eq!(g.ray_count, 683);
/// assert!(g.bearing_rad(340).abs() < 1e-12);
/// ```
pub fn breezy_geometry() -> ScanGeometry {
    let step = std::f64::consts::TAU / 1024.0;
    ScanGeometry::new((44.0 - 384.0) * step, step, BREEZY_RAY_COUNT, 0.02, 5.6)
        .expect("constant geometry is valid")
}

/// Parses one BreezySLAM line; `Ok(None)` for a blank line.
pub(crate) fn parse_line(
    line: &str,
    line_no: usize,
    geometry: &ScanGeometry,
) -> Result<Option<LogRecord>, String> {
    let toks: Vec<&str> = line.split_ascii_whitespace().collect();
    if toks.is_empty() {
        return Ok(None);
    }
    let n = geometry.ray_count;
    if toks.len() != BREEZY_HEADER_FIELDS + n {
        return Err(format!(
            "{} fields, expected {} ({BREEZY_HEADER_FIELDS} header fields + {n} ranges)",
            toks.len(),
            BREEZY_HEADER_FIELDS + n
        ));
    }
    let int = |i: usize, what: &str| -> Result<i64, String> {
        toks[i].parse::<i64>().map_err(|_| {
            format!(
                "field {} ({what}) {:?} is not a whole number",
                i + 1,
                toks[i]
            )
        })
    };
    let stamp_us = int(0, "timestamp")?;
    let ticks = [int(2, "left wheel ticks")?, int(3, "right wheel ticks")?];
    let mut ranges_m = Vec::with_capacity(n);
    let mut status = Vec::with_capacity(n);
    for (i, t) in toks[BREEZY_HEADER_FIELDS..].iter().enumerate() {
        let mm: u32 = t
            .parse()
            .map_err(|_| format!("range {i} {t:?} is not a whole number of millimetres"))?;
        let (r, s) = classify_mm(geometry, mm);
        ranges_m.push(r);
        status.push(s);
    }
    let scan = Scan {
        ranges_m,
        status,
        intensities: None,
        sensor_time_ms: None,
        host_time_s: stamp_us as f64 * 1e-6,
    };
    let mut rec = LogRecord::new(line_no, *geometry, scan);
    rec.wheel_ticks = Some(ticks);
    Ok(Some(rec))
}

/// Range and status of a URG-04LX reading in millimetres: 0 is "no return" (max range),
/// 1..=19 are error codes, readings at or beyond the maximum range are max-range misses.
///
/// ```
/// use scan_types::RayStatus;
/// let g = scan_log::breezy_geometry();
/// assert_eq!(scan_log::classify_mm(&g, 0), (5.6, RayStatus::MaxRange));
/// assert_eq!(scan_log::classify_mm(&g, 1234), (1.234, RayStatus::Hit));
/// assert_eq!(scan_log::classify_mm(&g, 7).1, RayStatus::Error(7));
/// ```
pub fn classify_mm(geometry: &ScanGeometry, mm: u32) -> (f64, RayStatus) {
    if mm == 0 {
        (geometry.max_range_m, RayStatus::MaxRange)
    } else if mm < URG_DMIN_MM {
        (f64::NAN, RayStatus::Error(mm as u16))
    } else {
        let r = f64::from(mm) / 1000.0;
        if r >= geometry.max_range_m {
            (geometry.max_range_m, RayStatus::MaxRange)
        } else {
            (r, RayStatus::Hit)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn line(ranges: &[u32]) -> String {
        let mut s = String::from("1000000 0 10 -20");
        for _ in 0..20 {
            s.push_str(" 0");
        }
        for r in ranges {
            s.push_str(&format!(" {r}"));
        }
        s
    }

    #[test]
    fn codes_are_not_distances() {
        let g = ScanGeometry::centred(5, 1.0, 0.02, 5.6).unwrap();
        let r = parse_line(&line(&[0, 7, 1500, 19, 6000]), 2, &g)
            .unwrap()
            .unwrap();
        assert_eq!(
            r.scan.status,
            vec![
                RayStatus::MaxRange,
                RayStatus::Error(7),
                RayStatus::Hit,
                RayStatus::Error(19),
                RayStatus::MaxRange
            ]
        );
        assert_eq!(r.scan.ranges_m[0], 5.6);
        assert!(r.scan.ranges_m[1].is_nan());
        assert_eq!(r.scan.ranges_m[2], 1.5);
        assert_eq!(r.scan.host_time_s, 1.0);
        assert_eq!(r.wheel_ticks, Some([10, -20]));
    }

    #[test]
    fn wrong_field_count_or_junk_is_an_error() {
        let g = ScanGeometry::centred(5, 1.0, 0.02, 5.6).unwrap();
        let e = parse_line(&line(&[0, 7, 1500]), 2, &g).unwrap_err();
        assert!(e.contains("27 fields, expected 29"), "{e}");
        let e = parse_line(&line(&[0, 7, 1500, 2, 3]).replace("1500", "15x0"), 2, &g).unwrap_err();
        assert!(e.contains("range 2") && e.contains("15x0"), "{e}");
        assert!(parse_line("", 1, &g).unwrap().is_none());
    }
}
