//! Detection rules on hand-built scans whose landmarks can be placed by hand.

use landmarks::{DetectParams, LandmarkKind, OpenSide, detect, detect_near, select_nearest};
use scan_types::testkit::{boxed, noisy, scan_at};
use scan_types::{RayStatus, Scan, ScanGeometry, WorldPoint};
use std::f64::consts::FRAC_PI_2;

fn paper_geometry() -> ScanGeometry {
    ScanGeometry::paper()
}

fn point(l: &landmarks::Landmark) -> WorldPoint {
    let p = l.robot_point();
    WorldPoint::new(p.x_m(), p.y_m())
}

/// Distance from `l` to the hand-placed point (x, y).
fn dist(l: &landmarks::Landmark, x: f64, y: f64) -> f64 {
    point(l).distance_m(&WorldPoint::new(x, y))
}

#[test]
fn single_box_corner_paper_rule() {
    // Box x 2..3, y 1..2; nothing else within 4 m. Seen from the origin facing +x its
    // silhouette ends at (2, 2) (bearing 45 deg, 2.83 m) and (3, 1) (18.4 deg, 3.16 m).
    let g = paper_geometry();
    let scan = scan_at(&g, &boxed(2.0, 1.0, 3.0, 2.0), 0.0, 0.0, 0.0);
    let found = detect(&g, &scan, &DetectParams::paper());
    assert_eq!(found.len(), 2, "{found:?}");
    // Ray spacing at ~3 m is 2 cm: the edge ray's hit lies within one spacing of the corner.
    let right = found
        .iter()
        .find(|l| dist(l, 3.0, 1.0) < 0.03)
        .expect("edge (3, 1)");
    let left = found
        .iter()
        .find(|l| dist(l, 2.0, 2.0) < 0.03)
        .expect("edge (2, 2)");
    assert_eq!(right.kind, LandmarkKind::MaxRangeJump);
    // Open space lies at lower bearings (right) of (3, 1), higher bearings (left) of (2, 2).
    assert_eq!(right.open_side, Some(OpenSide::Lower));
    assert_eq!(left.open_side, Some(OpenSide::Higher));
    // Eq. 6: the nearer one, 2.83 m away.
    let chosen = select_nearest(&found, FRAC_PI_2).unwrap();
    assert!(dist(&chosen, 2.0, 2.0) < 0.03);
    assert!((chosen.range_m - 8f64.sqrt()).abs() < 0.03);
}

#[test]
fn single_box_corner_goalseek_rules() {
    let g = paper_geometry();
    let scan = noisy(
        &g,
        &scan_at(&g, &boxed(2.0, 1.0, 3.0, 2.0), 0.0, 0.0, 0.0),
        0.01,
        7,
    );
    let found = detect(&g, &scan, &DetectParams::default());
    // Two silhouette edges plus the convex corner (2, 1) between the two visible faces.
    let corner = found
        .iter()
        .find(|l| l.kind == LandmarkKind::Corner)
        .expect("corner found");
    assert!(dist(corner, 2.0, 1.0) < 0.03, "{corner:?}");
    assert_eq!(
        found
            .iter()
            .filter(|l| l.kind == LandmarkKind::Corner)
            .count(),
        1
    );
    let far = found.iter().find(|l| dist(l, 3.0, 1.0) < 0.04).unwrap();
    let near = found.iter().find(|l| dist(l, 2.0, 2.0) < 0.04).unwrap();
    // (2, 2): its own face x = 2 runs from it toward the path, so the side ray at B
    // would graze that face: flagged and ranked down. (3, 1) stays clean.
    assert!(near.hidden_at_side && !near.is_stable());
    assert!(far.is_stable() && !far.hidden_at_side, "{far:?}");
    assert!(near.score < far.score);
}

#[test]
fn doorway_into_open_space() {
    // A wall at x = 2 from y = -4 to 4 with a door from y = 0.5 to 1.4; nothing behind.
    // The jambs are landmarks; where the wall runs out of range (|y| = sqrt(12) = 3.46)
    // the paper also finds range-limit artefacts at ~3.9-4.0 m.
    let g = paper_geometry();
    let walls = vec![((2.0, -4.0), (2.0, 0.5)), ((2.0, 1.4), (2.0, 4.0))];
    let scan = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let paper = detect(&g, &scan, &DetectParams::paper());
    assert_eq!(paper.len(), 4, "{paper:?}");
    assert_eq!(paper.iter().filter(|l| l.range_m > 3.9).count(), 2);
    let ours = detect(&g, &scan, &DetectParams::default());
    assert_eq!(ours.len(), 2, "{ours:?}");
    // Ray spacing at 2.1 m is 1.3 cm.
    let low = ours
        .iter()
        .find(|l| dist(l, 2.0, 0.5) < 0.02)
        .expect("jamb (2, 0.5)");
    let high = ours
        .iter()
        .find(|l| dist(l, 2.0, 1.4) < 0.02)
        .expect("jamb (2, 1.4)");
    assert_eq!(low.open_side, Some(OpenSide::Higher));
    assert_eq!(high.open_side, Some(OpenSide::Lower));
}

#[test]
fn doorway_with_a_room_behind_gives_occlusion_edges() {
    // Same door, a back wall at x = 3 within range: the jambs are now occlusion edges
    // (range 2.06 m against 3+ m behind), invisible to the paper's max-range rule.
    let g = paper_geometry();
    let walls = vec![
        ((2.0, -4.0), (2.0, 0.5)),
        ((2.0, 1.4), (2.0, 4.0)),
        ((3.0, -1.0), (3.0, 3.0)),
    ];
    let scan = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let paper = detect(&g, &scan, &DetectParams::paper());
    assert!(
        paper
            .iter()
            .all(|l| dist(l, 2.0, 0.5) > 0.1 && dist(l, 2.0, 1.4) > 0.1)
    );
    let ours = detect(&g, &scan, &DetectParams::default());
    for (x, y) in [(2.0, 0.5), (2.0, 1.4)] {
        let l = ours
            .iter()
            .find(|l| dist(l, x, y) < 0.02)
            .unwrap_or_else(|| panic!("no edge at ({x}, {y}): {ours:?}"));
        assert_eq!(l.kind, LandmarkKind::OcclusionEdge);
        // The nearer, occluding side is the landmark.
        assert!(l.range_m < 2.6);
    }
}

#[test]
fn wall_running_out_of_range() {
    // A wall parallel to the heading at y = 1: it leaves the 4 m range at bearing
    // asin(1/4) = 14.5 deg; the last hit there is a range-limit artefact (> 3.9 m).
    let g = paper_geometry();
    let walls = vec![((-6.0, 1.0), (10.0, 1.0))];
    let scan = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let paper = detect(&g, &scan, &DetectParams::paper());
    assert_eq!(paper.len(), 1, "{paper:?}");
    assert!(paper[0].range_m > 3.9 && paper[0].near_range_limit);
    assert!(paper[0].surface_continues);
    assert!((paper[0].bearing_rad.to_degrees() - 14.48).abs() < 0.5);
    // Each rule alone rejects it.
    let only_margin = DetectParams {
        reject_surface_continues: false,
        ..DetectParams::default()
    };
    assert!(detect(&g, &scan, &only_margin).is_empty());
    let only_surface = DetectParams {
        reject_near_range_limit: false,
        ..DetectParams::default()
    };
    assert!(detect(&g, &scan, &only_surface).is_empty());
    // The range margin alone with a 1 cm margin no longer catches it, the surface rule does.
    let thin = DetectParams {
        range_limit_margin_m: 0.01,
        reject_surface_continues: false,
        edge_refine: false,
        ..DetectParams::default()
    };
    // By hand: rays at -120 + i * 240/684 deg hit the wall when 1 / sin(b) < 4, i.e. from
    // i = 384 (b = 14.737 deg, range 1 / sin(b) = 3.9305 m): that hit is the landmark.
    let seen = detect(&g, &scan, &thin);
    assert_eq!(seen.len(), 1);
    assert_eq!(seen[0].index, 384);
    assert!((seen[0].range_m - 3.9305).abs() < 1e-3, "{:?}", seen[0]);
}

#[test]
fn neighbour_n_widens_the_rule() {
    // 9 rays: hits at 2 m on rays 0..=3, misses on 4..=8. With n = 1 the edge is ray 3;
    // with n = 3 it is still ray 3 (the hit nearest to the open ray), found once.
    let g = ScanGeometry::centred(9, 8f64.to_radians(), 0.0, 4.0).unwrap();
    let scan = Scan::from_ranges(&g, &[2.0, 2.0, 2.0, 2.0, 4.0, 4.0, 4.0, 4.0, 4.0], 0.0);
    for n in [1, 2, 3] {
        let p = DetectParams {
            neighbour_n: n,
            ..DetectParams::paper()
        };
        let found = detect(&g, &scan, &p);
        assert_eq!(found.len(), 1, "n = {n}");
        assert_eq!(found[0].index, 3);
    }
    // n larger than the hit run still finds the edge from the far side of the open run.
    let p = DetectParams {
        neighbour_n: 5,
        ..DetectParams::paper()
    };
    assert!(detect(&g, &scan, &p).is_empty() || detect(&g, &scan, &p)[0].index == 3);
}

#[test]
fn error_rays_are_skipped_never_hits_nor_open() {
    let g = ScanGeometry::centred(10, 9f64.to_radians(), 0.0, 4.0).unwrap();
    let mut scan = Scan::from_ranges(&g, &[2.0, 2.0, 2.0, 2.0, 2.0, 4.0, 4.0, 4.0, 4.0, 4.0], 0.0);
    // Two error rays between the wall and the open space: the edge is still ray 4.
    scan.status[5] = RayStatus::Error(0);
    scan.ranges_m[5] = f64::NAN;
    scan.status[6] = RayStatus::Error(7);
    scan.ranges_m[6] = f64::NAN;
    for p in [DetectParams::paper(), DetectParams::default()] {
        let found = detect(&g, &scan, &p);
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].index, 4);
    }
    // An error ray inside a wall makes no landmark.
    let mut wall = Scan::from_ranges(&g, &[2.0; 10], 0.0);
    wall.status[4] = RayStatus::Error(0);
    wall.ranges_m[4] = f64::NAN;
    assert!(detect(&g, &wall, &DetectParams::paper()).is_empty());
    // A long run of errors splits the scan: no edge across it.
    let mut gap = Scan::from_ranges(&g, &[2.0, 2.0, 2.0, 4.0, 4.0, 4.0, 4.0, 4.0, 4.0, 4.0], 0.0);
    for i in 3..8 {
        gap.status[i] = RayStatus::Error(0);
        gap.ranges_m[i] = f64::NAN;
    }
    assert!(detect(&g, &gap, &DetectParams::default()).is_empty());
}

#[test]
fn single_miss_inside_a_wall() {
    // One max-range dropout in a wall: the paper finds two landmarks, goalseek (at least
    // three open rays) none.
    let g = ScanGeometry::centred(11, 10f64.to_radians(), 0.0, 4.0).unwrap();
    let mut r = [2.0; 11];
    r[5] = f64::INFINITY;
    let scan = Scan::from_ranges(&g, &r, 0.0);
    let paper = detect(&g, &scan, &DetectParams::paper());
    assert_eq!(
        paper.iter().map(|l| l.index).collect::<Vec<_>>(),
        vec![4, 6]
    );
    assert_eq!(paper[0].open_side, Some(OpenSide::Higher));
    assert!(detect(&g, &scan, &DetectParams::default()).is_empty());
}

#[test]
fn l_shaped_room_corner() {
    // A concave corner at (3, 1) where a wall x = 3 (from y = -3) meets a wall y = 1 (from
    // x = -3): one corner landmark, placed within 2 cm of (3, 1) by the arm fits.
    let g = paper_geometry();
    let walls = vec![((3.0, -3.0), (3.0, 1.0)), ((3.0, 1.0), (-3.0, 1.0))];
    let scan = noisy(&g, &scan_at(&g, &walls, 0.0, 0.0, 0.0), 0.01, 3);
    let found = detect(&g, &scan, &DetectParams::default());
    let corners: Vec<_> = found
        .iter()
        .filter(|l| l.kind == LandmarkKind::Corner)
        .collect();
    assert_eq!(corners.len(), 1, "{found:?}");
    assert!(dist(corners[0], 3.0, 1.0) < 0.02, "{:?}", corners[0]);
    assert!(
        detect(&g, &scan, &DetectParams::paper())
            .iter()
            .all(|l| l.kind != LandmarkKind::Corner)
    );
}

#[test]
fn no_landmark_in_front() {
    // The only object lies behind-left (bearing 100..120 deg): landmarks exist but none
    // within 90 deg of the central ray.
    let g = paper_geometry();
    let walls = boxed(-1.5, 1.0, -0.8, 2.0);
    let scan = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let found = detect(&g, &scan, &DetectParams::default());
    assert!(!found.is_empty());
    assert!(found.iter().all(|l| l.bearing_rad > FRAC_PI_2));
    assert!(select_nearest(&found, FRAC_PI_2).is_none());
    // And open space: nothing at all.
    let empty = scan_at(&g, &[], 0.0, 0.0, 0.0);
    assert!(detect(&g, &empty, &DetectParams::default()).is_empty());
    assert!(select_nearest(&[], FRAC_PI_2).is_none());
}

#[test]
fn mismatched_scan_length_does_not_panic() {
    let g = paper_geometry();
    let scan = Scan::from_ranges(&g, &[1.0, 4.0, 4.0, 4.0, 1.0], 0.0);
    let _ = detect(&g, &scan, &DetectParams::default());
    assert!(DetectParams::default().validate().is_ok());
    assert!(DetectParams::paper().validate().is_ok());
    let bad = DetectParams {
        neighbour_n: 0,
        ..DetectParams::default()
    };
    assert!(
        bad.validate()
            .unwrap_err()
            .to_string()
            .contains("neighbour_n")
    );
}

#[test]
fn short_dropout_run_in_a_wall_is_not_open_space() {
    // Wall at 1 m straight ahead (x = 1), 5 rays reading no return in its middle: the two
    // bounding hits are 5 spacings apart (about 5 * 0.0061 = 3 cm): a dropout, not a gap.
    let g = paper_geometry();
    let mut scan = scan_at(&g, &[((1.0, -3.0), (1.0, 3.0))], 0.0, 0.0, 0.0);
    for i in 340..345 {
        scan.status[i] = RayStatus::MaxRange;
        scan.ranges_m[i] = g.max_range_m;
    }
    assert_eq!(detect(&g, &scan, &DetectParams::paper()).len(), 2 + 2);
    let ours = detect(&g, &scan, &DetectParams::default());
    assert!(
        ours.iter().all(|l| !(330..355).contains(&l.index)),
        "{ours:?}"
    );
    // A real door, 0.9 m wide, in the same wall keeps its jambs.
    let walls = vec![((1.0, -3.0), (1.0, -0.45)), ((1.0, 0.45), (1.0, 3.0))];
    let door = scan_at(&g, &walls, 0.0, 0.0, 0.0);
    let jambs = detect(&g, &door, &DetectParams::default());
    assert!(
        jambs.iter().any(|l| dist(l, 1.0, -0.45) < 0.02),
        "{jambs:?}"
    );
    assert!(jambs.iter().any(|l| dist(l, 1.0, 0.45) < 0.02), "{jambs:?}");
}

#[test]
fn detect_near_is_detect_within_the_radius() {
    // A room with two boxes and a zig-zag wall (many corners, runs of corner candidates),
    // seen from several poses with noise: `detect_near` gives exactly the landmarks of
    // `detect` within the radius, for centres on and between landmarks.
    let g = paper_geometry();
    let mut world = boxed(-3.0, -3.0, 3.0, 3.0);
    world.extend(boxed(1.0, 0.5, 1.6, 1.1));
    world.extend(boxed(-1.5, -2.0, -1.0, -1.2));
    world.extend([
        ((2.0, -2.5), (2.4, -2.1)),
        ((2.4, -2.1), (2.0, -1.7)),
        ((2.0, -1.7), (2.4, -1.3)),
    ]);
    let mut checked = 0;
    for (k, &(x, y, th)) in [
        (0.0, 0.0, 0.0),
        (-0.5, 0.3, 0.7),
        (0.8, -1.0, -1.2),
        (1.9, -1.9, 0.1),
    ]
    .iter()
    .enumerate()
    {
        let scan = noisy(&g, &scan_at(&g, &world, x, y, th), 0.01, k as u64);
        for params in [
            DetectParams::default().permissive(),
            DetectParams::default(),
        ] {
            let all = detect(&g, &scan, &params);
            assert!(all.iter().any(|l| l.kind == LandmarkKind::Corner));
            let mut centres: Vec<_> = all.iter().map(|l| l.robot_point()).collect();
            centres.push(scan_types::RobotPoint::new(0.7, -0.4));
            for c in centres {
                for radius in [0.0, 0.05, 0.1, 0.3, 1.0, f64::INFINITY] {
                    let want: Vec<_> = all
                        .iter()
                        .filter(|l| l.robot_point().distance_m(&c) <= radius)
                        .copied()
                        .collect();
                    assert_eq!(detect_near(&g, &scan, &params, c, radius), want);
                    checked += want.len();
                }
            }
        }
    }
    assert!(checked > 100, "{checked}");
    // A NaN radius matches nothing, without panicking.
    let scan = scan_at(&g, &world, 0.0, 0.0, 0.0);
    let c = scan_types::RobotPoint::new(1.0, 0.0);
    assert!(detect_near(&g, &scan, &DetectParams::default(), c, f64::NAN).is_empty());
}
