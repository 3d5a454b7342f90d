//! Building a world: its extent and grid, the per-cell shape lists and the solid cells.

use super::geometry::{point_in_polygon, segment_hits_box};
use super::obstacle::aabb_of;
use super::{Bitmap, EMPTY, NO_POLY, Obstacle, Prim, SOLID, World, WorldParts};
use crate::SimError;

/// Farthest a world's geometry may lie from the origin, metres: ample for any building, and
/// far within the range where coordinates keep the precision of a grid cell.
pub const MAX_COORD_M: f64 = 1e6;

impl World {
    /// Builds a world from a bitmap and/or vector obstacles.
    pub fn from_parts(parts: WorldParts) -> Result<World, SimError> {
        for (i, o) in parts.obstacles.iter().enumerate() {
            o.validate(i)?;
        }
        let (lo, hi) = extent(&parts)?;
        let bounds = (lo, hi);
        let (x0, y0, rx, ry, nx, ny) = grid_layout(&parts, lo, hi);
        if nx.saturating_mul(ny) > 64_000_000 {
            return Err(SimError::InvalidWorld(format!(
                "world needs a {nx} x {ny} grid; too large"
            )));
        }
        let mut w = World {
            name: parts.name,
            x0,
            y0,
            rx,
            ry,
            nx,
            ny,
            cells: vec![EMPTY; nx * ny],
            list_start: Vec::new(),
            list_items: Vec::new(),
            dist: Vec::new(),
            planes: Default::default(),
            irx: 1.0 / rx,
            iry: 1.0 / ry,
            prims: Vec::new(),
            polygons: Vec::new(),
            obstacle_count: parts.obstacles.len(),
            bounds,
        };
        let (pairs, interiors, inside_discs) = w.add_obstacles(&parts.obstacles);
        w.build_lists(pairs);
        // Cells entirely inside a disc are solid.
        for idx in inside_discs {
            w.cells[idx] = SOLID;
        }
        w.fill_polygon_interiors(&interiors);
        if let Some(b) = &parts.bitmap {
            w.stamp_bitmap(b);
        }
        w.build_distance();
        tracing::debug!(
            name = %w.name, nx = w.nx, ny = w.ny, prims = w.prims.len(),
            "world built"
        );
        Ok(w)
    }

    /// Adds the shapes of `obstacles` and lists them in the cells they touch: the (cell, prim)
    /// pairs, the polygons (whose interiors are still to fill) and the cells inside discs.
    fn add_obstacles(
        &mut self,
        obstacles: &[Obstacle],
    ) -> (Vec<(u32, u32)>, Vec<usize>, Vec<usize>) {
        // Per-cell primitive lists, gathered as (cell, prim) pairs.
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut interiors: Vec<usize> = Vec::new();
        let mut inside_discs: Vec<usize> = Vec::new();
        for o in obstacles {
            match o {
                Obstacle::Circle { centre, radius } => {
                    let id = self.prims.len() as u32;
                    self.prims.push(Prim::Circle {
                        c: *centre,
                        r: *radius,
                    });
                    self.bucket_circle(*centre, *radius, id, &mut pairs, &mut inside_discs);
                }
                Obstacle::Segment { a, b } => {
                    let id = self.prims.len() as u32;
                    self.prims.push(Prim::Segment {
                        a: *a,
                        b: *b,
                        poly: NO_POLY,
                    });
                    self.bucket_segment(*a, *b, id, &mut pairs);
                }
                _ => {
                    let pts = o.polygon_points().unwrap_or_default();
                    let poly = self.polygons.len() as u32;
                    for i in 0..pts.len() {
                        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                        let id = self.prims.len() as u32;
                        self.prims.push(Prim::Segment { a, b, poly });
                        self.bucket_segment(a, b, id, &mut pairs);
                    }
                    interiors.push(self.polygons.len());
                    self.polygons.push(pts);
                }
            }
        }
        (pairs, interiors, inside_discs)
    }

    /// Marks the mixed cells and builds their CSR shape lists from (cell, prim) pairs.
    fn build_lists(&mut self, mut pairs: Vec<(u32, u32)>) {
        pairs.sort_unstable();
        pairs.dedup();
        // Mark mixed cells and build CSR lists.
        self.list_start.push(0);
        let mut i = 0;
        while i < pairs.len() {
            let cell = pairs[i].0;
            let list = self.list_start.len() as u32 - 1;
            while i < pairs.len() && pairs[i].0 == cell {
                self.list_items.push(pairs[i].1);
                i += 1;
            }
            self.list_start.push(self.list_items.len() as u32);
            self.cells[cell as usize] = list + 2;
        }
    }

    /// Makes solid the cells of polygon interiors: cells without an edge of the polygon whose
    /// centre is inside.
    fn fill_polygon_interiors(&mut self, interiors: &[usize]) {
        for &p in interiors {
            let pts = self.polygons[p].clone();
            let (l, h) = aabb_of(&pts);
            let (cx0, cy0) = self.cell_of(l[0], l[1]);
            let (cx1, cy1) = self.cell_of(h[0], h[1]);
            for cy in cy0.max(0)..=cy1.min(self.ny as i64 - 1) {
                for cx in cx0.max(0)..=cx1.min(self.nx as i64 - 1) {
                    let idx = cy as usize * self.nx + cx as usize;
                    if self.cell_has_edge_of(idx, p as u32) {
                        continue;
                    }
                    let c = [
                        self.x0 + (cx as f64 + 0.5) * self.rx,
                        self.y0 + (cy as f64 + 0.5) * self.ry,
                    ];
                    if point_in_polygon(c, &pts) {
                        self.cells[idx] = SOLID;
                    }
                }
            }
        }
    }

    /// Makes solid the occupied cells of bitmap `b`.
    fn stamp_bitmap(&mut self, b: &Bitmap) {
        let kx = ((b.origin[0] - self.x0) / self.rx).round() as usize;
        let ky = ((b.origin[1] - self.y0) / self.ry).round() as usize;
        for row in 0..b.height {
            for col in 0..b.width {
                if b.occupied[row * b.width + col] {
                    self.cells[(ky + row) * self.nx + kx + col] = SOLID;
                }
            }
        }
    }

    /// The cells of the grid overlapping the box `l`..`h` widened by `e`, with their corners.
    fn cells_in(
        &self,
        l: [f64; 2],
        h: [f64; 2],
        e: f64,
    ) -> impl Iterator<Item = (usize, [f64; 2], [f64; 2])> + '_ {
        let (cx0, cy0) = self.cell_of(l[0] - e, l[1] - e);
        let (cx1, cy1) = self.cell_of(h[0] + e, h[1] + e);
        (cy0.max(0)..=cy1.min(self.ny as i64 - 1)).flat_map(move |cy| {
            (cx0.max(0)..=cx1.min(self.nx as i64 - 1)).map(move |cx| {
                let lo = [self.x0 + cx as f64 * self.rx, self.y0 + cy as f64 * self.ry];
                let hi = [lo[0] + self.rx, lo[1] + self.ry];
                (cy as usize * self.nx + cx as usize, lo, hi)
            })
        })
    }

    /// Lists segment `id` in every cell it touches.
    fn bucket_segment(&self, a: [f64; 2], b: [f64; 2], id: u32, pairs: &mut Vec<(u32, u32)>) {
        // Widen a little so that geometry lying exactly on a cell border is in both cells.
        let e = 1e-9;
        let (l, h) = aabb_of(&[a, b]);
        for (idx, lo, hi) in self.cells_in(l, h, e) {
            if segment_hits_box(a, b, [lo[0] - e, lo[1] - e], [hi[0] + e, hi[1] + e]) {
                pairs.push((idx as u32, id));
            }
        }
    }

    /// Lists circle `id` in every cell its boundary touches; notes the cells entirely inside.
    fn bucket_circle(
        &self,
        c: [f64; 2],
        r: f64,
        id: u32,
        pairs: &mut Vec<(u32, u32)>,
        inside: &mut Vec<usize>,
    ) {
        let e = 1e-9;
        for (idx, lo, hi) in self.cells_in([c[0] - r, c[1] - r], [c[0] + r, c[1] + r], e) {
            let near = |k: usize| (lo[k] - c[k]).max(c[k] - hi[k]).max(0.0);
            let far = |k: usize| (c[k] - lo[k]).abs().max((hi[k] - c[k]).abs());
            if far(0).hypot(far(1)) < r - e {
                inside.push(idx);
            } else if near(0).hypot(near(1)) <= r + e {
                pairs.push((idx as u32, id));
            }
        }
    }

    fn cell_has_edge_of(&self, idx: usize, poly: u32) -> bool {
        let c = self.cells[idx];
        c >= 2
            && self.list(c).iter().any(
                |&p| matches!(self.prims[p as usize], Prim::Segment { poly: q, .. } if q == poly),
            )
    }
}

/// The box holding the bitmap and every obstacle (one empty cell at the origin for an empty
/// world); checks the bitmap.
fn extent(parts: &WorldParts) -> Result<([f64; 2], [f64; 2]), SimError> {
    // Overall extent.
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    let mut grow = |l: [f64; 2], h: [f64; 2]| {
        for k in 0..2 {
            lo[k] = lo[k].min(l[k]);
            hi[k] = hi[k].max(h[k]);
        }
    };
    if let Some(b) = &parts.bitmap {
        if b.width == 0 || b.height == 0 || b.occupied.len() != b.width * b.height {
            return Err(SimError::InvalidWorld("bitmap has no cells".into()));
        }
        if !(b.cell_w_m > 0.0
            && b.cell_h_m > 0.0
            && b.cell_w_m.is_finite()
            && b.cell_h_m.is_finite())
        {
            return Err(SimError::InvalidWorld(
                "bitmap cell size must be > 0".into(),
            ));
        }
        grow(
            b.origin,
            [
                b.origin[0] + b.width as f64 * b.cell_w_m,
                b.origin[1] + b.height as f64 * b.cell_h_m,
            ],
        );
    }
    for o in &parts.obstacles {
        let (l, h) = o.aabb();
        grow(l, h);
    }
    if !lo[0].is_finite() {
        // An empty world: one empty cell at the origin.
        lo = [-0.5, -0.5];
        hi = [0.5, 0.5];
    }
    if lo.iter().chain(&hi).any(|v| v.abs() > MAX_COORD_M) {
        return Err(SimError::InvalidWorld(format!(
            "the world spans x {} .. {} m, y {} .. {} m; it must lie within {MAX_COORD_M:e} m \
             of the origin",
            lo[0], hi[0], lo[1], hi[1]
        )));
    }
    Ok((lo, hi))
}

/// The grid for `parts` over the extent `lo`..`hi`: origin, cell size and cell counts
/// (x0, y0, rx, ry, nx, ny). A bitmap's cells are grid cells.
fn grid_layout(
    parts: &WorldParts,
    lo: [f64; 2],
    hi: [f64; 2],
) -> (f64, f64, f64, f64, usize, usize) {
    match &parts.bitmap {
        Some(b) => {
            let (rx, ry) = (b.cell_w_m, b.cell_h_m);
            let kx0 = ((b.origin[0] - lo[0]) / rx).ceil().max(0.0) as usize + 1;
            let ky0 = ((b.origin[1] - lo[1]) / ry).ceil().max(0.0) as usize + 1;
            let x0 = b.origin[0] - kx0 as f64 * rx;
            let y0 = b.origin[1] - ky0 as f64 * ry;
            let nx = ((hi[0] - x0) / rx).ceil() as usize + 1;
            let ny = ((hi[1] - y0) / ry).ceil() as usize + 1;
            (x0, y0, rx, ry, nx, ny)
        }
        None => {
            let (w, h) = (hi[0] - lo[0], hi[1] - lo[1]);
            let res = parts
                .cell_size_m
                .filter(|r| *r > 0.0 && r.is_finite())
                .unwrap_or_else(|| 0.05f64.max((w * h / 1.0e6).sqrt()));
            let x0 = lo[0] - res;
            let y0 = lo[1] - res;
            let nx = (w / res).ceil() as usize + 3;
            let ny = (h / res).ceil() as usize + 3;
            (x0, y0, res, res, nx, ny)
        }
    }
}
