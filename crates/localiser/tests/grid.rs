//! The occupancy grid and the point map on a hand-built room, and the map_server export
//! read back as Nav2's loader would.

use localiser::{CellState, OccupancyGrid, PointMap, pixel};
use scan_types::testkit::{boxed, scan_at};
use scan_types::{Pose2, RayStatus, ScanGeometry, WorldPoint};

/// A 4 m x 3 m room (x 0.02..4.02, y 0.02..3.02: walls mid-cell) seen from (1, 1) facing +x with a 360-deg, 1-deg sensor.
fn room_scan() -> (ScanGeometry, scan_types::Scan, Pose2) {
    let g = ScanGeometry::new(
        -std::f64::consts::PI + 0.001,
        1f64.to_radians(),
        360,
        0.0,
        10.0,
    )
    .unwrap();
    let pose = Pose2::new(1.0, 1.0, 0.0);
    let scan = scan_at(&g, &boxed(0.02, 0.02, 4.02, 3.02), 1.0, 1.0, 0.0);
    (g, scan, pose)
}

#[test]
fn walls_occupied_inside_free_outside_unknown() {
    let (g, scan, pose) = room_scan();
    let mut grid = OccupancyGrid::new(0.05);
    grid.integrate(&pose, &g, &scan);
    // Wall cells.
    for p in [(4.02, 1.0), (2.0, 3.02), (0.02, 1.5), (2.5, 0.02)] {
        assert!(grid.is_occupied(WorldPoint::new(p.0, p.1)), "{p:?}");
    }
    // Free space the rays crossed.
    for p in [(2.0, 1.5), (3.0, 2.5), (0.5, 0.5), (1.2, 1.0)] {
        assert!(grid.is_free(WorldPoint::new(p.0, p.1)), "{p:?}");
    }
    // Behind the walls: never seen.
    for p in [(4.3, 1.0), (2.0, 3.4), (-0.5, 1.0)] {
        assert_eq!(
            grid.state(WorldPoint::new(p.0, p.1)),
            CellState::Unknown,
            "{p:?}"
        );
    }
    // The grid grew to fit the room (plus padding).
    let o = grid.origin();
    assert!(o.x_m() <= 0.0 && o.y_m() <= 0.0);
    assert!(o.x_m() + grid.width() as f64 * 0.05 >= 4.0);
}

#[test]
fn max_range_rays_only_free_and_errors_nothing() {
    // One ray ahead reading max range (3 m), one to the left an error.
    let g = ScanGeometry::centred(2, std::f64::consts::FRAC_PI_2, 0.0, 3.0).unwrap();
    let mut scan = scan_types::Scan::from_ranges(&g, &[f64::INFINITY, 1.0], 0.0);
    // Ray 0 points -45 deg, ray 1 +45 deg; make ray 1 an error.
    scan.status[1] = RayStatus::Error(3);
    scan.ranges_m[1] = f64::NAN;
    let mut grid = OccupancyGrid::new(0.1);
    grid.integrate(&Pose2::new(0.0, 0.0, 0.0), &g, &scan);
    let along = |d: f64| {
        WorldPoint::new(
            d * (-45f64).to_radians().cos(),
            d * (-45f64).to_radians().sin(),
        )
    };
    assert!(grid.is_free(along(1.5)));
    assert!(!grid.is_occupied(along(2.99)));
    let left = WorldPoint::new(0.7, 0.7);
    assert_eq!(grid.state(left), CellState::Unknown);
}

#[test]
fn map_server_export_reads_back() {
    let (g, scan, pose) = room_scan();
    let mut grid = OccupancyGrid::new(0.05);
    grid.integrate(&pose, &g, &scan);
    let dir = tempfile::tempdir().unwrap();
    let files = grid.write_map_server(dir.path(), "room").unwrap();
    let bytes = std::fs::read(&files.pgm).unwrap();
    assert_eq!(&bytes[..2], b"P5");
    let img = image::load_from_memory(&bytes).unwrap().to_luma8();
    assert_eq!(img.width() as usize, grid.width());
    assert_eq!(img.height() as usize, grid.height());
    let yaml = std::fs::read_to_string(&files.yaml).unwrap();
    assert!(yaml.contains("image: room.pgm\n"));
    assert!(yaml.contains("mode: trinary\n"));
    assert!(yaml.contains("resolution: 0.05\n"));
    assert!(yaml.contains("negate: 0\n"));
    // Parse the origin and map world points to pixels as map_server does: column from x,
    // row counted from the top.
    let line = yaml.lines().find(|l| l.starts_with("origin:")).unwrap();
    // No floating-point noise (a cell multiple such as -117 * 0.05 is written -5.85).
    for n in line["origin: [".len()..line.len() - 1].split(',') {
        let decimals = n.trim().split_once('.').map_or(0, |(_, d)| d.len());
        assert!(decimals <= 9, "{line}");
        // Always a decimal point, so every element reads as a float (`-48.0`, not `-48`).
        assert!(n.contains('.'), "{line}");
    }
    assert!(yaml.contains("free_thresh: 0.196\n") && yaml.contains("occupied_thresh: 0.65\n"));
    let nums: Vec<f64> = line["origin: [".len()..line.len() - 1]
        .split(',')
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let px = |x: f64, y: f64| {
        let col = ((x - nums[0]) / 0.05).floor() as u32;
        let row_from_bottom = ((y - nums[1]) / 0.05).floor() as u32;
        img.get_pixel(col, img.height() - 1 - row_from_bottom).0[0]
    };
    assert_eq!(px(4.02, 1.0), pixel::OCCUPIED);
    assert_eq!(px(2.0, 3.02), pixel::OCCUPIED);
    assert_eq!(px(2.0, 1.5), pixel::FREE);
    assert_eq!(px(4.3, 1.0), pixel::UNKNOWN);
    // Nav2 trinary: occ = (255 - p) / 255; 205 must land between the thresholds.
    let occ = |p: u8| (255.0 - p as f64) / 255.0;
    assert!(occ(pixel::UNKNOWN) > 0.196 && occ(pixel::UNKNOWN) < 0.65);
    assert!(occ(pixel::FREE) < 0.196 && occ(pixel::OCCUPIED) > 0.65);
    // PNG: the same pixels.
    let png = dir.path().join("room.png");
    grid.to_png(&png).unwrap();
    let back = image::open(&png).unwrap().to_luma8();
    assert_eq!(back.as_raw(), img.as_raw());
    // Written atomically: nothing but the three files is left.
    let mut names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    names.sort();
    assert_eq!(names, vec!["room.pgm", "room.png", "room.yaml"]);
}

#[test]
fn empty_grid_and_bad_dir_are_errors() {
    let grid = OccupancyGrid::new(0.05);
    let dir = tempfile::tempdir().unwrap();
    let e = grid.write_map_server(dir.path(), "m").unwrap_err();
    assert!(e.to_string().contains("empty"));
    let (g, scan, pose) = room_scan();
    let mut grid = OccupancyGrid::new(0.05);
    grid.integrate(&pose, &g, &scan);
    let missing = dir.path().join("no/such/dir");
    let e = grid.write_map_server(&missing, "m").unwrap_err();
    assert!(e.to_string().contains("no/such/dir"), "{e}");
}

#[test]
fn point_map_transforms_hits() {
    let (g, scan, pose) = room_scan();
    let mut map = PointMap::new();
    map.add_scan(&pose, &g, &scan);
    assert_eq!(map.len(), 1);
    assert_eq!(map.points().count(), 360);
    // Every point lies on a wall of the room.
    for p in map.points() {
        let on_wall = [
            p.x_m() - 0.02,
            4.02 - p.x_m(),
            p.y_m() - 0.02,
            3.02 - p.y_m(),
        ]
        .iter()
        .any(|d| d.abs() < 1e-6);
        assert!(on_wall, "{p:?}");
    }
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("points.csv");
    map.write_csv(&csv).unwrap();
    let text = std::fs::read_to_string(&csv).unwrap();
    assert_eq!(text.lines().count(), 361);
    assert!(text.starts_with("scan,x_m,y_m\n"));
}

#[test]
fn wild_pose_or_range_does_not_blow_up_the_grid() {
    let (g, scan, pose) = room_scan();
    let mut grid = OccupancyGrid::new(0.05);
    assert!(grid.integrate(&pose, &g, &scan));
    let (w, h) = (grid.width(), grid.height());
    // A pose a thousand kilometres away would need a 2e7-cell-wide grid: skipped.
    assert!(!grid.integrate(&Pose2::new(1e6, 0.0, 0.0), &g, &scan));
    assert!(!grid.integrate(&Pose2::new(f64::NAN, 0.0, 0.0), &g, &scan));
    // A "hit" at 1e9 m from a faulty source: skipped too.
    let mut wild = scan.clone();
    wild.ranges_m[0] = 1e9;
    assert!(!grid.integrate(&pose, &g, &wild));
    assert_eq!((grid.width(), grid.height()), (w, h));
}
