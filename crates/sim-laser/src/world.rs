//! The world: obstacles as grid cells (from bitmaps) and exact shapes (segments, circles,
//! polygons), with a uniform-grid index, a chessboard distance field and per-quadrant empty squares
//! for fast exact ray casts.

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
/// Plane value of a cell holding shapes.
const LIST: u8 = 255;
/// A lane of the ray caster with no ray.
const IDLE: usize = usize::MAX;

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
    /// For the ray caster, one plane per quadrant of travel `q` (bit 0: +x, bit 1: +y), indexed in
    /// that quadrant's mirrored cell coordinates (see [`Ray`]): the side, in cells, of the largest
    /// empty square with this cell at its corner extending toward the quadrant (at most 254);
    /// 0 for a solid cell, [`LIST`] for a cell holding shapes.
    planes: [Vec<u8>; 4],
    /// 1 / cell width and 1 / cell height.
    irx: f64,
    iry: f64,
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
            planes: Default::default(),
            irx: 1.0 / rx,
            iry: 1.0 / ry,
            prims: Vec::new(),
            polygons: Vec::new(),
            obstacle_count: parts.obstacles.len(),
            bounds,
        };
        // Per-cell primitive lists, gathered as (cell, prim) pairs.
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        let mut interiors: Vec<usize> = Vec::new();
        let mut inside_discs: Vec<usize> = Vec::new();
        for o in &parts.obstacles {
            match o {
                Obstacle::Circle { centre, radius } => {
                    let id = w.prims.len() as u32;
                    w.prims.push(Prim::Circle {
                        c: *centre,
                        r: *radius,
                    });
                    w.bucket_circle(*centre, *radius, id, &mut pairs, &mut inside_discs);
                }
                Obstacle::Segment { a, b } => {
                    let id = w.prims.len() as u32;
                    w.prims.push(Prim::Segment {
                        a: *a,
                        b: *b,
                        poly: NO_POLY,
                    });
                    w.bucket_segment(*a, *b, id, &mut pairs);
                }
                _ => {
                    let pts = o.polygon_points().unwrap_or_default();
                    let poly = w.polygons.len() as u32;
                    for i in 0..pts.len() {
                        let (a, b) = (pts[i], pts[(i + 1) % pts.len()]);
                        let id = w.prims.len() as u32;
                        w.prims.push(Prim::Segment { a, b, poly });
                        w.bucket_segment(a, b, id, &mut pairs);
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
        // Cells entirely inside a disc are solid.
        for idx in inside_discs {
            w.cells[idx] = SOLID;
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
        for q in 0..4 {
            let (px, py) = (q & 1 == 1, q & 2 == 2);
            // Mirrored coordinates (mx, my): the quadrant's rays move toward +mx and +my.
            let mut plane = vec![0u8; nx * ny];
            let side = |plane: &[u8], mx: usize, my: usize| -> u32 {
                if mx >= nx || my >= ny {
                    return 255; // Squares may reach the grid's edge.
                }
                match plane[my * nx + mx] {
                    LIST => 0,
                    v => u32::from(v),
                }
            };
            for my in (0..ny).rev() {
                let y = if py { my } else { ny - 1 - my };
                for mx in (0..nx).rev() {
                    let x = if px { mx } else { nx - 1 - mx };
                    plane[my * nx + mx] = match self.cells[y * nx + x] {
                        EMPTY => {
                            let m = side(&plane, mx + 1, my)
                                .min(side(&plane, mx, my + 1))
                                .min(side(&plane, mx + 1, my + 1));
                            (m + 1).min(u32::from(LIST) - 1) as u8
                        }
                        SOLID => 0,
                        _ => LIST,
                    };
                }
            }
            self.planes[q] = plane;
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
        let mut ray = Ray::default();
        if let Some(r) = self.ray_start(o, d, max_range_m, &mut ray) {
            return r;
        }
        loop {
            if let Some(r) = self.ray_step::<true>(&mut ray) {
                return r;
            }
        }
    }

    /// The ray origin `o` seen from each quadrant of travel, for rays cast from it.
    fn eye(&self, o: [f64; 2]) -> Eye {
        let gx = (o[0] - self.x0) * self.irx;
        let gy = (o[1] - self.y0) * self.iry;
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        let mut eye = Eye {
            inside: gx >= 0.0 && gy >= 0.0 && gx < nx && gy < ny,
            o,
            ..Eye::default()
        };
        if eye.inside {
            for q in 0..4 {
                let ox = if q & 1 == 1 { gx } else { nx - gx };
                let oy = if q & 2 == 2 { gy } else { ny - gy };
                eye.g[q] = [ox, oy];
                eye.c[q] = [
                    (ox as i32).clamp(0, self.nx as i32 - 1),
                    (oy as i32).clamp(0, self.ny as i32 - 1),
                ];
            }
        }
        eye
    }

    /// [`World::ray_start`] for a ray from `eye`'s origin, quicker when the origin is in the grid.
    #[inline(always)]
    fn ray_start_eye<'a>(
        &'a self,
        eye: &Eye,
        d: [f64; 2],
        max: f64,
        ray: &mut Ray<'a>,
    ) -> Option<Option<f64>> {
        if !(eye.inside && d[0].is_finite() && d[1].is_finite() && max >= 0.0 && max.is_finite()) {
            return self.ray_start(eye.o, d, max, ray);
        }
        let q = usize::from(d[0] >= 0.0) | (usize::from(d[1] >= 0.0) << 1);
        let dx = d[0].abs() * self.irx;
        let dy = d[1].abs() * self.iry;
        *ray = Ray {
            ox: eye.g[q][0],
            oy: eye.g[q][1],
            dx,
            dy,
            ix: 1.0 / dx,
            iy: 1.0 / dy,
            t1: max,
            max,
            t: 0.0,
            best: f64::INFINITY,
            cx: eye.c[q][0],
            cy: eye.c[q][1],
            q,
            plane: &self.planes[q],
            o: eye.o,
            d,
        };
        None
    }

    /// Sets up a ray for [`World::ray_step`], or answers at once.
    fn ray_start<'a>(
        &'a self,
        o: [f64; 2],
        d: [f64; 2],
        max: f64,
        ray: &mut Ray<'a>,
    ) -> Option<Option<f64>> {
        if !(o[0].is_finite()
            && o[1].is_finite()
            && d[0].is_finite()
            && d[1].is_finite()
            && max.is_finite()
            && max >= 0.0)
        {
            return Some(None);
        }
        // A zero component counts as positive: the ray then stays in the cell at or after it.
        let (sx, sy) = (d[0] >= 0.0, d[1] >= 0.0);
        let (nx, ny) = (self.nx as f64, self.ny as f64);
        // Mirrored cell coordinates in which the ray moves toward +x and +y.
        let gx = (o[0] - self.x0) * self.irx;
        let gy = (o[1] - self.y0) * self.iry;
        let ox = if sx { gx } else { nx - gx };
        let oy = if sy { gy } else { ny - gy };
        let dx = d[0].abs() * self.irx;
        let dy = d[1].abs() * self.iry;
        let (ix, iy) = (1.0 / dx, 1.0 / dy);
        let (mut t0, mut t1) = (0.0f64, max);
        for (oo, dd, ii, hi) in [(ox, dx, ix, nx), (oy, dy, iy, ny)] {
            if dd == 0.0 {
                if oo < 0.0 || oo >= hi {
                    return Some(None);
                }
            } else {
                t0 = t0.max(-oo * ii);
                t1 = t1.min((hi - oo) * ii);
            }
        }
        if t0 > t1 {
            return Some(None);
        }
        *ray = Ray {
            ox,
            oy,
            dx,
            dy,
            ix,
            iy,
            t1,
            max,
            t: t0,
            best: f64::INFINITY,
            cx: ((ox + t0 * dx) as i32).clamp(0, self.nx as i32 - 1),
            cy: ((oy + t0 * dy) as i32).clamp(0, self.ny as i32 - 1),
            q: usize::from(sx) | (usize::from(sy) << 1),
            plane: &self.planes[usize::from(sx) | (usize::from(sy) << 1)],
            o,
            d,
        };
        None
    }

    /// Advances a ray by one empty square (or one cell holding shapes); the answer once it is known.
    /// Without `SHAPES` the world must have no cells holding shapes (a pure bitmap).
    #[inline(always)]
    fn ray_step<const SHAPES: bool>(&self, r: &mut Ray) -> Option<Option<f64>> {
        let (cx, cy) = (r.cx, r.cy);
        let k = r.plane[cy as usize * self.nx + cx as usize];
        if k == 0 {
            return Some((r.t <= r.max).then_some(r.t));
        }
        let kk = if SHAPES && k == LIST { 1 } else { i32::from(k) };
        let ex = ((cx + kk) as f64 - r.ox) * r.ix;
        let ey = ((cy + kk) as f64 - r.oy) * r.iy;
        let e = if ex < ey { ex } else { ey };
        if SHAPES && k == LIST && self.test_list(r, e) {
            return Some((r.best <= r.max).then_some(r.best));
        }
        if e > r.t1 {
            return Some((r.best <= r.max).then_some(r.best));
        }
        // The cell the ray enters: across the exit side(s), and on the other axis the cell holding
        // the exit point, clamped to the square's span so rounding can never skip a cell.
        let (ncx, ncy) = if ex < ey {
            (cx + kk, ((r.oy + e * r.dy) as i32).max(cy).min(cy + kk - 1))
        } else if ey < ex {
            (((r.ox + e * r.dx) as i32).max(cx).min(cx + kk - 1), cy + kk)
        } else {
            (cx + kk, cy + kk)
        };
        if ncx >= self.nx as i32 || ncy >= self.ny as i32 {
            return Some((r.best <= r.max).then_some(r.best));
        }
        r.cx = ncx;
        r.cy = ncy;
        r.t = e;
        None
    }

    /// Tests the shapes of the ray's current cell; true when the nearest hit lies before `exit`.
    #[inline(never)]
    fn test_list(&self, r: &mut Ray, exit: f64) -> bool {
        let ax = if r.q & 1 == 1 {
            r.cx
        } else {
            self.nx as i32 - 1 - r.cx
        };
        let ay = if r.q & 2 == 2 {
            r.cy
        } else {
            self.ny as i32 - 1 - r.cy
        };
        for &p in self.list(self.cells[ay as usize * self.nx + ax as usize]) {
            if let Some(th) = ray_prim(r.o, r.d, &self.prims[p as usize]) {
                r.best = r.best.min(th);
            }
        }
        r.best <= exit
    }

    /// Casts rays from `o` along `dir(0)`, `dir(1)`, ... (called in order), several at once;
    /// `out[i]` is ray i's hit distance, or infinity for none within `max`.
    /// Each ray gives the same answer as [`World::raycast_dir`]; stepping six rays in turn lets
    /// the processor overlap their memory reads and arithmetic.
    pub(crate) fn raycast_many<'a>(
        &'a self,
        o: [f64; 2],
        mut dir: impl FnMut(usize) -> [f64; 2],
        max: f64,
        out: &mut [f64],
    ) {
        const LANES: usize = 6;
        let n = out.len();
        let eye = self.eye(o);
        let mut next = 0;
        let mut rays = [Ray::default(); LANES];
        let mut ids = [IDLE; LANES];
        // Starts the next ray that needs stepping in `ray`, answering the others at once.
        let mut refill = |next: &mut usize, out: &mut [f64], ray: &mut Ray<'a>| -> usize {
            while *next < n {
                let i = *next;
                *next += 1;
                match self.ray_start_eye(&eye, dir(i), max, ray) {
                    None => return i,
                    Some(r) => out[i] = r.unwrap_or(f64::INFINITY),
                }
            }
            IDLE
        };
        for (id, ray) in ids.iter_mut().zip(rays.iter_mut()) {
            *id = refill(&mut next, out, ray);
        }
        // A world without shapes has no cells holding shapes.
        if self.prims.is_empty() {
            let step = |ray: &mut Ray<'a>| self.ray_step::<false>(ray);
            run_lanes(&mut ids, &mut rays, step, &mut next, out, &mut refill);
        } else {
            let step = |ray: &mut Ray<'a>| self.ray_step::<true>(ray);
            run_lanes(&mut ids, &mut rays, step, &mut next, out, &mut refill);
        }
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

/// Steps the rays of `lanes` in turn until every ray is answered, writing answers to `out` and
/// starting the next rays with `refill`.
#[inline(always)]
fn run_lanes<'a, const L: usize>(
    ids: &mut [usize; L],
    rays: &mut [Ray<'a>; L],
    step: impl Fn(&mut Ray<'a>) -> Option<Option<f64>>,
    next: &mut usize,
    out: &mut [f64],
    refill: &mut impl FnMut(&mut usize, &mut [f64], &mut Ray<'a>) -> usize,
) {
    loop {
        let mut active = false;
        for (id, ray) in ids.iter_mut().zip(rays.iter_mut()) {
            if *id == IDLE {
                continue;
            }
            active = true;
            if let Some(res) = step(ray) {
                out[*id] = res.unwrap_or(f64::INFINITY);
                *id = refill(next, out, ray);
            }
        }
        if !active {
            break;
        }
    }
}

/// A ray in flight, in the mirrored cell coordinates of its quadrant `q` (bit 0: moving toward
/// +x, bit 1: toward +y): an axis along which the ray moves toward -x (or -y) is flipped,
/// `m = n - g` for cell coordinate `g` on a grid of `n` cells, so the ray always moves toward +m.
/// The point at distance `t` (metres) is `(ox + t dx, oy + t dy)`.
#[derive(Debug, Clone, Copy, Default)]
struct Ray<'a> {
    /// Origin, mirrored cell coordinates.
    ox: f64,
    oy: f64,
    /// Direction per metre, cells (>= 0).
    dx: f64,
    dy: f64,
    /// 1 / dx and 1 / dy (may be infinite).
    ix: f64,
    iy: f64,
    /// Where the ray stops: the maximum range, or where it leaves the grid.
    t1: f64,
    /// The maximum range.
    max: f64,
    /// Where the ray entered the current cell.
    t: f64,
    /// The nearest shape hit so far.
    best: f64,
    /// The current cell, mirrored.
    cx: i32,
    cy: i32,
    /// The quadrant.
    q: usize,
    /// Its plane.
    plane: &'a [u8],
    /// Origin and unit direction, world coordinates (for exact shape tests).
    o: [f64; 2],
    d: [f64; 2],
}

/// A ray origin seen from each quadrant of travel (`q` as in [`Ray`]).
#[derive(Debug, Clone, Copy, Default)]
struct Eye {
    /// True when the origin lies inside the grid.
    inside: bool,
    /// The origin, world coordinates.
    o: [f64; 2],
    /// The origin in each quadrant's mirrored cell coordinates.
    g: [[f64; 2]; 4],
    /// Its cell there.
    c: [[i32; 2]; 4],
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
