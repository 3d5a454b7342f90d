//! Heading from the scans: the rotation that best aligns the scans before and after a turn,
//! against the commanded rotation, in a hand-made room.

use localiser::{HeadingRule, heading_after_rotation, measure_rotation};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use scan_types::testkit::{Seg, boxed, scan_at};
use scan_types::{RayStatus, Scan, ScanGeometry};

/// An 8 m x 6 m room (x -4..4, y -3..3) with two boxes and a slanted wall piece.
fn room() -> Vec<Seg> {
    let mut w = boxed(-4.0, -3.0, 4.0, 3.0);
    w.extend(boxed(1.0, 0.5, 1.8, 1.2));
    w.extend(boxed(-2.5, -2.0, -1.9, -1.2));
    w.push(((-1.0, 2.0), (0.5, 2.8)));
    w
}

fn inside_free(x: f64, y: f64) -> bool {
    let clear = |x0: f64, y0: f64, x1: f64, y1: f64| {
        x < x0 - 0.3 || x > x1 + 0.3 || y < y0 - 0.3 || y > y1 + 0.3
    };
    x.abs() < 3.6 && y.abs() < 2.6 && clear(1.0, 0.5, 1.8, 1.2) && clear(-2.5, -2.0, -1.9, -1.2)
}

/// Adds N(0, sigma) to hits and turns a fraction of rays into errors.
fn degrade(g: &ScanGeometry, s: &Scan, sigma: f64, p_err: f64, rng: &mut ChaCha8Rng) -> Scan {
    let n = Normal::new(0.0, sigma).unwrap();
    let mut out = s.clone();
    for i in 0..out.len() {
        if rng.random::<f64>() < p_err {
            out.status[i] = RayStatus::Error(0);
            out.ranges_m[i] = f64::NAN;
        } else if out.status[i] == RayStatus::Hit {
            out.ranges_m[i] = (out.ranges_m[i] + n.sample(rng)).clamp(0.0, g.max_range_m - 1e-6);
        }
    }
    out
}

fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

#[test]
fn exact_shifts_are_recovered() {
    let g = ScanGeometry::paper();
    let walls = room();
    let before = scan_at(&g, &walls, 0.3, -0.4, 0.2);
    for rays in [10.0, -7.5, 0.25, 100.3] {
        let alpha = rays * g.increment_rad;
        let after = scan_at(&g, &walls, 0.3, -0.4, 0.2 + alpha);
        // Commanded off by 1 deg: the search still finds the true angle.
        let m = measure_rotation(
            &g,
            &before,
            &after,
            alpha + 1f64.to_radians(),
            5f64.to_radians(),
        )
        .unwrap();
        assert!(
            (m - alpha).abs() < 0.02f64.to_radians(),
            "{rays} rays: measured {} deg, true {} deg",
            m.to_degrees(),
            alpha.to_degrees()
        );
    }
}

#[test]
fn no_confident_match_gives_none() {
    let g = ScanGeometry::paper();
    // Nothing in range at all.
    let empty = scan_at(&g, &[], 0.0, 0.0, 0.0);
    assert!(measure_rotation(&g, &empty, &empty, 0.3, 0.1).is_none());
    // A round room centred on the robot looks the same at every angle.
    let ring: Vec<Seg> = (0..720)
        .map(|k| {
            let (a0, a1) = (
                k as f64 * 0.5f64.to_radians(),
                (k + 1) as f64 * 0.5f64.to_radians(),
            );
            (
                (2.0 * a0.cos(), 2.0 * a0.sin()),
                (2.0 * a1.cos(), 2.0 * a1.sin()),
            )
        })
        .collect();
    let a = scan_at(&g, &ring, 0.0, 0.0, 0.0);
    let b = scan_at(&g, &ring, 0.0, 0.0, 0.4);
    assert!(measure_rotation(&g, &a, &b, 0.4, 0.1).is_none());
    // Garbage input does not panic.
    let short = Scan::from_ranges(&g, &[1.0, 2.0], 0.0);
    assert!(measure_rotation(&g, &short, &a, 0.0, 0.1).is_none());
    assert!(measure_rotation(&g, &a, &b, f64::NAN, 0.1).is_none());
}

#[test]
fn heading_rules() {
    assert!(
        (heading_after_rotation(HeadingRule::Commanded, 0.1, 0.5, Some(0.52)) - 0.6).abs() < 1e-12
    );
    assert!(
        (heading_after_rotation(HeadingRule::ScanMeasured, 0.1, 0.5, Some(0.52)) - 0.62).abs()
            < 1e-12
    );
    // Without a measurement the command is used.
    assert!(
        (heading_after_rotation(HeadingRule::ScanMeasured, 0.1, 0.5, None) - 0.6).abs() < 1e-12
    );
    assert_eq!(HeadingRule::default(), HeadingRule::ScanMeasured);
}

/// Many turns with 1 deg rotation noise and 1 cm range noise: the measured rotation's error
/// against the commanded rotation's error (median and p95, printed).
#[test]
#[allow(clippy::print_stdout)] // the figures are the point of this test
fn measured_rotation_beats_the_command_under_noise() {
    let walls = room();
    let urg = ScanGeometry::new(
        (44.0 - 384.0) * std::f64::consts::TAU / 1024.0,
        std::f64::consts::TAU / 1024.0,
        682,
        0.02,
        5.6,
    )
    .unwrap();
    for (name, g, p_err) in [
        ("paper 4 m", ScanGeometry::paper(), 0.0),
        ("urg-04lx 5.6 m, 2 % error rays", urg, 0.02),
    ] {
        let mut rng = ChaCha8Rng::seed_from_u64(42);
        let rot_noise = Normal::new(0.0, 1f64.to_radians()).unwrap();
        let (mut e_cmd, mut e_meas) = (Vec::new(), Vec::new());
        let mut fallbacks = 0;
        let trials = 200;
        while e_cmd.len() < trials {
            let (x, y) = (rng.random_range(-3.6..3.6), rng.random_range(-2.6..2.6));
            if !inside_free(x, y) {
                continue;
            }
            let theta: f64 = rng.random_range(-3.1..3.1);
            let commanded: f64 = rng.random_range(-100f64.to_radians()..100f64.to_radians());
            let truth = commanded + rot_noise.sample(&mut rng);
            let before = degrade(&g, &scan_at(&g, &walls, x, y, theta), 0.01, p_err, &mut rng);
            let after = degrade(
                &g,
                &scan_at(&g, &walls, x, y, theta + truth),
                0.01,
                p_err,
                &mut rng,
            );
            let m = measure_rotation(&g, &before, &after, commanded, 5f64.to_radians());
            if m.is_none() {
                fallbacks += 1;
            }
            let est = heading_after_rotation(HeadingRule::ScanMeasured, 0.0, commanded, m);
            e_cmd.push((commanded - truth).abs().to_degrees());
            e_meas.push(scan_types::angle_diff_rad(est, truth).abs().to_degrees());
        }
        let (cm, c95) = (quantile(&mut e_cmd, 0.5), quantile(&mut e_cmd, 0.95));
        let (mm, m95) = (quantile(&mut e_meas, 0.5), quantile(&mut e_meas, 0.95));
        println!(
            "{name}: {trials} turns, heading error commanded median {cm:.3} deg p95 {c95:.3} deg; \
             scan-measured median {mm:.3} deg p95 {m95:.3} deg; {fallbacks} fell back to the command"
        );
        assert!(mm < 0.1, "{name}: median {mm}");
        assert!(m95 < 0.3, "{name}: p95 {m95}");
        assert!(m95 * 4.0 < c95, "{name}: p95 {m95} vs commanded {c95}");
        assert!(fallbacks * 20 <= trials, "{name}: {fallbacks} fallbacks");
    }
}

#[test]
fn half_turns_wrap_around() {
    // 240 deg of view: a turn near 180 deg leaves about 60 deg of overlap, still enough.
    let g = ScanGeometry::paper();
    let walls = room();
    let before = scan_at(&g, &walls, 0.3, -0.4, 0.2);
    for (commanded_deg, truth_deg) in [(175.0f64, 176.0f64), (179.5, 180.7), (-178.0, -179.0)] {
        let truth = truth_deg.to_radians();
        let after = scan_at(&g, &walls, 0.3, -0.4, 0.2 + truth);
        let m = measure_rotation(
            &g,
            &before,
            &after,
            commanded_deg.to_radians(),
            5f64.to_radians(),
        )
        .unwrap_or_else(|| panic!("{commanded_deg} deg: no match"));
        let err = scan_types::angle_diff_rad(m, truth).abs().to_degrees();
        assert!(err < 0.05, "{commanded_deg} deg: error {err} deg");
    }
}
