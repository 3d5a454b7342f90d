//! Frontiers of a map built from hand-made scans, and new targets for a finished navigator.

use localiser::OccupancyGrid;
use navigator::{Action, ExploreParams, Navigator, NavigatorError, Params, Reason, frontiers};
use scan_types::testkit::{Seg, boxed, scan_at};
use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

/// The map of a room seen from its centre, looking east and west (240 deg each: all round).
fn map_of(walls: &[Seg]) -> OccupancyGrid {
    let g = ScanGeometry::paper();
    let mut grid = OccupancyGrid::new(0.05);
    for theta in [0.0, std::f64::consts::PI] {
        let scan = scan_at(&g, walls, 0.0, 0.0, theta);
        assert!(grid.integrate(&Pose2::new(0.0, 0.0, theta), &g, &scan));
    }
    grid
}

#[test]
fn a_closed_room_has_no_frontier() {
    // A 3.04 m square room (walls off the 0.05 m cell boundaries), all of it within 4 m.
    let grid = map_of(&boxed(-1.52, -1.52, 1.52, 1.52));
    let f = frontiers(
        &grid,
        WorldPoint::new(0.0, 0.0),
        0.3,
        &[],
        &ExploreParams::default(),
    );
    assert!(f.is_empty(), "{f:?}");
}

#[test]
fn a_doorway_is_the_one_frontier_and_its_target_lies_beyond_it() {
    // The same room with a 1 m doorway in its east wall (y in -0.5..0.5): the rays through it
    // end at the 4 m range, so the map's only free cells next to unknown ones are beyond the
    // wall (x > 1.52).
    let walls = vec![
        ((-1.52, -1.52), (1.52, -1.52)),
        ((1.52, -1.52), (1.52, -0.5)),
        ((1.52, 0.5), (1.52, 1.52)),
        ((1.52, 1.52), (-1.52, 1.52)),
        ((-1.52, 1.52), (-1.52, -1.52)),
    ];
    let grid = map_of(&walls);
    let f = frontiers(
        &grid,
        WorldPoint::new(0.0, 0.0),
        0.3,
        &[],
        &ExploreParams::default(),
    );
    assert_eq!(f.len(), 1, "{f:?}");
    let t = f[0].target;
    assert!(t.x_m() > 1.52, "{t:?}");
    // Within the fan of rays through the doorway, at most 4 m from the robot.
    assert!(t.y_m().abs() <= t.x_m() * 0.5 / 1.52 + 0.1, "{t:?}");
    assert!(
        t.distance_m(&WorldPoint::new(0.0, 0.0)) <= 4.0 + 0.1,
        "{t:?}"
    );
    assert!(f[0].clearance_m >= 0.3, "{:?}", f[0]);
    // A wider robot (0.45 m, more than the 0.4 m target clearance) still finds it: the fan
    // beyond the 1 m doorway is 2.6 m wide at 4 m.
    let wide = frontiers(
        &grid,
        WorldPoint::new(0.0, 0.0),
        0.45,
        &[],
        &ExploreParams::default(),
    );
    assert_eq!(wide.len(), 1, "{wide:?}");
    assert!(
        wide[0].clearance_m >= 0.45 && wide[0].target.x_m() > 1.52,
        "{wide:?}"
    );
    // A target within 0.5 m of a point to avoid is not taken: another cell of the frontier is,
    // outside that disc.
    let avoid = [(t, 0.5)];
    let other = frontiers(
        &grid,
        WorldPoint::new(0.0, 0.0),
        0.3,
        &avoid,
        &ExploreParams::default(),
    );
    assert_eq!(other.len(), 1, "{other:?}");
    assert!(other[0].target.distance_m(&t) > 0.5, "{other:?}");
}

#[test]
fn a_finished_navigator_takes_a_new_target() {
    let g = ScanGeometry::paper();
    let start = Pose2::new(0.0, 0.0, 0.0);
    // The goal is the start: the first scan ends the run `reached`.
    let mut nav = Navigator::new(Params::goalseek(), g, start, start.position()).unwrap();
    // Not finished yet: no new target.
    assert_eq!(
        nav.retarget(WorldPoint::new(1.0, 0.0)),
        Err(NavigatorError::NotFinished(navigator::Phase::Starting))
    );
    let scan = Scan::from_ranges(&g, &vec![f64::INFINITY; g.ray_count], 0.0);
    assert_eq!(nav.on_scan(&scan), Action::Finish(Reason::Reached));
    assert!(nav.retarget(WorldPoint::new(f64::NAN, 0.0)).is_err());
    assert_eq!(nav.retarget(WorldPoint::new(2.0, 0.0)), Ok(Action::Scan));
    assert_eq!(nav.goal(), WorldPoint::new(2.0, 0.0));
    // The next scan plans toward the new target (2 m ahead, open space): a drive or a turn,
    // and the start is recorded once.
    let next = nav.on_scan(&scan);
    assert!(
        matches!(next, Action::Forward { .. } | Action::Rotate { .. }),
        "{next:?}"
    );
    assert_eq!(nav.legs().len(), 1);
    // A run ended by a failure takes no new target.
    nav.fail(Reason::Collision, "bumped");
    assert_eq!(
        nav.retarget(WorldPoint::new(0.0, 0.0)),
        Err(NavigatorError::EndedBy(Reason::Collision))
    );
}
