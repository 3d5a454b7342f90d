//! The direction of a scan's walls modulo 90 deg ([`localiser::wall_axes`]) in hand-built
//! rooms, whose walls' directions are known.

use localiser::{AxesParams, wall_axes, wrap_quarter_rad};
use scan_types::ScanGeometry;
use scan_types::testkit::{boxed, noisy, scan_at};

#[test]
fn a_box_rooms_walls_give_the_heading_modulo_90_deg() {
    let g = ScanGeometry::paper();
    // A 6 m x 4 m room: from the middle every wall lies within the 4 m range somewhere.
    let room = boxed(0.0, 0.0, 6.0, 4.0);
    for heading_deg in [0.0, 10.0, 25.0, 40.0, -30.0, 100.0, 178.0] {
        let scan = scan_at(&g, &room, 3.0, 2.0, f64::to_radians(heading_deg));
        let axes = wall_axes(&g, &scan, &AxesParams::default()).expect("four walls in view");
        // The walls run along x and y: in the robot frame at -heading, modulo 90 deg.
        let want = wrap_quarter_rad(-f64::to_radians(heading_deg));
        let off = wrap_quarter_rad(axes.angle_rad - want).to_degrees();
        // Exact but for the fits beside a corner, which reach a hit or two round it.
        assert!(off.abs() < 0.05, "heading {heading_deg}: {off} deg off");
        assert!(axes.share > 0.99, "{axes:?}");
    }
}

#[test]
fn range_noise_of_a_centimetre_moves_the_answer_by_a_fraction_of_a_degree() {
    // The `paper` sensor's noise (0.01 m): each wall hit's direction comes from neighbours
    // spanning at least 0.4 m, and a scan holds hundreds of them.
    let g = ScanGeometry::paper();
    let room = boxed(0.0, 0.0, 6.0, 4.0);
    for seed in 0..20 {
        let scan = noisy(&g, &scan_at(&g, &room, 3.0, 2.0, 0.3), 0.01, seed);
        let axes = wall_axes(&g, &scan, &AxesParams::default()).expect("walls");
        let off = wrap_quarter_rad(axes.angle_rad + 0.3).to_degrees();
        assert!(off.abs() < 0.2, "seed {seed}: {off} deg");
    }
}

#[test]
fn walls_off_the_axes_are_left_out_and_counted() {
    // A room whose right-hand wall is replaced by one at 20 deg to the y axis: its hits do
    // not agree with the other walls, which decide.
    let g = ScanGeometry::paper();
    let mut room = boxed(0.0, 0.0, 6.0, 4.0);
    room[1] = ((5.3, 0.0), (5.3 + 4.0 * 20f64.to_radians().tan(), 4.0));
    let scan = scan_at(&g, &room, 3.0, 2.0, 0.0);
    let axes = wall_axes(&g, &scan, &AxesParams::default()).expect("walls");
    assert!(axes.angle_rad.to_degrees().abs() < 0.01, "{axes:?}");
    assert!(axes.share < 0.9, "{axes:?}");
}

#[test]
fn a_scan_without_straight_walls_has_no_axes() {
    let g = ScanGeometry::paper();
    // A round room of radius 1.5 m as 360 short chords: every neighbourhood bends.
    let n = 360;
    let ring: Vec<_> = (0..n)
        .map(|i| {
            let a = |k: usize| std::f64::consts::TAU * k as f64 / n as f64;
            (
                (1.5 * a(i).cos(), 1.5 * a(i).sin()),
                (1.5 * a(i + 1).cos(), 1.5 * a(i + 1).sin()),
            )
        })
        .collect();
    let scan = scan_at(&g, &ring, 0.0, 0.0, 0.0);
    assert_eq!(wall_axes(&g, &scan, &AxesParams::default()), None);
    // Nothing in range at all, even when no fit at all would do.
    let empty = scan_at(&g, &[], 0.0, 0.0, 0.0);
    assert_eq!(wall_axes(&g, &empty, &AxesParams::default()), None);
    let any = AxesParams {
        min_points: 0,
        min_share: 0.0,
        ..AxesParams::default()
    };
    assert_eq!(wall_axes(&g, &empty, &any), None);
}
