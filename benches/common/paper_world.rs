//! Noise-free scans of the paper's world: sim-laser's embedded `cave.png` at 10 m x 10 m with
//! a boundary wall (see `sim/README.md`), cast exactly by `World::raycast`.

use scan_types::{Scan, ScanGeometry, WorldPoint};
use sim_laser::World;

/// The scan a noise-free sensor of geometry `g` takes at (x, y) facing `heading_rad`.
pub fn scan(world: &World, g: &ScanGeometry, x: f64, y: f64, heading_rad: f64) -> Scan {
    let ranges: Vec<f64> = (0..g.ray_count)
        .map(|i| {
            world
                .raycast(
                    WorldPoint::new(x, y),
                    heading_rad + g.bearing_rad(i),
                    g.max_range_m,
                )
                .unwrap_or(g.max_range_m)
        })
        .collect();
    Scan::from_ranges(g, &ranges, 0.0)
}
