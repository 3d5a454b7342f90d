//! The fast kernel allocates nothing per scan once its tables are built: the caller owns the
//! output buffer. Counted with a counting global allocator (this test binary only).

use expansion::Expander;
use scan_types::{Scan, ScanGeometry};

/// Scans of every kind: walls, gaps, invalid readings, a robot inside a disc, all misses.
fn scans(g: &ScanGeometry) -> Vec<Scan> {
    let n = g.ray_count;
    let wall: Vec<f64> = (0..n).map(|i| 1.0 + (i % 50) as f64 * 0.02).collect();
    let mixed: Vec<f64> = (0..n)
        .map(|i| match i % 7 {
            0 => f64::NAN,
            1 => g.max_range_m,
            2 => 0.1,
            _ => 0.5 + (i % 13) as f64 * 0.25,
        })
        .collect();
    let misses = vec![g.max_range_m; n];
    let invalid = vec![f64::NAN; n];
    [wall, mixed, misses, invalid]
        .iter()
        .map(|r| Scan::from_ranges(g, r, 0.0))
        .collect()
}

#[test]
fn clearances_allocate_nothing_after_construction() {
    let geometries = [
        ScanGeometry::paper(),
        ScanGeometry::centred(1081, 270f64.to_radians(), 0.1, 30.0).unwrap(),
        // A full turn: the wrap-around windows.
        ScanGeometry::new(-std::f64::consts::PI, 0.25f64.to_radians(), 1440, 0.0, 4.0).unwrap(),
    ];
    for g in geometries {
        let scans = scans(&g);
        let mut expander = Expander::new(&g);
        let mut out = vec![0.0; g.ray_count];
        let info = allocation_counter::measure(|| {
            for _ in 0..3 {
                for s in &scans {
                    for radius in [0.0, 0.3, 2.5] {
                        expander.clearances(s, radius, &mut out);
                    }
                }
            }
        });
        assert_eq!(
            info.count_total, 0,
            "{} rays: {} allocations",
            g.ray_count, info.count_total
        );
        // The measurement is live: building a new kernel does allocate.
        let info = allocation_counter::measure(|| {
            std::hint::black_box(Expander::new(&g));
        });
        assert!(info.count_total > 0);
    }
}
