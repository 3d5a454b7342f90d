//! Noise-free scans of the paper's world: sim-laser's embedded `cave.png` at 10 m x 10 m with
//! a boundary wall (see `sim/README.md`), cast exactly by `World::raycast`.

use scan_types::{Scan, ScanGeometry, WorldPoint};
use sim_laser::World;

/// Poses (x, y, heading rad) in free space of the paper's world, each at least 0.45 m from any
/// obstacle: the paper's start, its point B, and points spread over the world.
pub fn poses() -> [(f64, f64, f64); 6] {
    let start = sim_laser::paper_start();
    [
        (start.x_m, start.y_m, start.theta_rad),
        (-2.09, -2.34, 0.9),
        (-1.0, 2.0, 0.3),
        (3.5, -1.0, 1.2),
        (2.0, 3.0, 0.6),
        (4.0, 4.0, -2.4),
    ]
}

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
