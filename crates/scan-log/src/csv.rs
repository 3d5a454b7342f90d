//! The scan CSV form shared by `robot-app scan` (writer) and `robot-app expand` (reader), and
//! the JSON form of `robot-app scan --format json`.
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

use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};

use crate::{LogError, LogRecord};

/// The cause kept by [`LogError::Csv`].
type Cause = Option<Box<dyn std::error::Error + Send + Sync>>;

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

/// Scan number `index` as JSON: geometry, time stamps, ranges (null for invalid rays) and
/// statuses (`hit`, `max_range`, `error:CODE`).
pub fn scan_json(index: usize, g: &ScanGeometry, scan: &Scan) -> serde_json::Value {
    let ranges: Vec<Option<f64>> = scan
        .ranges_m
        .iter()
        .map(|&r| r.is_finite().then_some(r))
        .collect();
    let status: Vec<String> = scan
        .status
        .iter()
        .map(|s| match s {
            RayStatus::Hit => "hit".to_string(),
            RayStatus::MaxRange => "max_range".to_string(),
            RayStatus::Error(c) => format!("error:{c}"),
        })
        .collect();
    serde_json::json!({
        "scan": index,
        "sensor_time_ms": scan.sensor_time_ms,
        "host_time_s": scan.host_time_s,
        "first_bearing_rad": g.first_bearing_rad,
        "increment_rad": g.increment_rad,
        "ray_count": g.ray_count,
        "min_range_m": g.min_range_m,
        "max_range_m": g.max_range_m,
        "ranges_m": ranges,
        "status": status,
        "intensities": scan.intensities,
    })
}

/// Record number `index` of a log as JSON: [`scan_json`] of its scan (geometry `g`) with its
/// `line` and its `pose` and `true_pose` (`[x_m, y_m, theta_rad]`, null where the log has none).
pub fn record_json(index: usize, g: &ScanGeometry, record: &LogRecord) -> serde_json::Value {
    let mut v = scan_json(index, g, &record.scan);
    let pose = |p: Option<Pose2>| p.map(|p| serde_json::json!([p.x_m, p.y_m, p.theta_rad]));
    v["pose"] = pose(record.pose).into();
    v["true_pose"] = pose(record.true_pose).into();
    v["line"] = record.line.into();
    v
}

/// Reads a scan written by [`write_scan_csv`]; errors name the file and line.
pub fn read_scan_csv<R: BufRead>(r: R, file: &str) -> Result<(ScanGeometry, Scan), LogError> {
    let mut lines = r.lines().enumerate();
    let Some((_, first)) = lines.next() else {
        return Err(LogError::CsvEmpty {
            file: file.to_string(),
        });
    };
    let first = first.map_err(|e| csv_error(file, 1, "unreadable".into(), Some(e.into())))?;
    if !first.starts_with('#') {
        return read_plain_csv(std::iter::once((0, Ok(first))).chain(lines), file);
    }
    let (geometry, stamp) = parse_geometry_line(&first, file)?;
    let count = geometry.ray_count;

    let mut ranges = Vec::with_capacity(count);
    let mut status = Vec::with_capacity(count);
    for row in data_rows(lines, file) {
        let (lineno, line) = row?;
        let (range, st) = parse_row(&line, ranges.len(), geometry.max_range_m, file, lineno)?;
        ranges.push(range);
        status.push(st);
    }
    if ranges.len() != count {
        return Err(LogError::CsvRayCount {
            file: file.to_string(),
            expected: count,
            got: ranges.len(),
        });
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

/// The data rows of a scan CSV as (1-based line number, trimmed text): blank, comment and
/// header lines skipped.
fn data_rows<'a>(
    lines: impl Iterator<Item = (usize, std::io::Result<String>)> + 'a,
    file: &'a str,
) -> impl Iterator<Item = Result<(usize, String), LogError>> + 'a {
    lines.filter_map(move |(n, line)| {
        let lineno = n + 1;
        match line {
            Err(e) => Some(Err(csv_error(
                file,
                lineno,
                "unreadable".into(),
                Some(e.into()),
            ))),
            Ok(l) => {
                let t = l.trim();
                let skip = t.is_empty() || t.starts_with('#') || t.starts_with("index");
                (!skip).then(|| Ok((lineno, t.to_string())))
            }
        }
    })
}

/// Largest departure of a bearing from an even spacing, as a share of the increment.
const SPACING_TOLERANCE: f64 = 0.01;

/// One row `index,bearing_rad,range_m[,valid]` of a plain scan CSV: bearing, range, valid.
fn plain_row(
    line: &str,
    expected_index: usize,
    file: &str,
    lineno: usize,
) -> Result<(f64, f64, bool), LogError> {
    let err = |message: String| csv_error(file, lineno, message, None);
    let cols: Vec<&str> = line.split(',').map(str::trim).collect();
    if !(3..=4).contains(&cols.len()) {
        return Err(err(format!(
            "expected index,bearing_rad,range_m[,valid], found {} columns",
            cols.len()
        )));
    }
    if cols[0].parse::<usize>().ok() != Some(expected_index) {
        return Err(err(format!(
            "expected ray index {}, found {:?}",
            expected_index, cols[0]
        )));
    }
    let bearing = cols[1]
        .parse::<f64>()
        .ok()
        .filter(|b| b.is_finite())
        .ok_or_else(|| err(format!("bearing_rad {:?} is not a number", cols[1])))?;
    let range = cols[2].parse::<f64>().unwrap_or(f64::NAN);
    let valid = match cols.get(3) {
        None | Some(&"1") => range.is_finite() && range >= 0.0,
        Some(&"0") => false,
        Some(other) => return Err(err(format!("valid must be 0 or 1, found {other:?}"))),
    };
    Ok((bearing, range, valid))
}

/// A scan CSV without goalseek's geometry line (a user's own scan): rows
/// `index,bearing_rad,range_m[,valid]` after an optional header; the geometry comes from the
/// bearings, which must be evenly spaced. The range limits are 0 and the longest range; a
/// `valid` of 0, or a range that is empty, not a number or negative, is an error ray.
fn read_plain_csv(
    lines: impl Iterator<Item = (usize, std::io::Result<String>)>,
    file: &str,
) -> Result<(ScanGeometry, Scan), LogError> {
    let mut rows: Vec<(f64, f64, bool, usize)> = Vec::new();
    for row in data_rows(lines, file) {
        let (lineno, line) = row?;
        let (bearing, range, valid) = plain_row(&line, rows.len(), file, lineno)?;
        rows.push((bearing, range, valid, lineno));
    }
    if rows.len() < 2 {
        return Err(LogError::CsvEmpty {
            file: file.to_string(),
        });
    }
    let n = rows.len();
    let uneven = |i: usize, b: f64, lineno: usize| {
        csv_error(
            file,
            lineno,
            format!(
                "bearing of ray {i} ({b} rad) is not evenly spaced: the geometry cannot be read from the bearings"
            ),
            None,
        )
    };
    let first = rows[0].0;
    let increment = (rows[n - 1].0 - first) / (n - 1) as f64;
    let even = rows.iter().enumerate().all(|(i, &(b, ..))| {
        let off = (b - (first + i as f64 * increment)).abs();
        increment != 0.0 && off <= SPACING_TOLERANCE * increment.abs()
    });
    if !even {
        // Name the row where the bearings leave their median step (rounding counts twice in
        // a step), else the first; an odd last row would make every other row look off.
        let mut steps: Vec<f64> = rows.windows(2).map(|w| w[1].0 - w[0].0).collect();
        steps.sort_by(f64::total_cmp);
        let step = steps[steps.len() / 2];
        let i = rows
            .windows(2)
            .position(|w| (w[1].0 - w[0].0 - step).abs() > 2.0 * SPACING_TOLERANCE * step.abs())
            .map_or(0, |i| i + 1);
        return Err(uneven(i, rows[i].0, rows[i].3));
    }
    let max_r = rows
        .iter()
        .filter(|r| r.2)
        .map(|r| r.1)
        .fold(0.0f64, f64::max)
        .max(f64::MIN_POSITIVE);
    let geometry = ScanGeometry::new(first, increment, n, 0.0, max_r)
        .map_err(|e| csv_error(file, rows[0].3, "bad geometry".into(), Some(e.into())))?;
    let (ranges_m, status) = rows
        .iter()
        .map(|&(_, r, valid, _)| {
            if valid {
                (r, RayStatus::Hit)
            } else {
                (f64::NAN, RayStatus::Error(0))
            }
        })
        .unzip();
    let scan = Scan {
        ranges_m,
        status,
        intensities: None,
        sensor_time_ms: None,
        host_time_s: 0.0,
    };
    Ok((geometry, scan))
}

fn csv_error(file: &str, line: usize, message: String, source: Cause) -> LogError {
    LogError::Csv {
        file: file.to_string(),
        line,
        message,
        source,
    }
}

/// The geometry and the `sensor_time_ms` text of the first line.
fn parse_geometry_line(first: &str, file: &str) -> Result<(ScanGeometry, String), LogError> {
    let err = |message: String, source: Cause| csv_error(file, 1, message, source);
    let Some(fields) = first.strip_prefix("# goalseek-scan ") else {
        return Err(err(
            format!("expected a '# goalseek-scan ...' geometry line, found {first:?}"),
            None,
        ));
    };
    let get = |key: &str| -> Result<String, LogError> {
        fields
            .split_whitespace()
            .find_map(|kv| kv.strip_prefix(key).and_then(|v| v.strip_prefix('=')))
            .map(str::to_string)
            .ok_or_else(|| err(format!("geometry line has no {key}="), None))
    };
    let num = |key: &str, v: String| -> Result<f64, LogError> {
        v.parse::<f64>()
            .map_err(|e| err(format!("{key}={v} is not a number"), Some(e.into())))
    };
    let first_bearing = num("first_bearing_rad", get("first_bearing_rad")?)?;
    let increment = num("increment_rad", get("increment_rad")?)?;
    let count_s = get("ray_count")?;
    let count: usize = count_s.parse().map_err(|e: std::num::ParseIntError| {
        err(
            format!("ray_count={count_s} is not a whole number"),
            Some(e.into()),
        )
    })?;
    let min_r = num("min_range_m", get("min_range_m")?)?;
    let max_r = num("max_range_m", get("max_range_m")?)?;
    let stamp = get("sensor_time_ms")?;
    let geometry = ScanGeometry::new(first_bearing, increment, count, min_r, max_r)
        .map_err(|e| err("bad geometry".into(), Some(e.into())))?;
    Ok((geometry, stamp))
}

/// One ray row `index,bearing_rad,range_m,valid`: the range (NaN for an error) and status.
fn parse_row(
    line: &str,
    expected_index: usize,
    max_r: f64,
    file: &str,
    lineno: usize,
) -> Result<(f64, RayStatus), LogError> {
    let err = |message: String, source: Cause| csv_error(file, lineno, message, source);
    let cols: Vec<&str> = line.split(',').collect();
    if cols.len() != 4 {
        return Err(err(
            format!(
                "expected 4 columns (index,bearing_rad,range_m,valid), found {}",
                cols.len()
            ),
            None,
        ));
    }
    let index: usize = cols[0].parse().map_err(|e: std::num::ParseIntError| {
        err(
            format!("index {:?} is not a whole number", cols[0]),
            Some(e.into()),
        )
    })?;
    if index != expected_index {
        return Err(err(
            format!("expected ray index {expected_index}, found {index}"),
            None,
        ));
    }
    let range: f64 = cols[2].parse().map_err(|e: std::num::ParseFloatError| {
        err(
            format!("range_m {:?} is not a number", cols[2]),
            Some(e.into()),
        )
    })?;
    let st = match cols[3] {
        "0" => RayStatus::Error(0),
        "1" if range.is_finite() && range >= max_r => RayStatus::MaxRange,
        "1" if range.is_finite() && range >= 0.0 => RayStatus::Hit,
        "1" => {
            return Err(err(
                format!("valid ray with range {range} out of bounds"),
                None,
            ));
        }
        other => {
            return Err(err(format!("valid must be 0 or 1, found {other:?}"), None));
        }
    };
    let range = match st {
        RayStatus::Error(_) => f64::NAN,
        RayStatus::MaxRange => max_r,
        RayStatus::Hit => range,
    };
    Ok((range, st))
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
        assert!(
            matches!(
                &e,
                LogError::Csv {
                    line: 4,
                    source: Some(_),
                    ..
                }
            ),
            "{e:?}"
        );
        let e = read_scan_csv("hello\n".as_bytes(), "y.csv").unwrap_err();
        assert!(format!("{e:#}").contains("y.csv:1"), "{e:#}");
        let e = read_scan_csv("".as_bytes(), "z.csv").unwrap_err();
        assert!(matches!(e, LogError::CsvEmpty { .. }), "{e:?}");
    }

    #[test]
    fn a_plain_csv_gives_its_geometry_from_the_bearings() {
        // Five rays from -0.2 to 0.2 rad, 0.1 rad apart; ray 3 without a return.
        let text = "index,bearing_rad,range_m,valid\n0,-0.2,1.0,1\n1,-0.1,1.5,1\n2,0.0,2.0,1\n3,0.1,0,0\n4,0.2,2.5,1\n";
        let (g, s) = read_scan_csv(text.as_bytes(), "mine.csv").unwrap();
        assert_eq!(g.ray_count, 5);
        assert!((g.first_bearing_rad - -0.2).abs() < 1e-12);
        assert!((g.increment_rad - 0.1).abs() < 1e-12);
        assert_eq!(g.max_range_m, 2.5);
        assert_eq!(s.status[3], RayStatus::Error(0));
        assert_eq!(s.ranges_m[4], 2.5);
        // Three columns, no header, "nan" for no return.
        let (g3, s3) = read_scan_csv("0,1.0,3\n1,1.5,nan\n2,2.0,4\n".as_bytes(), "x").unwrap();
        assert!((g3.increment_rad - 0.5).abs() < 1e-12);
        assert_eq!(s3.status[1], RayStatus::Error(0));
        // Uneven bearings cannot give a geometry: the error names the row's line.
        let e = read_scan_csv("0,0.0,1\n1,0.1,1\n2,0.5,1\n".as_bytes(), "bad.csv").unwrap_err();
        assert!(
            e.to_string().contains("bad.csv") && e.to_string().contains("evenly"),
            "{e}"
        );
        // Nine rays 0.1 rad apart and a tenth 0.15 rad on: the tenth row (line 10) is named.
        let mut text = String::new();
        for i in 0..9 {
            text += &format!("{i},{},1\n", 0.1 * i as f64);
        }
        text += "9,0.95,1\n";
        let e = read_scan_csv(text.as_bytes(), "last.csv").unwrap_err();
        assert!(
            e.to_string().contains("last.csv:10") && e.to_string().contains("ray 9"),
            "{e}"
        );
    }
}
