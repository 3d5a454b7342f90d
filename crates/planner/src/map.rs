//! The planner's own obstacle memory (a coarse grid of world-frame hits, inflated by the robot
//! radius and a margin, unknown = free) and the path-length field toward the target over it.
//!
//! A graded memory ([`ObstacleMemory::graded`]) is lethal only within a smaller radius and
//! charges a higher cost per metre in the band between the two radii, as Nav2's inflation
//! layer does: a narrow door stays passable, and paths keep their distance where there is room.

use scan_types::WorldPoint;

/// Extra room kept around everything the grid must hold, metres.
const GROW_MARGIN_M: f64 = 2.0;
/// Step costs of the wavefront: straight 10, diagonal 14 (units of a tenth of a cell).
const STRAIGHT: u32 = 10;
const DIAGONAL: u32 = 14;
/// Cost factor of a step into a cell of the band of a graded memory (within the full
/// inflation, outside the lethal one).
pub const BAND_FACTOR: u32 = 3;
/// "No path".
const UNREACHED: u32 = u32::MAX;
/// The most cells the grid grows to (400 m square at 0.1 m); beyond it, new places count as
/// unknown (free), so that memory stays bounded however far the robot is sent.
pub const MAX_CELLS: usize = 1 << 24;
/// The grid grows to hold the target only while it stays within this many cells (100 m square
/// at 0.1 m); a farther target is reached through the unknown around the grid.
pub const TARGET_CELLS: usize = 1 << 20;

/// Hits remembered on a coarse grid, and the path length of every cell to a target.
#[derive(Debug, Clone)]
pub struct ObstacleMemory {
    resolution_m: f64,
    inflate_m: f64,
    /// The largest radius stamped (room kept around the grid's content), metres.
    grow_m: f64,
    /// World coordinates of the lower-left corner of cell (0, 0).
    origin: (f64, f64),
    width: usize,
    height: usize,
    /// Hits seen in each cell (saturating).
    hits: Vec<u16>,
    /// How many hit cells lie within the inflation radius of each cell (> 0: blocked).
    blocked: Vec<u16>,
    /// How many hit cells lie within the band radius of each cell (graded memory only).
    near: Vec<u16>,
    /// Cell offsets within the inflation radius.
    stamp: Vec<(i32, i32)>,
    /// Cell offsets within the band radius (empty unless graded).
    band_stamp: Vec<(i32, i32)>,
    /// Bumped whenever the set of blocked cells changes.
    version: u64,
    /// Set once the grid has refused to grow past [`MAX_CELLS`].
    full: bool,
    /// Whether the current field passes through the band.
    through_band: bool,
    /// The path-length field (tenths of a cell, above `field_base_m`) and what it was
    /// computed for: the memory's version and the target's cell (which may lie off the grid).
    field: Vec<u32>,
    field_base_m: f64,
    field_key: Option<(u64, (i64, i64))>,
    /// The last field's target, world coordinates.
    field_target: (f64, f64),
    /// Scratch of the wavefront: seeds not yet due, (cost, cell), costliest first.
    seeds: Vec<(u32, u32)>,
    /// Scratch of the wavefront: one bucket per cost modulo the bucket count.
    buckets: Vec<Vec<u32>>,
    /// Scratch of the wavefront: the bucket being expanded.
    popped: Vec<u32>,
    /// Scratch of the wavefront: free cells, border closed.
    passable: Vec<bool>,
}

impl ObstacleMemory {
    /// An empty memory with cells of `resolution_m` and obstacles grown by `inflate_m`.
    pub fn new(resolution_m: f64, inflate_m: f64) -> Self {
        Self::graded(resolution_m, inflate_m, inflate_m)
    }

    /// An empty memory whose obstacles are lethal within `lethal_m` and cost
    /// `BAND_FACTOR` (3) times as much per metre out to `band_m` (no band when
    /// `band_m <= lethal_m`).
    pub fn graded(resolution_m: f64, lethal_m: f64, band_m: f64) -> Self {
        let stamp_of = |radius_m: f64, skip_m: f64| {
            let reach = (radius_m / resolution_m).floor() as i32;
            let mut stamp = Vec::new();
            for dy in -reach..=reach {
                for dx in -reach..=reach {
                    let dist = ((dx * dx + dy * dy) as f64).sqrt() * resolution_m;
                    if dist <= radius_m && dist > skip_m {
                        stamp.push((dx, dy));
                    }
                }
            }
            stamp
        };
        let stamp = stamp_of(lethal_m, -1.0);
        let band_stamp = if band_m > lethal_m {
            stamp_of(band_m, lethal_m)
        } else {
            Vec::new()
        };
        let inflate_m = lethal_m.max(band_m);
        Self {
            resolution_m,
            inflate_m: lethal_m,
            grow_m: inflate_m,
            origin: (0.0, 0.0),
            width: 0,
            height: 0,
            hits: Vec::new(),
            blocked: Vec::new(),
            near: Vec::new(),
            stamp,
            band_stamp,
            version: 0,
            full: false,
            through_band: false,
            field: Vec::new(),
            field_base_m: 0.0,
            field_key: None,
            field_target: (0.0, 0.0),
            seeds: Vec::new(),
            buckets: vec![Vec::new(); (DIAGONAL * BAND_FACTOR + 1) as usize],
            popped: Vec::new(),
            passable: Vec::new(),
        }
    }

    /// Cell size, metres.
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }

    /// Number of cells in the grid.
    pub fn cell_count(&self) -> usize {
        self.width * self.height
    }

    /// Number of cells holding at least one hit.
    pub fn hit_cells(&self) -> usize {
        self.hits.iter().filter(|&&h| h > 0).count()
    }

    /// True when `p` lies within the inflation radius of a remembered hit.
    pub fn is_blocked(&self, p: WorldPoint) -> bool {
        self.cell_of(p).is_some_and(|c| self.blocked[c] > 0)
    }

    /// Distance from `p` to the centre of the nearest cell holding a hit, searched within
    /// `max_m`, metres; `None` when there is none.
    pub fn nearest_hit_m(&self, p: WorldPoint, max_m: f64) -> Option<f64> {
        if max_m.is_nan() || max_m < 0.0 || self.width == 0 {
            return None;
        }
        let fx = (p.x_m() - self.origin.0) / self.resolution_m;
        let fy = (p.y_m() - self.origin.1) / self.resolution_m;
        let reach = max_m / self.resolution_m + 1.0;
        let clamp = |v: f64, n: usize| v.clamp(0.0, n as f64 - 1.0) as usize;
        let (x0, x1) = (clamp(fx - reach, self.width), clamp(fx + reach, self.width));
        let (y0, y1) = (
            clamp(fy - reach, self.height),
            clamp(fy + reach, self.height),
        );
        let mut best: Option<f64> = None;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let c = y * self.width + x;
                if self.hits[c] == 0 {
                    continue;
                }
                let (cx, cy) = self.centre_of(c);
                let d = (cx - p.x_m()).hypot(cy - p.y_m());
                if d <= max_m && best.is_none_or(|b| d < b) {
                    best = Some(d);
                }
            }
        }
        best
    }

    /// Remembers a world-frame hit point.
    pub fn add_hit(&mut self, p: WorldPoint) {
        self.count_hit(p);
    }

    /// [`ObstacleMemory::add_hit`]; `Some(true)` when the hit made its cell occupied,
    /// `Some(false)` when it was counted in an occupied cell, `None` when not counted (not
    /// finite, off the grid, or the cell's count saturated).
    pub(crate) fn count_hit(&mut self, p: WorldPoint) -> Option<bool> {
        if !(p.x_m().is_finite() && p.y_m().is_finite()) {
            return None;
        }
        self.ensure_contains(p);
        let c = self.cell_of(p)?;
        if self.hits[c] == u16::MAX {
            return None;
        }
        let new = self.hits[c] == 0;
        if new {
            self.stamp_cell(c);
            self.version += 1;
        }
        self.hits[c] += 1;
        Some(new)
    }

    /// Takes back one hit counted by [`ObstacleMemory::count_hit`] at `p`.
    pub(crate) fn uncount_hit(&mut self, p: WorldPoint) {
        let Some(c) = self.cell_of(p).filter(|&c| self.hits[c] > 0) else {
            return;
        };
        self.hits[c] -= 1;
        if self.hits[c] == 0 {
            self.stamp_cell_by(c, -1);
            self.version += 1;
        }
    }

    /// Grows the grid (keeping its content) so that `p` lies inside with room around it.
    pub fn ensure_contains(&mut self, p: WorldPoint) {
        self.grow_to(p, MAX_CELLS);
    }

    /// [`ObstacleMemory::ensure_contains`] unless the grid would exceed `max_cells`.
    fn grow_to(&mut self, p: WorldPoint, max_cells: usize) {
        let (x, y) = (p.x_m(), p.y_m());
        if !(x.is_finite() && y.is_finite()) {
            return;
        }
        let inside = |v: f64, lo: f64, cells: usize| {
            v - self.grow_m - 1.0 >= lo
                && v + self.grow_m + 1.0 < lo + cells as f64 * self.resolution_m
        };
        if self.width > 0
            && inside(x, self.origin.0, self.width)
            && inside(y, self.origin.1, self.height)
        {
            return;
        }
        let res = self.resolution_m;
        let (mut x0, mut y0, mut x1, mut y1) = if self.width == 0 {
            (x, y, x, y)
        } else {
            (
                self.origin.0,
                self.origin.1,
                self.origin.0 + self.width as f64 * res,
                self.origin.1 + self.height as f64 * res,
            )
        };
        x0 = x0.min(x - GROW_MARGIN_M);
        y0 = y0.min(y - GROW_MARGIN_M);
        x1 = x1.max(x + GROW_MARGIN_M);
        y1 = y1.max(y + GROW_MARGIN_M);
        // Keep cell boundaries aligned with the old grid.
        let (ox, oy) = if self.width == 0 {
            ((x0 / res).floor() * res, (y0 / res).floor() * res)
        } else {
            (
                self.origin.0 - ((self.origin.0 - x0) / res).ceil() * res,
                self.origin.1 - ((self.origin.1 - y0) / res).ceil() * res,
            )
        };
        let (wf, hf) = ((x1 - ox) / res + 1.0, (y1 - oy) / res + 1.0);
        let cells = wf * hf;
        if cells.is_nan() || cells > max_cells as f64 {
            if max_cells == MAX_CELLS && !self.full {
                tracing::warn!(
                    x_m = x,
                    y_m = y,
                    max_cells = MAX_CELLS,
                    "obstacle memory full: places beyond it count as unknown"
                );
                self.full = true;
            }
            return;
        }
        let w = wf.ceil() as usize;
        let h = hf.ceil() as usize;
        let dx = ((self.origin.0 - ox) / res).round() as usize;
        let dy = ((self.origin.1 - oy) / res).round() as usize;
        let mut hits = vec![0u16; w * h];
        for row in 0..self.height {
            for col in 0..self.width {
                hits[(row + dy) * w + col + dx] = self.hits[row * self.width + col];
            }
        }
        self.origin = (ox, oy);
        self.width = w;
        self.height = h;
        self.hits = hits;
        self.blocked = vec![0; w * h];
        self.near = if self.band_stamp.is_empty() {
            Vec::new()
        } else {
            vec![0; w * h]
        };
        for c in 0..w * h {
            if self.hits[c] > 0 {
                self.stamp_cell(c);
            }
        }
        self.version += 1;
    }

    fn stamp_cell(&mut self, c: usize) {
        self.stamp_cell_by(c, 1);
    }

    /// Adds `by` (1 or -1) to the counts of the cells around `c`.
    fn stamp_cell_by(&mut self, c: usize, by: i32) {
        let (col, row) = ((c % self.width) as i32, (c / self.width) as i32);
        let (w, h) = (self.width, self.height);
        let within = move |(dx, dy): (i32, i32)| {
            let (x, y) = (col + dx, row + dy);
            (x >= 0 && y >= 0 && (x as usize) < w && (y as usize) < h)
                .then(|| y as usize * w + x as usize)
        };
        let add = |v: u16| {
            if by > 0 {
                v.saturating_add(1)
            } else {
                v.saturating_sub(1)
            }
        };
        for k in self.stamp.iter().filter_map(|&o| within(o)) {
            self.blocked[k] = add(self.blocked[k]);
        }
        for k in self.band_stamp.iter().filter_map(|&o| within(o)) {
            self.near[k] = add(self.near[k]);
        }
    }

    /// True when cell `k` is closed to the current field: the lethal core, and the band unless
    /// the field passes through it.
    fn closed(&self, k: usize) -> bool {
        self.blocked[k] > 0 || (!self.through_band && !self.near.is_empty() && self.near[k] > 0)
    }

    /// True when `p` lies within the band of a graded memory (within the full inflation but
    /// outside the lethal one); always false for a memory that is not graded.
    pub fn is_in_band(&self, p: WorldPoint) -> bool {
        !self.near.is_empty() && self.cell_of(p).is_some_and(|c| self.near[c] > 0)
    }

    fn cell_of(&self, p: WorldPoint) -> Option<usize> {
        // Compared before flooring: floor(x) >= 0 iff x >= 0 and floor(x) < w iff x < w for a
        // whole w, and for x >= 0 truncation is the floor (no libm call).
        let fx = (p.x_m() - self.origin.0) / self.resolution_m;
        let fy = (p.y_m() - self.origin.1) / self.resolution_m;
        if fx >= 0.0 && fy >= 0.0 && fx < self.width as f64 && fy < self.height as f64 {
            Some(fy as usize * self.width + fx as usize)
        } else {
            None
        }
    }

    fn centre_of(&self, c: usize) -> (f64, f64) {
        (
            self.origin.0 + ((c % self.width) as f64 + 0.5) * self.resolution_m,
            self.origin.1 + ((c / self.width) as f64 + 0.5) * self.resolution_m,
        )
    }

    /// Computes the path-length field to `target` unless it is current; true when recomputed.
    ///
    /// The grid grows to hold the target while it stays within [`TARGET_CELLS`]; a target
    /// beyond is reached through the unknown around the grid, which counts as free, so every
    /// free cell just inside the grid's border is seeded with its straight-line distance to
    /// the target.
    pub fn update_field(&mut self, target: WorldPoint) -> bool {
        self.update_field_through(target, false)
    }

    /// [`ObstacleMemory::update_field`]; with `through_band` a graded memory's band is
    /// passable at its higher cost, otherwise it is closed like the lethal core.
    pub fn update_field_through(&mut self, target: WorldPoint, through_band: bool) -> bool {
        let through_band = through_band && !self.near.is_empty();
        if through_band != self.through_band {
            self.through_band = through_band;
            self.field_key = None;
        }
        let (x, y) = (target.x_m(), target.y_m());
        if !(x.is_finite() && y.is_finite()) {
            return false;
        }
        self.grow_to(target, TARGET_CELLS);
        if self.width < 3 || self.height < 3 {
            return false;
        }
        let key_cell = (
            ((x - self.origin.0) / self.resolution_m).floor() as i64,
            ((y - self.origin.1) / self.resolution_m).floor() as i64,
        );
        // The field is kept for a target that moved within its cell; distances go to the new one.
        self.field_target = (x, y);
        if self.field_key == Some((self.version, key_cell)) {
            return false;
        }
        self.field.clear();
        self.field.resize(self.width * self.height, UNREACHED);
        for b in &mut self.buckets {
            b.clear();
        }
        self.seeds.clear();
        match self.cell_of(target) {
            Some(tc) => self.seed_at_target(tc),
            None => self.seed_border(x, y),
        }
        // Costliest first, so that the next due seed is the last one.
        self.seeds.sort_unstable_by(|a, b| b.cmp(a));
        for &(cost, k) in &self.seeds {
            self.field[k as usize] = self.field[k as usize].min(cost);
        }
        self.wavefront();
        self.field_key = Some((self.version, key_cell));
        true
    }

    /// Seeds the target cell, and when it is blocked (the target close to a wall) the free
    /// cells within the inflation radius of it, at their straight-line cost.
    fn seed_at_target(&mut self, tc: usize) {
        self.field_base_m = 0.0;
        self.seeds.push((0, tc as u32));
        if !self.closed(tc) {
            return;
        }
        let radius = if self.through_band {
            self.inflate_m
        } else {
            self.grow_m
        };
        let reach = (radius / self.resolution_m).ceil() as i32 + 1;
        let (tcol, trow) = ((tc % self.width) as i32, (tc / self.width) as i32);
        for dy in -reach..=reach {
            for dx in -reach..=reach {
                let (x, y) = (tcol + dx, trow + dy);
                if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
                    continue;
                }
                let k = y as usize * self.width + x as usize;
                if !self.closed(k) {
                    let cost = (((dx * dx + dy * dy) as f64).sqrt() * STRAIGHT as f64) as u32;
                    self.seeds.push((cost, k as u32));
                }
            }
        }
    }

    /// Seeds every free cell of the ring just inside the closed border with its straight-line
    /// distance to the off-grid target `(x, y)`, relative to the nearest of them.
    fn seed_border(&mut self, x: f64, y: f64) {
        let (w, h) = (self.width, self.height);
        let ring = (1..w - 1)
            .flat_map(|c| [w + c, (h - 2) * w + c])
            .chain((2..h - 2).flat_map(|r| [r * w + 1, r * w + w - 2]));
        let mut dists = Vec::new();
        for k in ring {
            if !self.closed(k) {
                let (cx, cy) = self.centre_of(k);
                dists.push(((cx - x).hypot(cy - y), k));
            }
        }
        let base = dists.iter().map(|d| d.0).fold(f64::INFINITY, f64::min);
        self.field_base_m = if base.is_finite() { base } else { 0.0 };
        let per_m = STRAIGHT as f64 / self.resolution_m;
        for (d, k) in dists {
            let cost = ((d - base) * per_m).round().min(f64::from(u32::MAX / 2)) as u32;
            self.seeds.push((cost, k as u32));
        }
    }

    /// Dial's shortest paths over free cells (8-connected, no corner cutting), from the
    /// seeded buckets.
    fn wavefront(&mut self) {
        let nb = self.buckets.len();
        let w = self.width;
        let n = self.width * self.height;
        // Passable cells, with the grid's border rows and columns closed so that neighbour
        // indices never leave the grid.
        let mut passable = std::mem::take(&mut self.passable);
        passable.clear();
        passable.extend((0..n).map(|k| !self.closed(k)));
        self.passable = passable;
        for c in 0..w {
            self.passable[c] = false;
            self.passable[n - 1 - c] = false;
        }
        for r in 0..self.height {
            self.passable[r * w] = false;
            self.passable[r * w + w - 1] = false;
        }
        let wi = w as isize;
        let straight = [1isize, -1, wi, -wi];
        // Diagonal step and the two straight cells it passes between.
        let diagonal = [
            (wi + 1, 1, wi),
            (wi - 1, -1, wi),
            (-wi + 1, 1, -wi),
            (-wi - 1, -1, -wi),
        ];
        let mut cost: u32 = 0;
        let mut empty_run = 0;
        let mut popped = Vec::new();
        std::mem::swap(&mut popped, &mut self.popped);
        loop {
            while let Some(&(due, k)) = self.seeds.last() {
                if due > cost {
                    break;
                }
                self.seeds.pop();
                if self.field[k as usize] == due {
                    self.buckets[due as usize % nb].push(k);
                }
            }
            let slot = cost as usize % nb;
            if self.buckets[slot].is_empty() {
                empty_run += 1;
                if empty_run >= nb {
                    // Nothing in flight: jump to the next seed, or stop.
                    let Some(&(due, _)) = self.seeds.last() else {
                        break;
                    };
                    cost = due;
                    empty_run = 0;
                } else {
                    cost += 1;
                }
                continue;
            }
            empty_run = 0;
            std::mem::swap(&mut popped, &mut self.buckets[slot]);
            for &c in &popped {
                let c = c as usize;
                if self.field[c] != cost {
                    continue; // a stale entry
                }
                // Only a seed can be impassable (the target next to a wall): it is expanded
                // unless it lies on the closed border.
                if !self.passable[c] && self.on_border(c) {
                    continue;
                }
                self.expand_from(c, cost, &straight, &diagonal);
            }
            popped.clear();
            cost += 1;
        }
        self.popped = popped;
    }

    fn on_border(&self, c: usize) -> bool {
        let (x, y) = (c % self.width, c / self.width);
        x == 0 || y == 0 || x + 1 == self.width || y + 1 == self.height
    }

    #[inline]
    fn expand_from(
        &mut self,
        c: usize,
        cost: u32,
        straight: &[isize; 4],
        diagonal: &[(isize, isize, isize); 4],
    ) {
        let nb = self.buckets.len();
        let graded = self.through_band;
        let step = |k: usize, base: u32| {
            if graded && self.near[k] > 0 {
                base * BAND_FACTOR
            } else {
                base
            }
        };
        for &o in straight {
            let k = (c as isize + o) as usize;
            let nc = cost + step(k, STRAIGHT);
            if self.passable[k] && nc < self.field[k] {
                self.field[k] = nc;
                self.buckets[nc as usize % nb].push(k as u32);
            }
        }
        for &(o, a, b) in diagonal {
            let k = (c as isize + o) as usize;
            let nc = cost + step(k, DIAGONAL);
            if self.passable[k]
                && self.passable[(c as isize + a) as usize]
                && self.passable[(c as isize + b) as usize]
                && nc < self.field[k]
            {
                self.field[k] = nc;
                self.buckets[nc as usize % nb].push(k as u32);
            }
        }
    }

    /// Straight-line distance to the last field's target from `p` when in sight of it, metres.
    ///
    /// `None` when the segment crosses a cell the field counts closed, or when the memory
    /// changed since the field was computed. Closed cells within two cells of `p` before the
    /// line's first free one (a safe end right at an obstacle's edge) and the last inflation
    /// radius plus one cell before the target (a target next to a wall) do not count; the
    /// line off the grid is free. When the field runs through the band, each metre in it
    /// costs `BAND_FACTOR` times as much, as in the field.
    pub fn line_of_sight_m(&self, p: WorldPoint) -> Option<f64> {
        if self.field_key.map(|k| k.0) != Some(self.version) {
            return None;
        }
        let (px, py) = (p.x_m(), p.y_m());
        let (tx, ty) = self.field_target;
        let d = (tx - px).hypot(ty - py);
        if !d.is_finite() {
            return None;
        }
        let radius = if self.through_band {
            self.inflate_m
        } else {
            self.grow_m
        };
        let (ux, uy) = if d > 0.0 {
            ((tx - px) / d, (ty - py) / d)
        } else {
            (0.0, 0.0)
        };
        // The part of the segment over the grid (outside it everything is free).
        let (mut lo, mut hi) = (0.0f64, (d - radius - self.resolution_m).max(0.0));
        let span = [
            (px, ux, self.origin.0, self.width),
            (py, uy, self.origin.1, self.height),
        ];
        for (start, u, origin, cells) in span {
            let (min, max) = (origin, origin + cells as f64 * self.resolution_m);
            if u.abs() < 1e-12 {
                if start < min || start >= max {
                    return Some(d);
                }
                continue;
            }
            let (a, b) = ((min - start) / u, (max - start) / u);
            lo = lo.max(a.min(b));
            hi = hi.min(a.max(b));
        }
        let step = self.resolution_m / 2.0;
        // Closed cells are forgiven within two cells of `p` until the first free one.
        let forgiven = if lo > 0.0 {
            -1.0
        } else {
            2.0 * self.resolution_m
        };
        let mut left_start = false;
        let mut band_m = 0.0;
        let mut t = lo;
        // Bounded by the samples too: far from the grid `t += step` may not move `t`.
        let samples = ((hi - lo) / step).max(0.0).ceil() as usize + 1;
        for _ in 0..samples {
            if t > hi {
                break;
            }
            let q = WorldPoint::new(px + ux * t, py + uy * t);
            if let Some(c) = self.cell_of(q) {
                let closed = self.closed(c);
                if closed && (left_start || t > forgiven) {
                    return None;
                }
                left_start |= !closed;
                if self.through_band && !closed && self.near[c] > 0 {
                    band_m += step;
                }
            }
            t += step;
        }
        Some(d + f64::from(BAND_FACTOR - 1) * band_m)
    }

    /// Cell centres along the steepest descent of the current field from `p` toward its
    /// target (`p`'s own cell left out), until the path reaches `max_m` (within a step);
    /// empty when the field is stale or `p` has no path.
    pub fn descent(&self, p: WorldPoint, max_m: f64) -> Vec<WorldPoint> {
        let mut path = Vec::new();
        let Some(mut c) = self.cell_of(p) else {
            return path;
        };
        if self.field_key.map(|k| k.0) != Some(self.version) {
            return path;
        }
        let open = |k: usize| self.field[k] != UNREACHED && !self.closed(k);
        let neighbours = |c: usize, reach: i64| {
            let (col, row) = ((c % self.width) as i64, (c / self.width) as i64);
            (-reach..=reach)
                .flat_map(move |dy| (-reach..=reach).map(move |dx| (col + dx, row + dy)))
                .filter(|&(x, y)| x >= 0 && y >= 0)
                .filter(|&(x, y)| x < self.width as i64 && y < self.height as i64)
                .map(|(x, y)| (y * self.width as i64 + x) as usize)
                .filter(move |&k| k != c && open(k))
        };
        // A point right at an obstacle's edge starts from the best open cell next to it.
        if !open(c) {
            let Some(k) = neighbours(c, 2).min_by_key(|&k| self.field[k]) else {
                return path;
            };
            c = k;
            let (x, y) = self.centre_of(c);
            path.push(WorldPoint::new(x, y));
        }
        let mut length_m = 0.0;
        while length_m < max_m && self.field[c] > 0 {
            let Some(next) = neighbours(c, 1)
                .filter(|&k| self.field[k] < self.field[c])
                .min_by_key(|&k| self.field[k])
            else {
                break;
            };
            let diagonal =
                next % self.width != c % self.width && next / self.width != c / self.width;
            length_m += self.resolution_m
                * if diagonal {
                    std::f64::consts::SQRT_2
                } else {
                    1.0
                };
            c = next;
            let (x, y) = self.centre_of(c);
            path.push(WorldPoint::new(x, y));
        }
        path
    }

    /// Path length from `p` to the target of the last field, metres; `None` when no path is
    /// known or the memory changed since the field was computed. A point in a blocked cell (right at the edge of an obstacle) takes the best free
    /// cell next to it plus the straight distance to that cell's centre.
    pub fn path_length_m(&self, p: WorldPoint) -> Option<f64> {
        let c = self.cell_of(p)?;
        // A field computed before the grid last changed may not match its cells.
        if self.field_key.map(|k| k.0) != Some(self.version) {
            return None;
        }
        let to_m = self.resolution_m / STRAIGHT as f64;
        if self.field[c] != UNREACHED && !self.closed(c) {
            return Some(self.field_base_m + self.field[c] as f64 * to_m);
        }
        let (col, row) = ((c % self.width) as i64, (c / self.width) as i64);
        let mut best: Option<f64> = None;
        for dy in -2..=2i64 {
            for dx in -2..=2i64 {
                let (x, y) = (col + dx, row + dy);
                if x < 0 || y < 0 || x >= self.width as i64 || y >= self.height as i64 {
                    continue;
                }
                let k = (y * self.width as i64 + x) as usize;
                if self.field[k] == UNREACHED {
                    continue;
                }
                let along = self.field_base_m + self.field[k] as f64 * to_m;
                // Adding a distance cannot bring it below the best so far.
                if best.is_some_and(|b| along >= b) {
                    continue;
                }
                let (cx, cy) = self.centre_of(k);
                let v = along + (cx - p.x_m()).hypot(cy - p.y_m());
                best = Some(best.map_or(v, |b: f64| b.min(v)));
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_space_path_is_octile_distance() {
        let mut m = ObstacleMemory::new(0.1, 0.4);
        m.ensure_contains(WorldPoint::new(0.0, 0.0));
        m.update_field(WorldPoint::new(0.05, 0.05));
        // 1 m straight along x: 10 cells.
        let d = m.path_length_m(WorldPoint::new(1.05, 0.05)).unwrap();
        assert!((d - 1.0).abs() < 1e-9, "{d}");
        // 0.5 m diagonal: 5 diagonal steps of 1.4 cells.
        let d = m.path_length_m(WorldPoint::new(0.55, 0.55)).unwrap();
        assert!((d - 0.7).abs() < 1e-9, "{d}");
    }

    #[test]
    fn line_of_sight_is_the_straight_distance_unless_a_closed_cell_cuts_it() {
        let mut m = ObstacleMemory::new(0.1, 0.3);
        m.ensure_contains(WorldPoint::new(0.0, 0.0));
        m.ensure_contains(WorldPoint::new(5.0, 2.0));
        m.update_field(WorldPoint::new(0.05, 0.05));
        // 3 m east and 1 m north of the target: sqrt(10) = 3.162 m in a straight line, 20
        // straight and 10 diagonal cells (3.4 m) on the grid.
        let p = WorldPoint::new(3.05, 1.05);
        let d = m.line_of_sight_m(p).unwrap();
        assert!((d - 10f64.sqrt()).abs() < 1e-9, "{d}");
        assert!((m.path_length_m(p).unwrap() - 3.4).abs() < 1e-9);
        // A post at (1.55, 0.55), on the line: its inflation cuts it; a post 1 m off the line
        // does not.
        m.add_hit(WorldPoint::new(1.55, 1.55));
        m.update_field(WorldPoint::new(0.05, 0.05));
        assert!((m.line_of_sight_m(p).unwrap() - 10f64.sqrt()).abs() < 1e-9);
        m.add_hit(WorldPoint::new(1.55, 0.55));
        assert_eq!(
            m.line_of_sight_m(p),
            None,
            "the memory changed since the field"
        );
        m.update_field(WorldPoint::new(0.05, 0.05));
        assert_eq!(m.line_of_sight_m(p), None);
        // A start just inside the post's inflation (a safe end at its edge) is free until it
        // leaves it within two cells; a line through the post is cut.
        // (The stamp reaches 2 cells: 0.3 / 0.1 floors to 2.)
        m.update_field(WorldPoint::new(4.05, 0.55));
        let (east, west) = (WorldPoint::new(1.75, 0.55), WorldPoint::new(1.35, 0.55));
        assert!(m.is_blocked(east) && m.is_blocked(west));
        let d = m.line_of_sight_m(east).unwrap();
        assert!((d - 2.3).abs() < 1e-9, "{d}");
        assert_eq!(m.line_of_sight_m(west), None);
        // A target inside the post's inflation: the inflation does not cut the line to it.
        m.update_field(WorldPoint::new(1.75, 0.55));
        let d = m.line_of_sight_m(WorldPoint::new(4.05, 0.55)).unwrap();
        assert!((d - 2.3).abs() < 1e-9, "{d}");
        // A target off the grid: the part outside the grid is free.
        m.update_field(WorldPoint::new(5000.0, 0.55));
        let d = m.line_of_sight_m(WorldPoint::new(3.05, 0.55)).unwrap();
        assert!((d - 4996.95).abs() < 1e-6, "{d}");
        assert_eq!(m.line_of_sight_m(WorldPoint::new(0.05, 0.55)), None);
    }

    #[test]
    fn line_of_sight_through_the_band_costs_as_the_field_does() {
        // Lethal within 0.2 m, band to 0.4 m: a line 0.3 m from a hit passes through 5 band
        // cells (|dx| <= 2 at dy = 3: sqrt(4 + 9) x 0.1 = 0.36 m), 0.5 m, each metre of it
        // costing 3 times: 3 m + 2 x 0.5 m.
        let mut m = ObstacleMemory::graded(0.1, 0.2, 0.4);
        m.ensure_contains(WorldPoint::new(0.0, 0.0));
        m.ensure_contains(WorldPoint::new(4.0, 1.0));
        m.add_hit(WorldPoint::new(1.55, 0.55));
        let (from, target) = (WorldPoint::new(3.05, 0.85), WorldPoint::new(0.05, 0.85));
        m.update_field_through(target, true);
        let d = m.line_of_sight_m(from).unwrap();
        assert!((d - 4.0).abs() <= 0.1 + 1e-9, "{d}");
        // With the band closed the line is cut.
        m.update_field_through(target, false);
        assert_eq!(m.line_of_sight_m(from), None);
    }

    #[test]
    fn a_wall_forces_a_detour() {
        let mut m = ObstacleMemory::new(0.1, 0.3);
        // A wall along y = 0 from x = -2 to x = 2.
        for i in -40..=40 {
            m.add_hit(WorldPoint::new(i as f64 * 0.05, 0.0));
        }
        m.update_field(WorldPoint::new(0.0, 1.0));
        let through = m.path_length_m(WorldPoint::new(0.0, -1.0)).unwrap();
        // Around an end: at least 2 * sqrt(2^2 + 1^2) = 4.47 m.
        assert!(through > 4.4, "{through}");
        assert!(m.is_blocked(WorldPoint::new(0.0, 0.2)));
        assert!(!m.is_blocked(WorldPoint::new(0.0, 0.5)));
        // The descent goes around an end of the wall to the target, through open cells, no
        // shorter than the way around an end and no longer than the field says (it may cut a
        // corner the wavefront does not).
        let path = m.descent(WorldPoint::new(0.0, -1.0), 50.0);
        let last = *path.last().unwrap();
        assert!(
            last.distance_m(&WorldPoint::new(0.0, 1.0)) < 0.08,
            "{last:?}"
        );
        assert!(path.iter().all(|p| !m.is_blocked(*p)));
        assert!(path.iter().any(|p| p.x_m().abs() > 2.0));
        let along: f64 = path.windows(2).map(|w| w[0].distance_m(&w[1])).sum();
        assert!(along > 4.47 && along < through + 0.01, "{along} {through}");
        // Cut at the length asked for, within a step.
        let short = m.descent(WorldPoint::new(0.0, -1.0), 1.0);
        let along: f64 = short.windows(2).map(|w| w[0].distance_m(&w[1])).sum();
        assert!(along < 1.0 && along > 0.8, "{along}");
        // Unchanged memory and target: no recomputation.
        assert!(!m.update_field(WorldPoint::new(0.0, 1.0)));
        m.add_hit(WorldPoint::new(5.0, 5.0));
        // A field computed before the memory changed gives no descent.
        assert!(m.descent(WorldPoint::new(0.0, -1.0), 50.0).is_empty());
        assert!(m.update_field(WorldPoint::new(0.0, 1.0)));
    }

    #[test]
    fn enclosed_target_has_no_path() {
        let mut m = ObstacleMemory::new(0.1, 0.2);
        for k in 0..400 {
            let a = k as f64 / 400.0 * std::f64::consts::TAU;
            m.add_hit(WorldPoint::new(1.5 * a.cos(), 1.5 * a.sin()));
        }
        m.update_field(WorldPoint::new(0.0, 0.0));
        assert!(m.path_length_m(WorldPoint::new(3.0, 0.0)).is_none());
        assert!(m.path_length_m(WorldPoint::new(0.5, 0.0)).is_some());
    }

    #[test]
    fn off_grid_target_is_reached_through_the_unknown() {
        let mut m = ObstacleMemory::new(0.1, 0.3);
        m.add_hit(WorldPoint::new(1.0, 1.0));
        let cells = m.cell_count();
        // 5 km east (a grid holding it would need 2 million cells): the grid does not grow,
        // and the path is the straight line (to within a cell for the ring cell's offset from
        // the line).
        assert!(m.update_field(WorldPoint::new(5000.0, 0.0)));
        assert_eq!(m.cell_count(), cells);
        let d = m.path_length_m(WorldPoint::new(0.05, 0.05)).unwrap();
        assert!((d - 4999.95).abs() < 0.15, "{d}");
        // A wall across the way east (x = 1.5, y from -1 to 2.5) forces a detour around its
        // nearer end (at y = -1, inflated 0.3 m): at least sqrt(1.45^2 + 1.35^2) + the rest.
        for i in 0..=70 {
            m.add_hit(WorldPoint::new(1.5, -1.0 + i as f64 * 0.05));
        }
        m.update_field(WorldPoint::new(5000.0, 0.0));
        let around = m.path_length_m(WorldPoint::new(0.05, 0.05)).unwrap();
        assert!(around > d + 0.5, "{around} vs {d}");
        // Any finite target, however far, leaves the grid as it is and gives a finite answer.
        let cells = m.cell_count();
        for far in [1e4, 1e12, 1e19, -1e300] {
            m.update_field(WorldPoint::new(far, far));
            assert_eq!(m.cell_count(), cells);
            assert!(m.path_length_m(WorldPoint::new(0.05, 0.05)).is_some());
        }
        assert!(!m.update_field(WorldPoint::new(f64::NAN, 0.0)));
    }

    #[test]
    fn grid_stops_growing_at_its_cell_budget() {
        let mut m = ObstacleMemory::new(0.1, 0.3);
        m.add_hit(WorldPoint::new(0.0, 0.0));
        // 10 km away: the grid would need 10^10 cells.
        m.add_hit(WorldPoint::new(10_000.0, 10_000.0));
        assert!(m.cell_count() <= MAX_CELLS);
        assert!(!m.is_blocked(WorldPoint::new(10_000.0, 10_000.0)));
        assert!(m.is_blocked(WorldPoint::new(0.0, 0.0)));
    }

    #[test]
    fn a_graded_memory_keeps_a_narrow_gap_open_at_a_higher_cost() {
        // A wall of hits on cell centres, y = 0.05, x = +-0.35 ... +-2.95: a gap of 0.7 m
        // between hit centres. Inflated by 0.3 m (3 cells) it is closed; lethal at 0.2 m
        // (2 cells) the columns x = -0.05 and 0.05 stay open, inside the 0.3 m band.
        let wall = |m: &mut ObstacleMemory| {
            for k in 3..30 {
                let x = k as f64 * 0.1 + 0.05;
                m.add_hit(WorldPoint::new(x, 0.05));
                m.add_hit(WorldPoint::new(-x, 0.05));
            }
        };
        let (start, target) = (WorldPoint::new(0.05, -1.95), WorldPoint::new(0.05, 2.05));
        // Radii a hair above whole cells: 3 x 0.1 is 0.30000000000000004 in floating point.
        let (lethal, band) = (0.2 + 1e-9, 0.3 + 1e-9);
        let mut full = ObstacleMemory::new(0.1, band);
        wall(&mut full);
        full.ensure_contains(start);
        full.update_field(target);
        // Around a wall end instead: more than 2 sqrt(3.2^2 + 2^2) = 7.55 m.
        let around = full.path_length_m(start).unwrap();
        assert!(around > 7.5, "{around}");
        let mut graded = ObstacleMemory::graded(0.1, lethal, band);
        wall(&mut graded);
        graded.ensure_contains(start);
        // Band closed: the same detour as the full memory's.
        graded.update_field(target);
        assert!((graded.path_length_m(start).unwrap() - around).abs() < 1e-9);
        graded.update_field_through(target, true);
        // Straight through: 40 steps of 0.1 m, the one into the wall's row (in the band)
        // at three times the cost: 4.2 m.
        let through = graded.path_length_m(start).unwrap();
        assert!(
            (through - (4.0 + 0.1 * f64::from(BAND_FACTOR - 1))).abs() < 1e-9,
            "{through}"
        );
        let gap = WorldPoint::new(0.05, 0.05);
        assert!(graded.is_in_band(gap) && !graded.is_blocked(gap));
        assert!(graded.is_blocked(WorldPoint::new(0.15, 0.05)));
        assert!(!graded.is_in_band(WorldPoint::new(0.05, 0.15)));
        assert!(full.is_blocked(gap) && !full.is_in_band(gap));
    }

    #[test]
    fn the_nearest_hit_is_the_nearest_hit_cell_centre() {
        // A wall of hits on the cell centres of row 0 (y = 0.05), x from -2.95 to 2.95.
        let mut m = ObstacleMemory::new(0.1, 0.3);
        for k in -30..30 {
            m.add_hit(WorldPoint::new(k as f64 * 0.1 + 0.05, 0.05));
        }
        let d = m.nearest_hit_m(WorldPoint::new(0.05, 0.22), 1.0).unwrap();
        assert!((d - 0.17).abs() < 1e-9, "{d}");
        // Past the wall's end at x = 2.95: 0.5 m along x, 0.3 m along y.
        let d = m.nearest_hit_m(WorldPoint::new(3.45, 0.35), 1.0).unwrap();
        assert!((d - 0.34f64.sqrt()).abs() < 1e-9, "{d}");
        assert_eq!(m.nearest_hit_m(WorldPoint::new(3.45, 0.35), 0.5), None);
        assert_eq!(m.nearest_hit_m(WorldPoint::new(50.0, 0.0), 1.0), None);
        assert_eq!(m.nearest_hit_m(WorldPoint::new(0.05, 0.05), f64::NAN), None);
    }
}
