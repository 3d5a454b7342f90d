//! Every scan of the four shared real logs reads, with the counts their MANIFEST gives.

use std::path::PathBuf;

use scan_log::{LogOptions, LogReader, LogSource};
use scan_types::{LaserSource, RayStatus};

#[allow(clippy::print_stdout)]
fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/"
    ))
    .join(rel);
    if p.exists() {
        Some(p)
    } else {
        println!("skipping: {} not found (../shared is absent)", p.display());
        None
    }
}

/// Reads a whole log, asserting no record fails; returns the records.
fn read_all(rel: &str) -> Option<Vec<scan_log::LogRecord>> {
    let p = shared(rel)?;
    let recs: Vec<_> = LogReader::open(&p, &LogOptions::default())
        .unwrap()
        .collect::<Result<_, _>>()
        .unwrap();
    Some(recs)
}

#[test]
fn breezyslam_counts_match_the_manifest() {
    for (rel, scans, secs) in [
        ("breezyslam/exp1.dat", 756, 74.6),
        ("breezyslam/exp2.dat", 641, 63.2),
    ] {
        let Some(recs) = read_all(rel) else { return };
        assert_eq!(recs.len(), scans, "{rel}");
        assert!(recs.iter().all(|r| r.scan.len() == 683 && r.pose.is_none()));
        let span = recs.last().unwrap().scan.host_time_s - recs[0].scan.host_time_s;
        assert!((span - secs).abs() < 0.1, "{rel}: {span} s");
    }
}

#[test]
fn carmen_counts_match_the_manifest() {
    for (rel, scans) in [
        ("carmen/intel-corrected.log.gz", 910),
        ("carmen/aces-corrected.log.gz", 440),
    ] {
        let Some(recs) = read_all(rel) else { return };
        assert_eq!(recs.len(), scans, "{rel}");
        assert!(
            recs.iter()
                .all(|r| r.scan.len() == 180 && r.pose.is_some() && r.odom_pose.is_some())
        );
    }
}

#[test]
fn intel_no_return_reads_as_max_range() {
    let Some(recs) = read_all("carmen/intel-corrected.log.gz") else {
        return;
    };
    // First FLASER line of the log, checked by hand: readings 1.09 1.08 ... 1.22 1.23, corrected
    // pose 0.600266 -0.0320327 -0.354665, ipc timestamp 32.9068.
    let r = &recs[0];
    assert_eq!(r.scan.ranges_m[..2], [1.09, 1.08]);
    assert_eq!(r.scan.ranges_m[178..], [1.22, 1.23]);
    let p = r.pose.unwrap();
    assert_eq!(
        (p.x_m, p.y_m, p.theta_rad),
        (0.600266, -0.0320327, -0.354665)
    );
    assert_eq!(r.scan.host_time_s, 32.9068);
    // 81.83 m means no return (MANIFEST): never a hit, reads exactly the maximum range.
    let max_range = recs
        .iter()
        .flat_map(|r| r.scan.status.iter())
        .filter(|s| **s == RayStatus::MaxRange)
        .count();
    assert_eq!(max_range, 4172); // `zcat | awk` count of "81.83" readings
    assert!(
        recs.iter()
            .all(|r| r.scan.ranges_m.iter().all(|&x| x <= 50.0))
    );
}

#[test]
fn exp1_error_codes_on_real_data() {
    let Some(p) = shared("breezyslam/exp1.dat") else {
        return;
    };
    let mut src = LogSource::open(&p, &LogOptions::default()).unwrap();
    let g = *src.geometry();
    let (mut zero, mut codes, mut hits, mut total) = (0usize, 0usize, 0usize, 0usize);
    while let Ok(s) = src.next_scan() {
        for (r, st) in s.ranges_m.iter().zip(&s.status) {
            total += 1;
            match st {
                // Code 0: nothing within range (set A), reads exactly r_max, never a distance.
                RayStatus::MaxRange => {
                    zero += 1;
                    assert_eq!(*r, g.max_range_m);
                }
                // Codes 1..19: invalid, NaN, never an obstacle.
                RayStatus::Error(c) => {
                    codes += 1;
                    assert!((1..20).contains(c), "code {c}");
                    assert!(r.is_nan());
                }
                RayStatus::Hit => {
                    hits += 1;
                    assert!(*r >= 0.02 && *r < g.max_range_m, "{r}");
                }
            }
        }
        // No error ray is ever a hit point.
        assert!(s.robot_hits(&g).all(|(i, _)| s.status[i] == RayStatus::Hit));
    }
    assert_eq!(src.skipped(), 0);
    assert_eq!(total, 756 * 683);
    // MANIFEST: 52.5 % of the readings are 0.
    let share = zero as f64 / total as f64;
    assert!((share - 0.525).abs() < 0.005, "{share}");
    // `awk` over the file: 14 591 readings are codes 1..19 (1, 2, 6, 7, 8, 10, 15).
    assert_eq!(codes, 1320 + 413 + 4256 + 7541 + 263 + 418 + 180);
    assert_eq!(hits, total - zero - codes);
}
