//! The scan CSV form shared by `robot-app scan` (writer) and `robot-app expand` (reader).
//!
//! A first comment line carries the geometry, then a header and one row per ray:
//!
//! ```text
//! # goalseek-scan first_bearing_rad=-2.0943951 increment_rad=0.0061234 ray_count=685 min_range_m=0 max_range_m=4 sensor_time_ms=-
//! index,bearing_rad,range_m,valid
//! 0,-2.094395102,1.234000,1
//! ```
//!
//! `valid` is 1 for a real reading (a hit, or a max-range miss whose range equals
//! `max_range_m`) and 0 for a sensor error (its range is written as `nan`).

use std::io::{BufRead, Write};

use anyhow::{Context, bail};
use scan_types::{RayStatus, Scan, ScanGeometry};

/// Writes one scan as CSV with its geometry line.
pub fn write_scan_csv<W: Write>(
    mut w: W,
    geometry: &ScanGeometry,
    scan: &Scan,
) -> std::io::Result<()> {
    let stamp = scan
        .sensor_time_ms
        .map_or_else(|| "-".to_string(), |t| t.to_string());
    writeln!(
        w,
        "# goalseek-scan first_bearing_rad={} increment_rad={} ray_count={} min_range_m={} max_range_m={} sensor_time_ms={}",
        geometry.first_bearing_rad,
        geometry.increment_rad,
        geometry.ray_count,
        geometry.min_range_m,
        geometry.max_range_m,
        stamp
    )?;
    writeln!(w, "index,bearing_rad,range_m,valid")?;
    for (i, (&r, s)) in scan.ranges_m.iter().zip(&scan.status).enumerate() {
        let valid = u8::from(!matches!(s, RayStatus::Error(_)));
        writeln!(w, "{i},{:.9},{:.6},{valid}", geometry.bearing_rad(i), r)?;
    }
    Ok(())
}

/// Reads a scan written by [`write_scan_csv`]; errors name the source and line.
pub fn read_scan_csv<R: BufRead>(r: R, source: &str) -> anyhow::Result<(ScanGeometry, Scan)> {
    let mut lines = r.lines().enumerate();
    let (_, first) = lines
        .next()
        .with_context(|| format!("{source}: empty file, expected a '# goalseek-scan' line"))?;
    let first = first.with_context(|| format!("{source}:1: unreadable"))?;
    let Some(fields) = first.strip_prefix("# goalseek-scan ") else {
        bail!("{source}:1: expected a '# goalseek-scan ...' geometry line, found {first:?}");
    };
    let get = |key: &str| -> anyhow::Result<String> {
        fields
            .split_whitespace()
            .find_map(|kv| kv.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
            .map(str::to_string)
            .with_context(|| format!("{source}:1: geometry line has no {key}="))
    };
    let num = |key: &str, v: String| -> anyhow::Result<f64> {
        v.parse::<f64>()
            .with_context(|| format!("{source}:1: {key}={v} is not a number"))
    };
    let first_bearing = num("first_bearing_rad", get("first_bearing_rad")?)?;
    let increment = num("increment_rad", get("increment_rad")?)?;
    let count_s = get("ray_count")?;
    let count: usize = count_s
        .parse()
        .with_context(|| format!("{source}:1: ray_count={count_s} is not a whole number"))?;
    let min_r = num("min_range_m", get("min_range_m")?)?;
    let max_r = num("max_range_m", get("max_range_m")?)?;
    let stamp = get("sensor_time_ms")?;
    let geometry = ScanGeometry::new(first_bearing, increment, count, min_r, max_r)
        .with_context(|| format!("{source}:1: bad geometry"))?;

    let mut ranges = Vec::with_capacity(count);
    let mut status = Vec::with_capacity(count);
    for (n, line) in lines {
        let lineno = n + 1;
        let line = line.with_context(|| format!("{source}:{lineno}: unreadable"))?;
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') || line.starts_with("index") {
            continue;
        }
        let cols: Vec<&str> = line.split(',').collect();
        if cols.len() != 4 {
            bail!(
                "{source}:{lineno}: expected 4 columns (index,bearing_rad,range_m,valid), found {}",
                cols.len()
            );
        }
        let index: usize = cols[0].parse().with_context(|| {
            format!(
                "{source}:{lineno}: index {:?} is not a whole number",
                cols[0]
            )
        })?;
        if index != ranges.len() {
            bail!(
                "{source}:{lineno}: expected ray index {}, found {index}",
                ranges.len()
            );
        }
        let range: f64 = cols[2]
            .parse()
            .with_context(|| format!("{source}:{lineno}: range_m {:?} is not a number", cols[2]))?;
        let st = match cols[3] {
            "0" => RayStatus::Error(0),
            "1" if range.is_finite() && range >= max_r => RayStatus::MaxRange,
            "1" if range.is_finite() && range >= 0.0 => RayStatus::Hit,
            "1" => bail!("{source}:{lineno}: valid ray with range {range} out of bounds"),
            other => bail!("{source}:{lineno}: valid must be 0 or 1, found {other:?}"),
        };
        ranges.push(match st {
            RayStatus::Error(_) => f64::NAN,
            RayStatus::MaxRange => max_r,
            RayStatus::Hit => range,
        });
        status.push(st);
    }
    if ranges.len() != count {
        bail!(
            "{source}: geometry says {count} rays, file has {}",
            ranges.len()
        );
    }
    let scan = Scan {
        ranges_m: ranges,
        status,
        intensities: None,
        sensor_time_ms: stamp.parse().ok(),
        host_time_s: 0.0,
    };
    Ok((geometry, scan))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_keeps_status() {
        let g = ScanGeometry::centred(4, 1.0, 0.0, 4.0).unwrap();
        let mut s = Scan::from_ranges(&g, &[1.25, 4.0, f64::NAN, 0.5], 0.0);
        s.sensor_time_ms = Some(6968830);
        let mut buf = Vec::new();
        write_scan_csv(&mut buf, &g, &s).unwrap();
        let (g2, s2) = read_scan_csv(&buf[..], "mem").unwrap();
        assert_eq!(g2.ray_count, 4);
        assert_eq!(s2.status, s.status);
        assert_eq!(s2.ranges_m[0], 1.25);
        assert_eq!(s2.sensor_time_ms, Some(6968830));
    }

    #[test]
    fn errors_name_the_line() {
        let text = "# goalseek-scan first_bearing_rad=0 increment_rad=0.1 ray_count=2 min_range_m=0 max_range_m=4 sensor_time_ms=-\nindex,bearing_rad,range_m,valid\n0,0,1.0,1\n1,0.1,abc,1\n";
        let e = read_scan_csv(text.as_bytes(), "x.csv").unwrap_err();
        assert!(format!("{e:#}").contains("x.csv:4"), "{e:#}");
        let e = read_scan_csv("hello\n".as_bytes(), "y.csv").unwrap_err();
        assert!(format!("{e:#}").contains("y.csv:1"), "{e:#}");
    }
}
