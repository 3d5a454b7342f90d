//! Questions about the world besides ray casts: clearance, collisions, occupancy, true
//! ranges and rasterising.

use scan_types::{Pose2, WorldPoint};

use super::geometry::{point_in_polygon, point_prim_distance, segment_hits_box};
use super::{Bitmap, EMPTY, NO_POLY, Prim, SOLID, World};

impl World {
    /// Distance from `p` to the nearest obstacle, or `search_m` if none lies closer.
    /// Zero inside an obstacle.
    pub fn clearance(&self, p: WorldPoint, search_m: f64) -> f64 {
        let q = [p.x_m(), p.y_m()];
        if !(q[0].is_finite() && q[1].is_finite()) {
            return 0.0;
        }
        let (cx, cy) = self.cell_of(q[0], q[1]);
        let inside = cx >= 0 && cy >= 0 && cx < self.nx as i64 && cy < self.ny as i64;
        if inside {
            let idx = cy as usize * self.nx + cx as usize;
            let d = self.dist[idx] as f64;
            if (d - 1.0) * self.rx.min(self.ry) >= search_m {
                return search_m;
            }
            let cell = self.cells[idx];
            if cell == SOLID {
                return 0.0;
            }
            if cell != EMPTY {
                for &pi in self.list(cell) {
                    if let Prim::Segment { poly, .. } = self.prims[pi as usize]
                        && poly != NO_POLY
                        && point_in_polygon(q, &self.polygons[poly as usize])
                    {
                        return 0.0;
                    }
                }
            }
        }
        let mut best = search_m;
        let (ax, ay) = self.cell_of(q[0] - search_m, q[1] - search_m);
        let (bx, by) = self.cell_of(q[0] + search_m, q[1] + search_m);
        for y in ay.max(0)..=by.min(self.ny as i64 - 1) {
            for x in ax.max(0)..=bx.min(self.nx as i64 - 1) {
                let idx = y as usize * self.nx + x as usize;
                let cell = self.cells[idx];
                if cell == EMPTY {
                    continue;
                }
                let lx = self.x0 + x as f64 * self.rx;
                let ly = self.y0 + y as f64 * self.ry;
                let dx = (lx - q[0]).max(q[0] - lx - self.rx).max(0.0);
                let dy = (ly - q[1]).max(q[1] - ly - self.ry).max(0.0);
                let box_d = dx.hypot(dy);
                if box_d >= best {
                    continue;
                }
                if cell == SOLID {
                    best = box_d;
                } else {
                    for &pi in self.list(cell) {
                        best = best.min(point_prim_distance(q, &self.prims[pi as usize]));
                    }
                }
            }
        }
        best
    }

    /// True when a disc of `radius_m` centred at `centre` overlaps an obstacle.
    pub fn disc_collides(&self, centre: WorldPoint, radius_m: f64) -> bool {
        self.clearance(centre, radius_m + 1e-6) < radius_m
    }

    /// True when the point lies inside an obstacle (or on its boundary).
    pub fn is_occupied(&self, p: WorldPoint) -> bool {
        self.clearance(p, 1e-9) < 1e-9
    }

    /// Noise-free ranges of every ray of `geometry` seen from `pose`; `None` for rays that see
    /// nothing within the maximum range.
    pub fn true_ranges(
        &self,
        pose: &Pose2,
        geometry: &scan_types::ScanGeometry,
    ) -> Vec<Option<f64>> {
        (0..geometry.ray_count)
            .map(|i| {
                let a = pose.theta_rad + geometry.bearing_rad(i);
                self.raycast(pose.position(), a, geometry.max_range_m)
            })
            .collect()
    }

    /// Rasterises the world to a bitmap of `cell_m` cells covering `lo`..`hi`:
    /// a cell is occupied when its centre lies inside an obstacle or a wall passes through it.
    pub fn rasterise(&self, lo: [f64; 2], hi: [f64; 2], cell_m: f64) -> Bitmap {
        let width = (((hi[0] - lo[0]) / cell_m).round() as usize).max(1);
        let height = (((hi[1] - lo[1]) / cell_m).round() as usize).max(1);
        let mut occupied = vec![false; width * height];
        for row in 0..height {
            for col in 0..width {
                let c = [
                    lo[0] + (col as f64 + 0.5) * cell_m,
                    lo[1] + (row as f64 + 0.5) * cell_m,
                ];
                // Thin walls: occupied if within half a cell (chessboard) of the cell centre.
                let clear = self.clearance(WorldPoint::new(c[0], c[1]), cell_m);
                let centre_in = clear == 0.0;
                let wall = clear < cell_m * 0.5 && self.segment_crosses_cell(c, cell_m);
                occupied[row * width + col] = centre_in || wall;
            }
        }
        Bitmap {
            width,
            height,
            cell_w_m: cell_m,
            cell_h_m: cell_m,
            origin: lo,
            occupied,
        }
    }

    fn segment_crosses_cell(&self, c: [f64; 2], cell_m: f64) -> bool {
        let h = cell_m / 2.0;
        let (cx, cy) = self.cell_of(c[0], c[1]);
        for y in (cy - 1).max(0)..=(cy + 1).min(self.ny as i64 - 1) {
            for x in (cx - 1).max(0)..=(cx + 1).min(self.nx as i64 - 1) {
                let cell = self.cells[y as usize * self.nx + x as usize];
                if cell < 2 {
                    continue;
                }
                for &pi in self.list(cell) {
                    if let Prim::Segment { a, b, poly } = self.prims[pi as usize]
                        && poly == NO_POLY
                        && segment_hits_box(a, b, [c[0] - h, c[1] - h], [c[0] + h, c[1] + h])
                    {
                        return true;
                    }
                }
            }
        }
        false
    }
}
