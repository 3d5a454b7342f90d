//! Property test: the fast kernel equals the reference within 1e-9 m per ray on tens of
//! thousands of random scans (random geometry, radius, hits, misses, errors, surfaces).

mod common;

use common::{both, first_difference};
use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed};
use scan_types::{Scan, ScanGeometry};

/// A random geometry (1..=96 rays, any field of view up to a full turn, either sweep
/// direction) and a radius.
fn geometry_and_radius() -> impl Strategy<Value = (ScanGeometry, f64)> {
    (
        1usize..=96,
        0.05f64..std::f64::consts::TAU,
        any::<bool>(),
        -3.2f64..3.2,
        prop_oneof![Just(4.0), 0.5f64..30.0],
        prop_oneof![Just(0.3), 0.0f64..1.2],
    )
        .prop_map(|(n, fov, flip, first, max_r, r)| {
            let inc = if n > 1 { fov / (n - 1) as f64 } else { fov };
            let inc = if flip { -inc } else { inc };
            (ScanGeometry::new(first, inc, n, 0.0, max_r).unwrap(), r)
        })
}

/// Ranges for `n` rays: either independent readings or a random-walk surface with gaps.
fn ranges(n: usize, max_r: f64) -> impl Strategy<Value = Vec<f64>> {
    let reading = prop_oneof![
        6 => (0.0f64..1.0).prop_map(move |u| u * max_r),
        1 => 0.0f64..0.5,
        2 => Just(max_r),
        1 => Just(f64::NAN),
    ];
    let independent = proptest::collection::vec(reading, n);
    let surface = (
        0.1f64..1.0,
        proptest::collection::vec((-0.05f64..0.05, 0u8..40), n),
    )
        .prop_map(move |(start, steps)| {
            let mut d = start * max_r;
            steps
                .into_iter()
                .map(|(step, kind)| {
                    d = (d + step * max_r).clamp(0.0, max_r * 1.2);
                    match kind {
                        0 => f64::NAN,
                        1..=3 => max_r,
                        _ => d,
                    }
                })
                .collect()
        });
    prop_oneof![independent, surface]
}

fn case() -> impl Strategy<Value = (ScanGeometry, f64, Vec<f64>)> {
    geometry_and_radius()
        .prop_flat_map(|(g, r)| (Just(g), Just(r), ranges(g.ray_count, g.max_range_m)))
}

fn config(cases: u32, seed: u64) -> Config {
    Config {
        cases,
        failure_persistence: None,
        rng_seed: RngSeed::Fixed(seed),
        ..Config::default()
    }
}

proptest! {
    #![proptest_config(config(20_000, 0x6f61_6c73))]
    #[test]
    fn fast_equals_reference_small_scans((g, r, ranges) in case()) {
        let scan = Scan::from_ranges(&g, &ranges, 0.0);
        let (slow, fast) = both(&g, &scan, r);
        prop_assert_eq!(first_difference(&slow, &fast, 1e-9), None, "{:?}\n{:?}\n{:?}", g, slow, fast);
        prop_assert!(fast.iter().all(|&c| c >= 0.0 && c <= g.max_range_m));
    }
}

proptest! {
    #![proptest_config(config(60, 0x0685))]
    #[test]
    fn fast_equals_reference_paper_sized_scans(
        ranges in ranges(685, 4.0),
        r in prop_oneof![Just(0.3), Just(0.4), 0.0f64..1.0],
    ) {
        let g = ScanGeometry::paper();
        let scan = Scan::from_ranges(&g, &ranges, 0.0);
        let (slow, fast) = both(&g, &scan, r);
        prop_assert_eq!(first_difference(&slow, &fast, 1e-9), None);
    }
}
