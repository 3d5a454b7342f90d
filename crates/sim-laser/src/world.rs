//! The world: obstacles as grid cells (from bitmaps) and exact shapes (segments, circles,
//! polygons), with a uniform-grid index and a chessboard distance field for fast exact ray casts.

use scan_types::{Pose2, WorldPoint};

use crate::SimError;

/// An obstacle of a vector world, in world coordinates (metres, radians).
#[derive(Debug, Clone, PartialEq)]
pub enum Obstacle {
    /// A solid polygon (at least three vertices, either orientation, simple).
    Polygon {
        /// Vertices in order; the last connects back to the first.
        points: Vec<[f64; 2]>,
    },
    /// A solid rectangle, `size` = (width, height), rotated by `angle_rad` about its centre.
    Box {
        /// Centre, metres.
        centre: [f64; 2],
        /// Width and height, metres.
        size: [f64; 2],
        /// Rotation, radians counter-clockwise.
        angle_rad: f64,
    },
    /// A solid disc.
    Circle {
        /// Centre, metres.
        centre: [f64; 2],
        /// Radius, metres.
        radius: f64,
    },
    /// A wall of zero thickness between two points.
    Segment {
        /// One end.
        a: [f64; 2],
        /// The other end.
        b: [f64; 2],
    },
}

impl Obstacle {
    /// The polygon vertices of a box or polygon obstacle (`None` for circles and segments).
    pub fn polygon_points(&self) -> Option<Vec<[f64; 2]>> {
        match self {
            Obstacle::Polygon { points } => Some(points.clone()),
            Obstacle::Box {
                centre,
                size,
                angle_rad,
            } => {
                let (s, c) = angle_rad.sin_cos();
                let (hw, hh) = (size[0] / 2.0, size[1] / 2.0);
                Some(
                    [(-hw, -hh), (hw, -hh), (hw, hh), (-hw, hh)]
                        .iter()
                        .map(|&(x, y)| [centre[0] + c * x - s * y, centre[1] + s * x + c * y])
                        .collect(),
                )
            }
            _ => None,
        }
    }

    fn aabb(&self) -> ([f64; 2], [f64; 2]) {
        match self {
            Obstacle::Circle { centre, radius } => (
                [centre[0] - radius, centre[1] - radius],
                [centre[0] + radius, centre[1] + radius],
            ),
            Obstacle::Segment { a, b } => (
                [a[0].min(b[0]), a[1].min(b[1])],
                [a[0].max(b[0]), a[1].max(b[1])],
            ),
            _ => aabb_of(&self.polygon_points().unwrap_or_default()),
        }
    }

    pub(crate) fn validate(&self, index: usize) -> Result<(), SimError> {
        let bad = |m: &str| Err(SimError::InvalidWorld(format!("obstacle {index}: {m}")));
        let finite = |p: &[f64; 2]| p[0].is_finite() && p[1].is_finite();
        match self {
            Obstacle::Polygon { points } => {
                if points.len() < 3 {
                    return bad("a polygon needs at least 3 points");
                }
                if !points.iter().all(finite) {
                    return bad("polygon point is not finite");
                }
            }
            Obstacle::Box {
                centre,
                size,
                angle_rad,
            } => {
                if !finite(centre) || !angle_rad.is_finite() {
                    return bad("box centre or angle is not finite");
                }
                if !(size[0] > 0.0 && size[1] > 0.0 && size[0].is_finite() && size[1].is_finite()) {
                    return bad("box size must be finite and > 0");
                }
            }
            Obstacle::Circle { centre, radius } => {
                if !finite(centre) {
                    return bad("circle centre is not finite");
                }
                if !(radius.is_finite() && *radius > 0.0) {
                    return bad("circle radius must be finite and > 0");
                }
            }
            Obstacle::Segment { a, b } => {
                if !finite(a) || !finite(b) {
                    return bad("segment end is not finite");
                }
            }
        }
        Ok(())
    }
}

fn aabb_of(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// An occupancy bitmap placed in the world: `occupied[row * width + col]`, row 0 at the
/// bottom (lowest y), each cell `cell_w_m` x `cell_h_m`, cell (0, 0)'s lower-left corner at `origin`.
#[derive(Debug, Clone, PartialEq)]
pub struct Bitmap {
    /// Columns.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// Cell width, metres.
    pub cell_w_m: f64,
    /// Cell height, metres.
    pub cell_h_m: f64,
    /// World position of the lower-left corner of cell (0, 0).
    pub origin: [f64; 2],
    /// Occupancy, row-major from the bottom row.
    pub occupied: Vec<bool>,
}

/// Primitive the ray caster tests exactly.
#[derive(Debug, Clone, Copy)]
enum Prim {
    Segment { a: [f64; 2], b: [f64; 2], poly: u32 },
    Circle { c: [f64; 2], r: f64 },
}

const NO_POLY: u32 = u32::MAX;
const EMPTY: u32 = 0;
const SOLID: u32 = 1;

/// The simulated world: where obstacles are. Cheap to share with `Arc`.
///
/// ```
/// use sim_laser::World;
/// use scan_types::WorldPoint;
/// let w = World::paper();
/// let (lo, hi) = w.bounds();
/// assert!((lo.x_m() + 5.0).abs() < 1e-9 && (hi.y_m() - 5.0).abs() < 1e-9);
/// // From the paper's start, straight down, the boundary wall's inner face is 0.72 m away.
/// let r = w.raycast(WorldPoint::new(-3.92, -4.26), -std::f64::consts::FRAC_PI_2, 4.0).unwrap();
/// assert!((r - 0.72).abs() < 1e-9, "{r}");
/// ```
#[derive(Debug, Clone)]
pub struct World {
    name: String,
    x0: f64,
    y0: f64,
    rx: f64,
    ry: f64,
    nx: usize,
    ny: usize,
    cells: Vec<u32>,
    list_start: Vec<u32>,
    list_items: Vec<u32>,
    dist: Vec<u16>,
    /// For the ray caster, per cell and per quadrant of travel (`4 * cell + q`, `q` = bit 0: +x,
    /// bit 1: +y): the side, in cells, of the largest empty square with this cell at its corner
    /// extending toward that quadrant (capped at 255); 0 for a non-empty cell.
    quad: Vec<u8>,
    prims: Vec<Prim>,
    polygons: Vec<Vec<[f64; 2]>>,
    obstacle_count: usize,
    bounds: ([f64; 2], [f64; 2]),
}

/// Everything needed to build a [`World`]: an optional bitmap and vector obstacles.
#[derive(Debug, Clone, Default)]
pub struct WorldParts {
    /// A name for messages.
    pub name: String,
    /// Occupied cells of a bitmap, if any.
    pub bitmap: Option<Bitmap>,
    /// Vector obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Grid cell size for vector-only worlds (metres); `None` picks one from the extent.
    pub cell_size_m: Option<f64>,
}

impl World {
    /// Builds a world from a bitmap and/or vector obstacles.
    pub fn from_parts(parts: WorldParts) -> Result<World, SimError> {
        for (i, o) in parts.obstacles.iter().enumerate() {
            o.validate(i)?;
        }
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
        let bounds = (lo, hi);
        let (x0, y0, rx, ry, nx, ny) = match &parts.bitmap {
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
        };
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
            quad: Vec::new(),
            prims: Vec::new(),
            polygons: Vec::new(),
            obstacle_count: parts.obstacles.len(),
            bounds,
        };
        // Per-cell primitive lists, gathered as (cell, prim) pairs.
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut interiors: Vec<usize> = Vec::new();
        for o in &parts.obstacles {
            match o {
                Obstacle::Circle { centre, radius } => {
                    let id = w.prims.len() as u32;
                    w.prims.push(Prim::Circle {
                        c: *centre,
                        r: *radius,
                    });
                    w.bucket(o.aabb(), id, &mut pairs);
                }
                Obstacle::Segment { a, b } => {
                    let id = w.prims.len() as u32;
                    w.prims.push(Prim::Segment {
                        a: *a,
                        b: *b,
                        poly: NO_POLY,
                    });
                    w.bucket(o.aabb(), id, &mut pairs);
                }
                _ => {
                    let pts = o.polygon_points().unwrap_or_default();
                    let poly = w.polygons.len() as u32;
                    for i in 0..pts.len() {
                        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                        let id = w.prims.len() as u32;
                        w.prims.push(Prim::Segment { a, b, poly });
                        w.bucket(aabb_of(&[a, b]), id, &mut pairs);
                    }
                    interiors.push(w.polygons.len());
                    w.polygons.push(pts);
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        // Mark mixed cells and build CSR lists.
        w.list_start.push(0);
        let mut i = 0;
        while i < pairs.len() {
            let cell = pairs[i].0;
            let list = w.list_start.len() as u32 - 1;
            while i < pairs.len() && pairs[i].0 == cell {
                w.list_items.push(pairs[i].1);
                i += 1;
            }
            w.list_start.push(w.list_items.len() as u32);
            w.cells[cell as usize] = list + 2;
        }
        // Polygon interiors: cells without an edge of the polygon whose centre is inside.
        for &p in &interiors {
            let pts = w.polygons[p].clone();
            let (l, h) = aabb_of(&pts);
            let (cx0, cy0) = w.cell_of(l[0], l[1]);
            let (cx1, cy1) = w.cell_of(h[0], h[1]);
            for cy in cy0.max(0)..=cy1.min(w.ny as i64 - 1) {
                for cx in cx0.max(0)..=cx1.min(w.nx as i64 - 1) {
                    let idx = cy as usize * w.nx + cx as usize;
                    if w.cell_has_edge_of(idx, p as u32) {
                        continue;
                    }
                    let c = [
                        w.x0 + (cx as f64 + 0.5) * w.rx,
                        w.y0 + (cy as f64 + 0.5) * w.ry,
                    ];
                    if point_in_polygon(c, &pts) {
                        w.cells[idx] = SOLID;
                    }
                }
            }
        }
        if let Some(b) = &parts.bitmap {
            let kx = ((b.origin[0] - w.x0) / w.rx).round() as usize;
            let ky = ((b.origin[1] - w.y0) / w.ry).round() as usize;
            for row in 0..b.height {
                for col in 0..b.width {
                    if b.occupied[row * b.width + col] {
                        w.cells[(ky + row) * w.nx + kx + col] = SOLID;
                    }
                }
            }
        }
        w.build_distance();
        tracing::debug!(
            name = %w.name, nx = w.nx, ny = w.ny, prims = w.prims.len(),
            "world built"
        );
        Ok(w)
    }

    fn bucket(&self, (l, h): ([f64; 2], [f64; 2]), id: u32, pairs: &mut Vec<(u32, u32)>) {
        // Widen a little so that geometry lying exactly on a cell border is in both cells.
        let e = 1e-9;
        let (cx0, cy0) = self.cell_of(l[0] - e, l[1] - e);
        let (cx1, cy1) = self.cell_of(h[0] + e, h[1] + e);
        for cy in cy0.max(0)..=cy1.min(self.ny as i64 - 1) {
            for cx in cx0.max(0)..=cx1.min(self.nx as i64 - 1) {
                pairs.push(((cy as usize * self.nx + cx as usize) as u32, id));
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

    fn list(&self, cell: u32) -> &[u32] {
        let l = (cell - 2) as usize;
        &self.list_items[self.list_start[l] as usize..self.list_start[l + 1] as usize]
    }

    fn cell_of(&self, x: f64, y: f64) -> (i64, i64) {
        (
            ((x - self.x0) / self.rx).floor() as i64,
            ((y - self.y0) / self.ry).floor() as i64,
        )
    }

    /// Chessboard distance (in cells) from each cell to the nearest non-empty cell.
    fn build_distance(&mut self) {
        let (nx, ny) = (self.nx, self.ny);
        let inf = u16::MAX as u32;
        let mut d: Vec<u32> = self
            .cells
            .iter()
            .map(|&c| if c == EMPTY { inf } else { 0 })
            .collect();
        for y in 0..ny {
            for x in 0..nx {
                let i = y * nx + x;
                let mut v = d[i];
                if x > 0 {
                    v = v.min(d[i - 1] + 1);
                }
                if y > 0 {
                    v = v.min(d[i - nx] + 1);
                    if x > 0 {
                        v = v.min(d[i - nx - 1] + 1);
                    }
                    if x + 1 < nx {
                        v = v.min(d[i - nx + 1] + 1);
                    }
                }
                d[i] = v.min(inf);
            }
        }
        for y in (0..ny).rev() {
            for x in (0..nx).rev() {
                let i = y * nx + x;
                let mut v = d[i];
                if x + 1 < nx {
                    v = v.min(d[i + 1] + 1);
                }
                if y + 1 < ny {
                    v = v.min(d[i + nx] + 1);
                    if x + 1 < nx {
                        v = v.min(d[i + nx + 1] + 1);
                    }
                    if x > 0 {
                        v = v.min(d[i + nx - 1] + 1);
                    }
                }
                d[i] = v.min(inf);
            }
        }
        self.dist = d.into_iter().map(|v| v as u16).collect();
        self.quad = vec![0u8; 4 * nx * ny];
        for q in 0..4usize {
            let (px, py) = (q & 1 == 1, q & 2 == 2);
            let xs: Vec<usize> = if px {
                (0..nx).rev().collect()
            } else {
                (0..nx).collect()
            };
            let ys: Vec<usize> = if py {
                (0..ny).rev().collect()
            } else {
                (0..ny).collect()
            };
            let step = |v: usize, pos: bool, n: usize| -> Option<usize> {
                if pos {
                    (v + 1 < n).then_some(v + 1)
                } else {
                    v.checked_sub(1)
                }
            };
            for &y in &ys {
                for &x in &xs {
                    let i = y * nx + x;
                    if self.cells[i] != EMPTY {
                        continue;
                    }
                    let get = |xx: Option<usize>, yy: Option<usize>| match (xx, yy) {
                        (Some(a), Some(b)) => self.quad[4 * (b * nx + a) + q] as u32,
                        _ => 255,
                    };
                    let (x2, y2) = (step(x, px, nx), step(y, py, ny));
                    let m = get(x2, Some(y)).min(get(Some(x), y2)).min(get(x2, y2));
                    self.quad[4 * i + q] = (m + 1).min(255) as u8;
                }
            }
        }
    }

    /// The world's name (file stem or "paper").
    pub fn name(&self) -> &str {
        &self.name
    }

    /// Number of vector obstacles (0 for a pure bitmap world).
    pub fn obstacle_count(&self) -> usize {
        self.obstacle_count
    }

    /// Lower-left and upper-right corners of the box holding every obstacle.
    pub fn bounds(&self) -> (WorldPoint, WorldPoint) {
        let (l, h) = self.bounds;
        (WorldPoint::new(l[0], l[1]), WorldPoint::new(h[0], h[1]))
    }

    /// Distance from `origin` along the direction `angle_rad` to the first obstacle, if one lies
    /// within `max_range_m`. Exact against the geometry (bitmap cells are solid squares).
    pub fn raycast(&self, origin: WorldPoint, angle_rad: f64, max_range_m: f64) -> Option<f64> {
        let (s, c) = angle_rad.sin_cos();
        self.raycast_dir([origin.x_m(), origin.y_m()], [c, s], max_range_m)
    }

    /// Ray cast with a unit direction vector.
    pub(crate) fn raycast_dir(&self, o: [f64; 2], d: [f64; 2], max_range_m: f64) -> Option<f64> {
        if !(o[0].is_finite() && o[1].is_finite() && max_range_m.is_finite() && max_range_m >= 0.0)
        {
            return None;
        }
        // Work in cell units: cell coordinate = oc + t * dc.
        let (irx, iry) = (1.0 / self.rx, 1.0 / self.ry);
        let oc = [(o[0] - self.x0) * irx, (o[1] - self.y0) * iry];
        let dc = [d[0] * irx, d[1] * iry];
        let idc = [1.0 / dc[0], 1.0 / dc[1]];
        let (nx, ny) = (self.nx as i64, self.ny as i64);
        // Clip against the grid box [0, nx] x [0, ny].
        let (mut t0, mut t1) = (0.0f64, max_range_m);
        for (oo, ii, hi) in [(oc[0], idc[0], nx as f64), (oc[1], idc[1], ny as f64)] {
            if ii.is_infinite() {
                if oo < 0.0 || oo >= hi {
                    return None;
                }
            } else {
                let (a, b) = (-oo * ii, (hi - oo) * ii);
                t0 = t0.max(a.min(b));
                t1 = t1.min(a.max(b));
            }
        }
        if t0 > t1 {
            return None;
        }
        let mut t = t0;
        let mut best = f64::INFINITY;
        let (sx, sy) = (d[0] > 0.0, d[1] > 0.0);
        let quadrant = usize::from(sx) | (usize::from(sy) << 1);
        // The cell holding coordinate f on a ray moving with slope `dcs`: on a cell border, the
        // cell ahead.
        // Coordinates within rounding of the grid's edge are clamped into it (the ray enters the
        // grid exactly on its edge).
        let cell = |f: f64, dcs: f64, n: i64| {
            // Truncation with a correction: `floor`/`ceil` are library calls on baseline x86-64.
            let i = f as i64;
            let c = if dcs < 0.0 {
                // ceil(f) - 1
                if (i as f64) < f { i } else { i - 1 }
            } else if (i as f64) > f {
                i - 1
            } else {
                i
            };
            if (c < 0 && f > -1e-7) || (c >= n && f < n as f64 + 1e-7) {
                c.clamp(0, n - 1)
            } else {
                c
            }
        };
        loop {
            let cx = cell(oc[0] + t * dc[0], dc[0], nx);
            let cy = cell(oc[1] + t * dc[1], dc[1], ny);
            if cx < 0 || cy < 0 || cx >= nx || cy >= ny {
                break;
            }
            let idx = cy as usize * self.nx + cx as usize;
            let k = self.quad[4 * idx + quadrant];
            let k = if k == 0 {
                if self.cells[idx] == SOLID {
                    return (t <= max_range_m).then_some(t);
                }
                1
            } else {
                k as i64
            };
            // Exit of the empty square of k x k cells from this cell toward the ray's quadrant.
            let bx = if sx { cx + k } else { cx - k + 1 } as f64;
            let by = if sy { cy + k } else { cy - k + 1 } as f64;
            let ex = if dc[0] != 0.0 {
                (bx - oc[0]) * idc[0]
            } else {
                f64::INFINITY
            };
            let ey = if dc[1] != 0.0 {
                (by - oc[1]) * idc[1]
            } else {
                f64::INFINITY
            };
            let exit = ex.min(ey);
            if self.quad[4 * idx + quadrant] == 0 {
                for &p in self.list(self.cells[idx]) {
                    if let Some(th) = ray_prim(o, d, &self.prims[p as usize]) {
                        best = best.min(th);
                    }
                }
                if best <= exit {
                    return (best <= max_range_m).then_some(best);
                }
            }
            if exit > t1 {
                break;
            }
            // Always progress, even when rounding puts the exit at or before t.
            t = exit.max(t + 1e-12 + t * 1e-15);
        }
        (best <= max_range_m).then_some(best)
    }

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

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

fn ray_prim(o: [f64; 2], d: [f64; 2], p: &Prim) -> Option<f64> {
    match *p {
        Prim::Segment { a, b, .. } => {
            let e = [b[0] - a[0], b[1] - a[1]];
            let den = cross(d, e);
            if den == 0.0 {
                return None;
            }
            let ao = [a[0] - o[0], a[1] - o[1]];
            let t = cross(ao, e) / den;
            let s = cross(ao, d) / den;
            (t >= 0.0 && (0.0..=1.0).contains(&s)).then_some(t)
        }
        Prim::Circle { c, r } => {
            let oc = [o[0] - c[0], o[1] - c[1]];
            let b = d[0] * oc[0] + d[1] * oc[1];
            let cc = oc[0] * oc[0] + oc[1] * oc[1] - r * r;
            let disc = b * b - cc;
            if disc < 0.0 {
                return None;
            }
            let sq = disc.sqrt();
            let t_near = -b - sq;
            if t_near >= 0.0 {
                Some(t_near)
            } else if cc <= 0.0 {
                Some(0.0) // inside the disc
            } else {
                None
            }
        }
    }
}

fn point_prim_distance(q: [f64; 2], p: &Prim) -> f64 {
    match *p {
        Prim::Segment { a, b, .. } => point_segment_distance(q, a, b),
        Prim::Circle { c, r } => ((q[0] - c[0]).hypot(q[1] - c[1]) - r).max(0.0),
    }
}

pub(crate) fn point_segment_distance(q: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let e = [b[0] - a[0], b[1] - a[1]];
    let l2 = e[0] * e[0] + e[1] * e[1];
    let t = if l2 > 0.0 {
        (((q[0] - a[0]) * e[0] + (q[1] - a[1]) * e[1]) / l2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    (q[0] - a[0] - t * e[0]).hypot(q[1] - a[1] - t * e[1])
}

pub(crate) fn point_in_polygon(q: [f64; 2], pts: &[[f64; 2]]) -> bool {
    let mut inside = false;
    let n = pts.len();
    let mut j = n - 1;
    for i in 0..n {
        let (a, b) = (pts[i], pts[j]);
        if (a[1] > q[1]) != (b[1] > q[1]) {
            let x = a[0] + (q[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]);
            if q[0] < x {
                inside = !inside;
            }
        }
        j = i;
    }
    inside
}

fn segment_hits_box(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> bool {
    // Liang-Barsky clip of the segment against the box.
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for k in 0..2 {
        if d[k] == 0.0 {
            if a[k] < lo[k] || a[k] > hi[k] {
                return false;
            }
        } else {
            let (u, v) = ((lo[k] - a[k]) / d[k], (hi[k] - a[k]) / d[k]);
            t0 = t0.max(u.min(v));
            t1 = t1.min(u.max(v));
        }
    }
    t0 <= t1
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_abs_diff_eq;
    use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};

    fn vec_world(obstacles: Vec<Obstacle>) -> World {
        World::from_parts(WorldParts {
            name: "t".into(),
            obstacles,
            ..Default::default()
        })
        .unwrap()
    }

    #[test]
    fn wall_straight_and_oblique() {
        // A wall x = 2 from y = -5 to 5; robot at the origin.
        let w = vec_world(vec![Obstacle::Segment {
            a: [2.0, -5.0],
            b: [2.0, 5.0],
        }]);
        let o = WorldPoint::new(0.0, 0.0);
        assert_abs_diff_eq!(w.raycast(o, 0.0, 10.0).unwrap(), 2.0, epsilon = 1e-12);
        // At 60 deg the distance is 2 / cos 60 = 4.
        assert_abs_diff_eq!(w.raycast(o, PI / 3.0, 10.0).unwrap(), 4.0, epsilon = 1e-9);
        assert_eq!(w.raycast(o, PI / 3.0, 3.9), None);
        assert_eq!(w.raycast(o, PI, 100.0), None);
        assert_eq!(w.raycast(o, FRAC_PI_2, 100.0), None);
    }

    #[test]
    fn corner_of_a_box() {
        // Box [1,3] x [1,3]; from the origin at 45 deg the ray meets the corner (1,1).
        let w = vec_world(vec![Obstacle::Box {
            centre: [2.0, 2.0],
            size: [2.0, 2.0],
            angle_rad: 0.0,
        }]);
        let o = WorldPoint::new(0.0, 0.0);
        assert_abs_diff_eq!(
            w.raycast(o, FRAC_PI_4, 10.0).unwrap(),
            2f64.sqrt(),
            epsilon = 1e-9
        );
        // From (0, 2) heading +x: the face x = 1.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(0.0, 2.0), 0.0, 10.0).unwrap(),
            1.0,
            epsilon = 1e-12
        );
        assert!(w.is_occupied(WorldPoint::new(2.0, 2.0)));
        assert!(!w.is_occupied(WorldPoint::new(0.5, 2.0)));
        assert_abs_diff_eq!(
            w.clearance(WorldPoint::new(0.0, 0.0), 5.0),
            2f64.sqrt(),
            epsilon = 1e-12
        );
    }

    #[test]
    fn circle_tangent_and_centre() {
        // Circle at (5, 0) radius 1: straight ahead 4 m; tangent ray at asin(1/5).
        let w = vec_world(vec![Obstacle::Circle {
            centre: [5.0, 0.0],
            radius: 1.0,
        }]);
        let o = WorldPoint::new(0.0, 0.0);
        assert_abs_diff_eq!(w.raycast(o, 0.0, 10.0).unwrap(), 4.0, epsilon = 1e-12);
        let a = (1.0f64 / 5.0).asin();
        // Just inside the tangent: hits near the tangent distance sqrt(24).
        let r = w.raycast(o, a - 1e-7, 10.0).unwrap();
        assert_abs_diff_eq!(r, 24f64.sqrt(), epsilon = 2e-3);
        assert_eq!(w.raycast(o, a + 1e-6, 10.0), None);
        assert!(w.disc_collides(WorldPoint::new(3.75, 0.0), 0.3));
        assert!(!w.disc_collides(WorldPoint::new(3.65, 0.0), 0.3));
    }

    #[test]
    fn bitmap_cells_are_solid_squares() {
        // 4 x 4 bitmap of 0.5 m cells at origin (0,0); cell (col 2, row 1) occupied.
        let mut occ = vec![false; 16];
        occ[4 + 2] = true;
        let w = World::from_parts(WorldParts {
            name: "b".into(),
            bitmap: Some(Bitmap {
                width: 4,
                height: 4,
                cell_w_m: 0.5,
                cell_h_m: 0.5,
                origin: [0.0, 0.0],
                occupied: occ,
            }),
            ..Default::default()
        })
        .unwrap();
        // Cell covers x in [1, 1.5], y in [0.5, 1]. From (0, 0.75) heading +x: 1.0.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(0.0, 0.75), 0.0, 10.0).unwrap(),
            1.0,
            epsilon = 1e-12
        );
        // From (1.25, 3) heading -y: top face y = 1 at 2.0.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(1.25, 3.0), -FRAC_PI_2, 10.0)
                .unwrap(),
            2.0,
            epsilon = 1e-12
        );
        // From (0.25, 0) at 45 deg: y = x - 0.25 enters the left face at (1, 0.75).
        let r = w.raycast(WorldPoint::new(0.25, 0.0), FRAC_PI_4, 10.0);
        assert_abs_diff_eq!(r.unwrap(), 0.75 * 2f64.sqrt(), epsilon = 1e-9);
        // Behind the bitmap (outside the grid) heading away: nothing.
        assert_eq!(w.raycast(WorldPoint::new(-1.0, 0.75), PI, 10.0), None);
        // From outside the grid heading in.
        assert_abs_diff_eq!(
            w.raycast(WorldPoint::new(-3.0, 0.75), 0.0, 10.0).unwrap(),
            4.0,
            epsilon = 1e-12
        );
    }
}
