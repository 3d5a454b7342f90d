//! CARMEN text logs: `FLASER` (old front-laser message) and `ROBOTLASER1` lines.
//!
//! Lines are parsed by counts: the number of readings (and of remissions) says where the
//! fields that follow them start, so logs with other beam counts read the same way.

use std::f64::consts::PI;

use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};

use crate::LogRecord;

/// Default range at or beyond which a CARMEN reading means "no return", metres.
///
/// The Intel log writes 81.83 m for no return, the ACES log 50 m; real readings of both stay
/// below 50 m.
pub const CARMEN_DEFAULT_MAX_RANGE_M: f64 = 50.0;

/// The geometry goalseek assumes for a `FLASER` line of `n` readings.
///
/// `n` = 180k or 180k+1 readings: ray `i` at -90 deg + i * (1/k) deg (the Intel log's 180 beams
/// fit their corrected poses best this way, see `docs/logs.md`); any other `n`: spread evenly
/// over 180 deg.
///
/// ```
/// let g = scan_log::flaser_geometry(180, 50.0).unwrap();
/// assert!((g.bearing_rad(0) + std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// assert!((g.bearing_rad(90)).abs() < 1e-12);
/// assert!((g.increment_rad.to_degrees() - 1.0).abs() < 1e-12);
/// ```
pub fn flaser_geometry(
    n: usize,
    max_range_m: f64,
) -> Result<ScanGeometry, scan_types::ScanTypesError> {
    let k = n / 180;
    if k >= 1 && n - 180 * k <= 1 {
        ScanGeometry::new(-PI / 2.0, PI / (180 * k) as f64, n, 0.0, max_range_m)
    } else {
        ScanGeometry::centred(n, PI, 0.0, max_range_m)
    }
}

/// Parses one CARMEN line. `Ok(None)` for lines that are not laser scans (ODOM, PARAM,
/// comments, blank lines, ...). Errors say what is wrong, without the file and line.
pub(crate) fn parse_line(
    line: &str,
    line_no: usize,
    geometry: Option<&ScanGeometry>,
    max_range_m: f64,
) -> Result<Option<LogRecord>, String> {
    let mut it = line.split_ascii_whitespace();
    let Some(kind) = it.next() else {
        return Ok(None);
    };
    match kind {
        "FLASER" => {
            let toks: Vec<&str> = it.collect();
            flaser(&toks, line_no, geometry, max_range_m).map(Some)
        }
        "ROBOTLASER1" => {
            let toks: Vec<&str> = it.collect();
            robotlaser1(&toks, line_no, geometry).map(Some)
        }
        _ => Ok(None),
    }
}

fn num(tok: &str, what: &str) -> Result<f64, String> {
    tok.parse::<f64>()
        .map_err(|_| format!("{what} {tok:?} is not a number"))
}

fn count(tok: Option<&&str>, what: &str) -> Result<usize, String> {
    let tok = tok.ok_or_else(|| format!("line ends before {what}"))?;
    tok.parse::<usize>()
        .map_err(|_| format!("{what} {tok:?} is not a whole number"))
}

fn pose(t: &[&str], what: &str) -> Result<Pose2, String> {
    Ok(Pose2::new(
        num(t[0], what)?,
        num(t[1], what)?,
        num(t[2], what)?,
    ))
}

/// Builds the scan: readings at or beyond the maximum range are "no return", negative or
/// non-finite readings are errors.
fn scan_of(toks: &[&str], geometry: &ScanGeometry, host_time_s: f64) -> Result<Scan, String> {
    let mut ranges_m = Vec::with_capacity(toks.len());
    let mut status = Vec::with_capacity(toks.len());
    for (i, t) in toks.iter().enumerate() {
        let r: f64 = t
            .parse()
            .map_err(|_| format!("reading {i} {t:?} is not a number"))?;
        if r.is_nan() || r < 0.0 {
            ranges_m.push(f64::NAN);
            status.push(RayStatus::Error(0));
        } else if r >= geometry.max_range_m {
            ranges_m.push(geometry.max_range_m);
            status.push(RayStatus::MaxRange);
        } else {
            ranges_m.push(r);
            status.push(RayStatus::Hit);
        }
    }
    Ok(Scan {
        ranges_m,
        status,
        intensities: None,
        sensor_time_ms: None,
        host_time_s,
    })
}

fn check_count(geometry: &ScanGeometry, n: usize) -> Result<(), String> {
    if geometry.ray_count == n {
        Ok(())
    } else {
        Err(format!(
            "{n} readings, but the geometry in use has {} rays",
            geometry.ray_count
        ))
    }
}

/// `FLASER n r1..rn x y theta odom_x odom_y odom_theta ipc_timestamp hostname logger_timestamp`
/// or, without poses, `FLASER n r1..rn ipc_timestamp hostname logger_timestamp`.
fn flaser(
    toks: &[&str],
    line_no: usize,
    geometry: Option<&ScanGeometry>,
    max_range_m: f64,
) -> Result<LogRecord, String> {
    let n = count(toks.first(), "the reading count")?;
    if n == 0 {
        return Err("FLASER with 0 readings".into());
    }
    if toks.len() < 1 + n {
        return Err(format!(
            "truncated FLASER: {n} readings announced, {} fields follow",
            toks.len() - 1
        ));
    }
    let rest = &toks[1 + n..];
    let (pose_toks, ts) = match rest.len() {
        9 => (Some(&rest[..6]), rest[6]),
        3 => (None, rest[0]),
        k => {
            return Err(format!(
                "FLASER with {n} readings has {k} fields after them, expected 9 (poses, timestamps, host) or 3"
            ));
        }
    };
    let g = match geometry {
        Some(g) => {
            check_count(g, n)?;
            *g
        }
        None => flaser_geometry(n, max_range_m).map_err(|e| e.to_string())?,
    };
    let host_time_s = num(ts, "ipc_timestamp")?;
    let scan = scan_of(&toks[1..1 + n], &g, host_time_s)?;
    let mut rec = LogRecord::new(line_no, g, scan);
    if let Some(p) = pose_toks {
        rec.pose = Some(pose(&p[..3], "pose")?);
        rec.odom_pose = Some(pose(&p[3..], "odometry pose")?);
    }
    Ok(rec)
}

/// Fields after the readings (and remissions) of a `ROBOTLASER1` line: laser pose (3), robot
/// pose (3), tv, rv, forward and side safety distances, turn axis (5), timestamp, host,
/// logger timestamp (3).
const RL1_TAIL: usize = 14;

/// `ROBOTLASER1 laser_type start_angle fov resolution max_range accuracy remission_mode n
/// r1..rn [m rem1..remm] laser_x laser_y laser_theta robot_x robot_y robot_theta tv rv
/// forward_safety side_safety turn_axis timestamp host logger_timestamp`. Older logs have no
/// remission block; newer ones always write the count `m` (often 0).
fn robotlaser1(
    toks: &[&str],
    line_no: usize,
    geometry: Option<&ScanGeometry>,
) -> Result<LogRecord, String> {
    if toks.len() < 8 {
        return Err(format!(
            "truncated ROBOTLASER1: {} header fields, expected 8",
            toks.len()
        ));
    }
    let start = num(toks[1], "start_angle")?;
    let resolution = num(toks[3], "angular_resolution")?;
    let max_range = num(toks[4], "maximum_range")?;
    let n = count(toks.get(7), "the reading count")?;
    if toks.len() < 8 + n {
        return Err(format!(
            "truncated ROBOTLASER1: {n} readings announced, {} fields follow",
            toks.len() - 8
        ));
    }
    let readings = &toks[8..8 + n];
    let rest = &toks[8 + n..];
    let (remissions, tail) = if rest.len() == RL1_TAIL {
        (None, rest)
    } else {
        let m = count(rest.first(), "the remission count")?;
        if rest.len() != 1 + m + RL1_TAIL {
            return Err(format!(
                "ROBOTLASER1 with {n} readings and {m} remissions has {} fields after the remissions, expected {RL1_TAIL}",
                rest.len().saturating_sub(1 + m)
            ));
        }
        (Some(&rest[1..1 + m]), &rest[1 + m..])
    };
    let g = match geometry {
        Some(g) => {
            check_count(g, n)?;
            *g
        }
        None => {
            ScanGeometry::new(start, resolution, n, 0.0, max_range).map_err(|e| e.to_string())?
        }
    };
    let host_time_s = num(tail[11], "timestamp")?;
    let mut scan = scan_of(readings, &g, host_time_s)?;
    if let Some(rem) = remissions.filter(|r| r.len() == n) {
        let mut v = Vec::with_capacity(n);
        for t in rem {
            v.push(num(t, "remission")? as f32);
        }
        scan.intensities = Some(v);
    }
    let mut rec = LogRecord::new(line_no, g, scan);
    rec.pose = Some(pose(&tail[..3], "laser pose")?);
    // The robot pose (tail[3..6]) differs from the laser pose only by the mounting offset.
    pose(&tail[3..6], "robot pose")?;
    Ok(rec)
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;

    fn flaser_line(n: usize, tail: &str) -> String {
        let ranges: Vec<String> = (0..n)
            .map(|i| format!("{}", 1.0 + i as f64 * 0.01))
            .collect();
        format!("FLASER {n} {} {tail}", ranges.join(" "))
    }

    #[test]
    fn flaser_with_poses() {
        let line = flaser_line(180, "1.5 -2.0 0.25 1.4 -2.1 0.2 32.9 host 33.0");
        let r = parse_line(&line, 7, None, 50.0).unwrap().unwrap();
        assert_eq!(r.line, 7);
        assert_eq!(r.scan.len(), 180);
        assert_eq!(r.scan.ranges_m[0], 1.0);
        assert_eq!(r.scan.ranges_m[179], 1.0 + 179.0 * 0.01);
        assert_eq!(r.pose, Some(Pose2::new(1.5, -2.0, 0.25)));
        assert_eq!(r.odom_pose, Some(Pose2::new(1.4, -2.1, 0.2)));
        assert_eq!(r.scan.host_time_s, 32.9);
        // Beam 90 points straight ahead, beam 0 to the right.
        assert_abs_diff_eq!(r.geometry.bearing_rad(90), 0.0, epsilon = 1e-12);
        assert_abs_diff_eq!(r.geometry.bearing_rad(0), -PI / 2.0, epsilon = 1e-12);
    }

    #[test]
    fn flaser_without_poses_and_no_return() {
        let line = "FLASER 3 1.0 81.83 -1 12.5 host 12.6";
        let r = parse_line(line, 1, None, 50.0).unwrap().unwrap();
        assert_eq!(r.pose, None);
        assert_eq!(
            r.scan.status,
            vec![RayStatus::Hit, RayStatus::MaxRange, RayStatus::Error(0)]
        );
        assert_eq!(r.scan.ranges_m[1], 50.0);
        assert!(r.scan.ranges_m[2].is_nan());
        // 3 readings spread over 180 deg.
        assert_abs_diff_eq!(r.geometry.bearing_rad(2), PI / 2.0, epsilon = 1e-12);
    }

    #[test]
    fn flaser_errors_say_what() {
        let e = parse_line("FLASER 180 1 2 3", 1, None, 50.0).unwrap_err();
        assert!(e.contains("truncated") && e.contains("180"), "{e}");
        let e = parse_line("FLASER 2 1 2 0 0 0 0 0", 1, None, 50.0).unwrap_err();
        assert!(e.contains("5 fields"), "{e}");
        let e = parse_line("FLASER 2 1 x 1.0 host 2.0", 1, None, 50.0).unwrap_err();
        assert!(e.contains("reading 1") && e.contains("\"x\""), "{e}");
        let e = parse_line("FLASER many", 1, None, 50.0).unwrap_err();
        assert!(e.contains("whole number"), "{e}");
        assert!(
            parse_line("ODOM 0 0 0 0 0 0 0.1 h 0.1", 1, None, 50.0)
                .unwrap()
                .is_none()
        );
        assert!(parse_line("   ", 1, None, 50.0).unwrap().is_none());
    }

    #[test]
    fn robotlaser1_both_variants() {
        let head = "ROBOTLASER1 0 -1.5 3.0 0.75 81.9 0.01 0 5 1 2 3 4 81.9";
        let tail = "1.0 2.0 0.5 0.9 2.0 0.5 0.1 0.0 0.5 0.3 0.0 100.25 host 100.5";
        // Newer variant: remission count (here 5 values) before the poses.
        let with = format!("{head} 5 10 20 30 40 50 {tail}");
        // Older variant: no remission block at all.
        let without = format!("{head} {tail}");
        // Newer variant with a zero remission count.
        let zero = format!("{head} 0 {tail}");
        for (line, intens) in [(&with, true), (&without, false), (&zero, false)] {
            let r = parse_line(line, 3, None, 50.0).unwrap().unwrap();
            assert_eq!(r.scan.len(), 5);
            assert_eq!(r.scan.ranges_m[..4], [1.0, 2.0, 3.0, 4.0]);
            assert_eq!(r.scan.status[4], RayStatus::MaxRange);
            assert_eq!(r.pose, Some(Pose2::new(1.0, 2.0, 0.5)));
            assert_eq!(r.scan.host_time_s, 100.25);
            assert_eq!(r.geometry.first_bearing_rad, -1.5);
            assert_eq!(r.geometry.increment_rad, 0.75);
            assert_eq!(r.geometry.max_range_m, 81.9);
            assert_eq!(r.scan.intensities.is_some(), intens);
        }
        let r = parse_line(&with, 3, None, 50.0).unwrap().unwrap();
        assert_eq!(
            r.scan.intensities.unwrap(),
            vec![10.0, 20.0, 30.0, 40.0, 50.0]
        );
        // A line cut inside the tail.
        let cut = &with[..with.len() - 12];
        let e = parse_line(cut, 3, None, 50.0).unwrap_err();
        assert!(e.contains("remission"), "{e}");
    }

    #[test]
    fn geometry_override_must_match_count() {
        let g = ScanGeometry::centred(4, PI, 0.0, 10.0).unwrap();
        let e = parse_line("FLASER 3 1 2 3 1.0 h 1.0", 1, Some(&g), 50.0).unwrap_err();
        assert!(e.contains("4 rays"), "{e}");
    }
}
