//! An occupancy grid built from scans at known poses (a log's, or a SLAM estimate), and how
//! consistent it is: the share of hit endpoints within one cell of an occupied cell.

use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};

use crate::{CellState, OccupancyGrid};

/// How a map built by [`build_map`] fits its scans.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapStats {
    /// Scans in the log.
    pub scans: usize,
    /// Scans integrated (those with a pose).
    pub mapped: usize,
    /// Hit endpoints checked.
    pub endpoints: usize,
    /// Endpoints within one cell (8-neighbourhood) of an occupied cell of the final map.
    pub near_occupied: usize,
}

impl MapStats {
    /// Share of endpoints within one cell of an occupied cell.
    pub fn endpoint_fit(&self) -> f64 {
        self.near_occupied as f64 / self.endpoints.max(1) as f64
    }
}

/// The scan limited to `max_range_m` (farther hits become max-range misses) and its
/// geometry; without `clear_no_return`, max-range misses are left out (marked invalid).
fn clip(
    geometry: &ScanGeometry,
    scan: &Scan,
    max_range_m: f64,
    clear_no_return: bool,
) -> (ScanGeometry, Scan) {
    let mut g = *geometry;
    g.max_range_m = max_range_m.min(g.max_range_m);
    let mut s = scan.clone();
    for (r, st) in s.ranges_m.iter_mut().zip(s.status.iter_mut()) {
        if *st == RayStatus::Hit && *r >= g.max_range_m {
            *st = RayStatus::MaxRange;
        }
        if *st == RayStatus::MaxRange {
            if clear_no_return {
                *r = g.max_range_m;
            } else {
                *r = f64::NAN;
                *st = RayStatus::Error(0);
            }
        }
    }
    (g, s)
}

/// Builds the grid from `(pose, scan)` pairs and measures how well the endpoints fit it.
pub fn build_map(
    geometry: &ScanGeometry,
    scans: &[(Pose2, Scan)],
    resolution_m: f64,
    max_range_m: f64,
    clear_no_return: bool,
) -> (OccupancyGrid, MapStats) {
    let mut grid = OccupancyGrid::new(resolution_m);
    let clipped: Vec<(ScanGeometry, Scan)> = scans
        .iter()
        .map(|(_, s)| clip(geometry, s, max_range_m, clear_no_return))
        .collect();
    for ((pose, _), (g, s)) in scans.iter().zip(&clipped) {
        grid.integrate(pose, g, s);
    }
    let (mut endpoints, mut near) = (0usize, 0usize);
    for ((pose, _), (g, s)) in scans.iter().zip(&clipped) {
        for (_, p) in s.world_hits(g, pose) {
            endpoints += 1;
            if let Some((c, r)) = grid.cell_of(p) {
                let hit = (-1i64..=1).any(|dr| {
                    (-1i64..=1).any(|dc| {
                        let (cc, rr) = (c as i64 + dc, r as i64 + dr);
                        cc >= 0
                            && rr >= 0
                            && (cc as usize) < grid.width()
                            && (rr as usize) < grid.height()
                            && grid.cell_state(cc as usize, rr as usize) == CellState::Occupied
                    })
                });
                near += usize::from(hit);
            }
        }
    }
    let stats = MapStats {
        scans: scans.len(),
        mapped: scans.len(),
        endpoints,
        near_occupied: near,
    };
    (grid, stats)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A robot in a 4 m x 4 m square room, seen from a few poses with exact ranges: every
    /// endpoint lies on a wall, so every one is within a cell of an occupied cell.
    #[test]
    fn exact_scans_of_a_room_fit_their_map() {
        let g = ScanGeometry::centred(360, 2.0 * PI * 359.0 / 360.0, 0.0, 10.0).unwrap();
        let range = |x: f64, y: f64, a: f64| {
            // Distance from (x, y) along a to the walls x = +-2, y = +-2.
            let (c, s) = (a.cos(), a.sin());
            let tx = if c > 0.0 {
                (2.0 - x) / c
            } else if c < 0.0 {
                (-2.0 - x) / c
            } else {
                f64::INFINITY
            };
            let ty = if s > 0.0 {
                (2.0 - y) / s
            } else if s < 0.0 {
                (-2.0 - y) / s
            } else {
                f64::INFINITY
            };
            tx.min(ty)
        };
        let poses = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.5, -0.3, 1.0),
            Pose2::new(-1.0, 1.0, -2.0),
        ];
        let scans: Vec<(Pose2, Scan)> = poses
            .iter()
            .map(|p| {
                let r: Vec<f64> = (0..g.ray_count)
                    .map(|i| range(p.x_m, p.y_m, p.theta_rad + g.bearing_rad(i)))
                    .collect();
                (*p, Scan::from_ranges(&g, &r, 0.0))
            })
            .collect();
        let (grid, stats) = build_map(&g, &scans, 0.05, 20.0, false);
        assert_eq!(stats.endpoints, 3 * 360);
        assert_eq!(stats.near_occupied, stats.endpoints);
        // The wall is occupied, the middle of the room free.
        // (Endpoints on x = 2 land on either side of the cell border at 2.0.)
        let w = |x| grid.is_occupied(scan_types::WorldPoint::new(x, 0.3));
        assert!(w(1.99) || w(2.01));
        assert!(grid.is_free(scan_types::WorldPoint::new(0.2, 0.2)));
        // Clipping at 1 m: no hit is closer than 1 m here, so none is checked.
        let (_, clipped) = build_map(&g, &scans[..1], 0.05, 1.0, true);
        assert_eq!(clipped.endpoints, 0);
    }
}
