//! The clearance table of `robot-app expand` on a hand-made scan.

use expansion::{Expander, write_clearance_csv};
use scan_types::{Scan, ScanGeometry};

#[test]
fn table_of_a_single_hit() {
    // Rays at -90, 0, +90 deg; a hit 2 m ahead, r = 0.5: the centre ray clears 1.5 m.
    let g = ScanGeometry::centred(3, std::f64::consts::PI, 0.0, 4.0).unwrap();
    let s = Scan::from_ranges(&g, &[4.0, 2.0, f64::NAN], 0.0);
    let mut c = vec![0.0; 3];
    Expander::new(&g).clearances(&s, 0.5, &mut c);
    let mut buf = Vec::new();
    let n = write_clearance_csv(&mut buf, &g, &s.ranges_m, &s.status, &c, 1.6).unwrap();
    let text = String::from_utf8(buf).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "index,bearing_rad,range_m,clearance_m,blocked");
    assert_eq!(lines[1], "0,-1.570796327,4.000000,4.000000,0");
    assert_eq!(lines[2], "1,0.000000000,2.000000,1.500000,1");
    // The invalid ray has no free length: blocked.
    assert_eq!(lines[3], "2,1.570796327,NaN,0.000000,1");
    assert_eq!(n, 2);
}
