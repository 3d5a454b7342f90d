//! The definition's edge cases, each checked by hand-computable geometry on both kernels.

#![allow(clippy::needless_range_loop)]

mod common;

use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI, TAU};

use common::{both, first_difference, scan_with_hits};
use expansion::{Expander, clearances_reference, is_blocked, ray_disc_entry_m};
use scan_types::{RayStatus, Scan, ScanGeometry};

/// The paper's Fig. 4 on a geometry with a ray exactly at 45 deg: the hit at (2, 2), r = 0.3,
/// blocks exactly the rays within asin(0.3 / sqrt 8) of 45 deg.
#[test]
fn fig4_blocks_exactly_the_rays_through_the_disc() {
    // 240 deg at 0.25 deg: ray 660 is at 45 deg.
    let g = ScanGeometry::new(-120f64.to_radians(), 0.25f64.to_radians(), 961, 0.0, 4.0).unwrap();
    let i45 = 660;
    assert!((g.bearing_rad(i45) - FRAC_PI_4).abs() < 1e-12);
    let scan = scan_with_hits(&g, &[(i45, 8f64.sqrt())]);
    let p = g.robot_point(i45, 8f64.sqrt());
    assert!((p.x_m() - 2.0).abs() < 1e-12 && (p.y_m() - 2.0).abs() < 1e-12);
    let half = (0.3 / 8f64.sqrt()).asin(); // 6.089 deg
    let (slow, fast) = both(&g, &scan, 0.3);
    let mut blocked_count = 0;
    for i in 0..g.ray_count {
        let off = (g.bearing_rad(i) - FRAC_PI_4).abs();
        assert!(
            (off - half).abs() > 1e-6,
            "ray {i} too close to the tangent"
        );
        let through_disc = off < half;
        for (name, c) in [("reference", slow[i]), ("fast", fast[i])] {
            // A 3 m leg: every entry into the disc is nearer than sqrt(8 - 0.09) = 2.81 m.
            assert_eq!(
                is_blocked(c, 3.0),
                through_disc,
                "{name} ray {i} clearance {c}"
            );
            if !through_disc {
                assert_eq!(c, 4.0, "{name} ray {i}");
            }
        }
        blocked_count += usize::from(through_disc);
    }
    // 6.089 deg / 0.25 deg = 24.4: 24 rays each side plus the centre ray.
    assert_eq!(blocked_count, 49);
    // The centre ray enters the disc at sqrt(8) - 0.3.
    assert!((fast[i45] - (8f64.sqrt() - 0.3)).abs() < 1e-12);
}

/// Fig. 4 on the paper's own sensor (685 rays, 0.351 deg): the hit lies on the ray nearest
/// 45 deg (44.91 deg), so the blocked rays are those within asin(0.3 / sqrt 8) of that ray.
#[test]
fn fig4_on_the_paper_sensor() {
    let g = ScanGeometry::paper();
    let i = g.nearest_index(FRAC_PI_4).unwrap();
    assert_eq!(i, 470);
    let scan = scan_with_hits(&g, &[(i, 8f64.sqrt())]);
    let half = (0.3 / 8f64.sqrt()).asin();
    let (slow, fast) = both(&g, &scan, 0.3);
    let blocked: Vec<usize> = (0..g.ray_count).filter(|&k| fast[k] < 4.0).collect();
    let expected: Vec<usize> = (0..g.ray_count)
        .filter(|&k| (g.bearing_rad(k) - g.bearing_rad(i)).abs() < half)
        .collect();
    assert_eq!(blocked, expected);
    // 6.089 deg / 0.3509 deg = 17.35: 17 rays each side plus the centre.
    assert_eq!(expected.len(), 35);
    assert_eq!(first_difference(&slow, &fast, 1e-12), None);
}

/// Each blocked ray enters the Fig. 4 disc where the chord formula says.
#[test]
fn entry_distance_is_the_near_root() {
    let g = ScanGeometry::paper();
    let i = 470;
    let d = 8f64.sqrt();
    let scan = scan_with_hits(&g, &[(i, d)]);
    let mut out = vec![0.0; g.ray_count];
    Expander::new(&g).clearances(&scan, 0.3, &mut out);
    for k in 455..=485 {
        let a = g.bearing_rad(k) - g.bearing_rad(i);
        let perp = d * a.sin();
        if perp.abs() < 0.3 {
            let expected = d * a.cos() - (0.09 - perp * perp).sqrt();
            assert!((out[k] - expected).abs() < 1e-12, "ray {k}");
        }
    }
}

#[test]
fn tangent_ray_touches_the_disc() {
    // The x axis is tangent to a disc of radius 0.5 at (2, 0.5): touches at x = 2.
    assert_eq!(ray_disc_entry_m(1.0, 0.0, 2.0, 0.5, 0.5), Some(2.0));
    assert_eq!(ray_disc_entry_m(1.0, 0.0, 2.0, -0.5, 0.5), Some(2.0));
    assert_eq!(ray_disc_entry_m(0.0, 1.0, 0.25, 3.0, 0.25), Some(3.0));
    // A hair further out: no contact.
    assert_eq!(ray_disc_entry_m(1.0, 0.0, 2.0, 0.5 + 1e-12, 0.5), None);
    // On a scan: ray 0 along x, ray 1 toward the hit at (2, 0.5).
    let b1 = 0.5f64.atan2(2.0);
    let g = ScanGeometry::new(0.0, b1, 2, 0.0, 4.0).unwrap();
    let scan = scan_with_hits(&g, &[(1, 4.25f64.sqrt())]);
    let perp = 4.25f64.sqrt() * b1.sin(); // 0.5 up to rounding
    for (r, touches) in [(perp + 1e-12, true), (perp - 1e-12, false)] {
        let (slow, fast) = both(&g, &scan, r);
        for c in [slow[0], fast[0]] {
            if touches {
                assert!((c - 2.0).abs() < 1e-5, "r {r}: {c}");
            } else {
                assert_eq!(c, 4.0, "r {r}");
            }
        }
    }
}

#[test]
fn robot_inside_a_disc_is_blocked_toward_it_and_free_away_from_it() {
    let g = ScanGeometry::paper();
    // A hit 0.1 m straight ahead, r = 0.3: the robot centre is inside its disc.
    let scan = scan_with_hits(&g, &[(342, 0.1)]);
    let (slow, fast) = both(&g, &scan, 0.3);
    for k in 0..g.ray_count {
        let b = g.bearing_rad(k).abs();
        let expected = if b < FRAC_PI_2 { 0.0 } else { 4.0 };
        assert_eq!(
            slow[k],
            expected,
            "reference ray {k} at {} deg",
            b.to_degrees()
        );
        assert_eq!(fast[k], expected, "fast ray {k}");
    }
    // Exactly on the edge (d = r): the same.
    let scan = scan_with_hits(&g, &[(342, 0.3)]);
    let (slow, fast) = both(&g, &scan, 0.3);
    assert_eq!(first_difference(&slow, &fast, 1e-12), None);
    assert_eq!(fast[342], 0.0);
    assert_eq!(fast[342 + 200], 0.0); // 70 deg to the left
    assert_eq!(fast[0], 4.0); // 120 deg to the right
}

#[test]
fn hit_at_the_robot_centre_blocks_nothing() {
    // |c| = 0: no direction brings the robot closer to it.
    let g = ScanGeometry::centred(5, PI, 0.0, 4.0).unwrap();
    let scan = scan_with_hits(&g, &[(2, 0.0)]);
    let (slow, fast) = both(&g, &scan, 0.3);
    assert_eq!(slow, vec![4.0, 4.0, 0.0, 4.0, 4.0]);
    assert_eq!(fast, slow);
}

#[test]
fn max_range_and_invalid_readings_are_never_obstacles() {
    let g = ScanGeometry::centred(101, PI, 0.0, 4.0).unwrap();
    // All max range: every ray is free to the maximum range.
    let all_max = Scan::from_ranges(&g, &vec![4.0; 101], 0.0);
    let (slow, fast) = both(&g, &all_max, 0.3);
    assert!(slow.iter().chain(&fast).all(|&c| c == 4.0));
    // All invalid: nothing is an obstacle, and no ray has a free length.
    let all_bad = Scan::from_ranges(&g, &vec![f64::NAN; 101], 0.0);
    let (slow, fast) = both(&g, &all_bad, 0.3);
    assert!(slow.iter().chain(&fast).all(|&c| c == 0.0));
    // One error ray among max-range rays: its neighbours stay free; it has no free length.
    let mut ranges = vec![4.0; 101];
    ranges[50] = f64::NAN;
    let one_bad = Scan::from_ranges(&g, &ranges, 0.0);
    let (slow, fast) = both(&g, &one_bad, 0.3);
    for k in 0..101 {
        let expected = if k == 50 { 0.0 } else { 4.0 };
        assert_eq!((slow[k], fast[k]), (expected, expected), "ray {k}");
    }
    // A malformed Hit (NaN or negative range) is not an obstacle either.
    let mut bad_hit = Scan::from_ranges(&g, &vec![4.0; 101], 0.0);
    bad_hit.status[10] = RayStatus::Hit;
    bad_hit.ranges_m[10] = f64::NAN;
    bad_hit.status[20] = RayStatus::Hit;
    bad_hit.ranges_m[20] = -1.0;
    let (slow, fast) = both(&g, &bad_hit, 0.3);
    assert_eq!((slow[10], slow[20], slow[11]), (0.0, 0.0, 4.0));
    assert_eq!(fast, slow);
}

#[test]
fn empty_scan_and_mismatched_buffers_do_not_panic() {
    let g = ScanGeometry::centred(5, PI, 0.0, 4.0).unwrap();
    let empty = Scan::from_ranges(&g, &[], 0.0);
    let (slow, fast) = both(&g, &empty, 0.3);
    assert_eq!(slow, vec![0.0; 5]);
    assert_eq!(fast, vec![0.0; 5]);
    // A scan with fewer rays than the geometry: the missing rays are invalid.
    let short = Scan::from_ranges(&g, &[4.0, 4.0, 2.0], 0.0);
    let (slow, fast) = both(&g, &short, 0.3);
    assert_eq!(slow[3..], [0.0, 0.0]);
    assert_eq!(first_difference(&slow, &fast, 1e-12), None);
    // Output longer than the geometry: the extra entries are 0; shorter: the first rays only.
    let full = Scan::from_ranges(&g, &[4.0; 5], 0.0);
    let mut long = vec![9.0; 7];
    Expander::new(&g).clearances(&full, 0.3, &mut long);
    assert_eq!(long, vec![4.0, 4.0, 4.0, 4.0, 4.0, 0.0, 0.0]);
    let mut long_ref = vec![9.0; 7];
    clearances_reference(&g, &full, 0.3, &mut long_ref);
    assert_eq!(long_ref, long);
    let mut shorter = vec![9.0; 2];
    Expander::new(&g).clearances(&full, 0.3, &mut shorter);
    assert_eq!(shorter, vec![4.0, 4.0]);
    let mut none: Vec<f64> = Vec::new();
    Expander::new(&g).clearances(&full, 0.3, &mut none);
    clearances_reference(&g, &full, 0.3, &mut none);
}

#[test]
fn bad_radius_counts_as_zero() {
    let g = ScanGeometry::centred(9, PI, 0.0, 4.0).unwrap();
    let scan = scan_with_hits(&g, &[(4, 1.0)]);
    for r in [0.0, -0.3, f64::NAN, f64::INFINITY] {
        let (slow, fast) = both(&g, &scan, r);
        // Radius 0: only the hit ray itself meets its point, at its range.
        let mut expected = vec![4.0; 9];
        expected[4] = 1.0;
        assert_eq!(slow, expected, "r {r}");
        assert_eq!(fast, expected, "r {r}");
    }
}

#[test]
fn ray_counts_from_1_to_4096() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(5);
    for n in [1usize, 2, 3, 4, 7, 64, 685, 1081, 1440, 4096] {
        let fov = if n == 1 { 0.0 } else { 240f64.to_radians() };
        let g = ScanGeometry::centred(n, fov, 0.0, 4.0).unwrap();
        let ranges: Vec<f64> = (0..n)
            .map(|_| match rng.random_range(0..10) {
                0 => f64::NAN,
                1..=3 => 4.0,
                _ => rng.random_range(0.05..4.0),
            })
            .collect();
        let scan = Scan::from_ranges(&g, &ranges, 0.0);
        let (slow, fast) = both(&g, &scan, 0.3);
        assert_eq!(first_difference(&slow, &fast, 1e-9), None, "n {n}");
        assert!(fast.iter().all(|&c| (0.0..=4.0).contains(&c)), "n {n}");
    }
    // One ray: its own disc only.
    let g = ScanGeometry::centred(1, 0.0, 0.0, 4.0).unwrap();
    let (slow, fast) = both(&g, &Scan::from_ranges(&g, &[2.0], 0.0), 0.3);
    assert!((slow[0] - 1.7).abs() < 1e-12 && (fast[0] - 1.7).abs() < 1e-12);
}

#[test]
fn full_turn_scanner_wraps_around() {
    // 360 rays over a full turn: ray 0 at 0 deg, ray 359 at 359 deg (= -1 deg).
    let g = ScanGeometry::new(0.0, TAU / 360.0, 360, 0.0, 4.0).unwrap();
    let scan = scan_with_hits(&g, &[(0, 1.0)]);
    let (slow, fast) = both(&g, &scan, 0.3);
    assert_eq!(first_difference(&slow, &fast, 1e-12), None);
    // asin(0.3) = 17.46 deg: rays 0..=17 and 343..=359 are blocked.
    for k in 0..360 {
        let off = k.min(360 - k);
        assert_eq!(fast[k] < 4.0, off <= 17, "ray {k}");
    }
    // Ray 359 (1 deg off) enters at cos(1 deg) - sqrt(0.09 - sin^2(1 deg)).
    let a = 1f64.to_radians();
    assert!((fast[359] - (a.cos() - (0.09 - a.sin().powi(2)).sqrt())).abs() < 1e-12);
}

#[test]
fn expander_is_reusable_across_scans_and_radii() {
    let g = ScanGeometry::paper();
    let mut e = Expander::new(&g);
    let mut out = vec![0.0; g.ray_count];
    let near = scan_with_hits(&g, &[(342, 1.0)]);
    let far = scan_with_hits(&g, &[(100, 3.0)]);
    for (scan, r) in [(&near, 0.3), (&far, 0.5), (&near, 0.1), (&far, 0.3)] {
        e.clearances(scan, r, &mut out);
        let mut expected = vec![0.0; g.ray_count];
        clearances_reference(&g, scan, r, &mut expected);
        assert_eq!(first_difference(&out, &expected, 1e-12), None);
    }
}
