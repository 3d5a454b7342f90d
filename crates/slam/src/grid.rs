//! A likelihood field over a submap's points, with max-pooled copies for branch and bound.

use std::rc::Rc;

use scan_types::{floor_i32, floor_i64};

/// Field values are stored as `u8`: 255 on a point, falling off as a Gaussian.
pub(crate) const FULL: u32 = 255;

/// The likelihood field of a point set on a square grid, and its max-pooled levels: level `k`
/// holds at each cell the largest level-0 value of the `2^k` x `2^k` block that starts there.
#[derive(Debug, Clone)]
pub(crate) struct ScoreGrid {
    /// World coordinates of the lower-left corner of cell (0, 0).
    pub(crate) origin: [f64; 2],
    pub(crate) resolution_m: f64,
    width: usize,
    height: usize,
    levels: Vec<Vec<u8>>,
}

impl ScoreGrid {
    /// The field of `points` (world frame) with Gaussian fall-off `sigma_m`, and `depth`
    /// max-pooled levels above it. The grid reaches `window_cells + 2^depth` cells beyond the
    /// field, so that a block of a search that shifts a point by up to `window_cells` never
    /// starts below the grid while it overlaps the field. `None` without points.
    pub(crate) fn new(
        points: &[[f64; 2]],
        resolution_m: f64,
        sigma_m: f64,
        depth: usize,
        window_cells: usize,
    ) -> Option<Self> {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for p in points {
            for k in 0..2 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if points.is_empty() || !(lo[0].is_finite() && hi[0].is_finite()) {
            return None;
        }
        let radius = (2.5 * sigma_m / resolution_m).ceil() as usize;
        let margin = (radius + 1 + window_cells + (1 << depth)) as f64 * resolution_m;
        // Cells on the world's lattice of `resolution_m`.
        let origin = [
            ((lo[0] - margin) / resolution_m).floor() * resolution_m,
            ((lo[1] - margin) / resolution_m).floor() * resolution_m,
        ];
        let width = ((hi[0] - lo[0] + 2.0 * margin) / resolution_m).ceil() as usize + 1;
        let height = ((hi[1] - lo[1] + 2.0 * margin) / resolution_m).ceil() as usize + 1;
        let kernel = Kernel::cached(radius, resolution_m, sigma_m);
        // Room past the last cell for a whole padded patch row (zeros there change nothing).
        let mut base = vec![0u8; width * height + kernel.stride];
        let r = radius as i64;
        let (w, h) = (width as i64, height as i64);
        for p in points {
            let fx = (p[0] - origin[0]) / resolution_m;
            let fy = (p[1] - origin[1]) / resolution_m;
            let (cx, cy) = (floor_i64(fx), floor_i64(fy));
            let patch = kernel.patch(fx - cx as f64, fy - cy as f64);
            if cx - r >= 0 && cx + r < w && cy - r >= 0 && cy + r < h {
                // Inside the grid (the margin sees to it): whole padded rows, which vectorise;
                // a row's padding lands on cells to its right, or on the next row's first
                // cells, and leaves them as they are.
                for (j, src) in patch.chunks_exact(kernel.stride).enumerate() {
                    let start = (cy - r) as usize * width + j * width + (cx - r) as usize;
                    let dst = &mut base[start..start + kernel.stride];
                    for (d, s) in dst.chunks_exact_mut(LANES).zip(src.chunks_exact(LANES)) {
                        max_lanes(d.try_into().expect("LANES"), s.try_into().expect("LANES"));
                    }
                }
                continue;
            }
            let (x0, x1) = ((cx - r).max(0), (cx + r).min(w - 1));
            if x0 > x1 {
                continue;
            }
            for y in (cy - r).max(0)..=(cy + r).min(h - 1) {
                let k = (y - cy + r) as usize * kernel.stride;
                let src = &patch[k + (x0 - cx + r) as usize..=k + (x1 - cx + r) as usize];
                let start = y as usize * width;
                max_assign(&mut base[start + x0 as usize..=start + x1 as usize], src);
            }
        }
        base.truncate(width * height);
        let mut levels = vec![base];
        for k in 1..=depth {
            let next = pool(&levels[k - 1], width, height, 1usize << (k - 1));
            levels.push(next);
        }
        Some(Self {
            origin,
            resolution_m,
            width,
            height,
            levels,
        })
    }

    /// The highest level.
    pub(crate) fn depth(&self) -> usize {
        self.levels.len() - 1
    }

    /// The value of level `k` at cell (`x`, `y`); 0 outside the grid.
    #[inline]
    pub(crate) fn value(&self, k: usize, x: i32, y: i32) -> u32 {
        if x < 0 || y < 0 || x as usize >= self.width || y as usize >= self.height {
            return 0;
        }
        u32::from(self.levels[k][y as usize * self.width + x as usize])
    }

    /// Cells along x and along y.
    pub(crate) fn size(&self) -> [usize; 2] {
        [self.width, self.height]
    }

    /// The cells of level `k`, row after row.
    #[inline]
    pub(crate) fn level(&self, k: usize) -> &[u8] {
        &self.levels[k]
    }

    /// The cell holding world point `p` (may lie outside the grid).
    #[inline]
    pub(crate) fn cell(&self, p: [f64; 2]) -> [i32; 2] {
        [
            floor_i32((p[0] - self.origin[0]) / self.resolution_m),
            floor_i32((p[1] - self.origin[1]) / self.resolution_m),
        ]
    }
}

/// The level above `prev` (`width` x `height`): at each cell the largest of `prev` at the
/// cell and `s` cells right, up, and both (0 beyond the grid). Row slices, so that the
/// maxima vectorise.
fn pool(prev: &[u8], width: usize, height: usize, s: usize) -> Vec<u8> {
    let mut cur = vec![0u8; width * height];
    let keep = width.saturating_sub(s);
    for (row, out) in prev.chunks_exact(width).zip(cur.chunks_exact_mut(width)) {
        let (head, tail) = out.split_at_mut(keep);
        head.copy_from_slice(&row[..keep]);
        max_assign(head, &row[s.min(width)..]);
        tail.copy_from_slice(&row[keep..]);
    }
    // Rows in order: row y + s is still the horizontal maximum when row y reads it.
    for y in 0..height.saturating_sub(s) {
        let (lower, upper) = cur.split_at_mut((y + s) * width);
        max_assign(&mut lower[y * width..(y + 1) * width], &upper[..width]);
    }
    cur
}

/// Sub-cell steps of a point's position in the field's kernel table (a point is placed to
/// within 1 / 32 of a cell).
const SUB: usize = 16;

/// Bytes a patch row is padded to a multiple of (one SIMD register).
const LANES: usize = 16;

/// `d = max(d, s)` element by element over `d` (`s` at least as long), a vector at a time.
fn max_assign(d: &mut [u8], s: &[u8]) {
    let s = &s[..d.len()];
    let mut dc = d.chunks_exact_mut(LANES);
    let mut sc = s.chunks_exact(LANES);
    for (d, s) in (&mut dc).zip(&mut sc) {
        max_lanes(d.try_into().expect("LANES"), s.try_into().expect("LANES"));
    }
    for (d, s) in dc.into_remainder().iter_mut().zip(sc.remainder()) {
        *d = (*d).max(*s);
    }
}

/// `d = max(d, s)` lane by lane (one vector instruction).
#[inline(always)]
fn max_lanes(d: &mut [u8; LANES], s: &[u8; LANES]) {
    for i in 0..LANES {
        d[i] = d[i].max(s[i]);
    }
}

/// The Gaussian fall-off around a point, tabulated for the point at `SUB + 1` positions
/// along each axis within its cell: each patch of `width` x `width` cells holds the product
/// of an x and a y factor (each `sqrt(FULL)` at the point), rounded, so that no exponential
/// or product is evaluated per cell.
struct Kernel {
    width: usize,
    /// Row length in `patches`: `width` padded with zeros to a multiple of `LANES`.
    stride: usize,
    /// `(SUB + 1)^2` patches, row after row: patch `qy * (SUB + 1) + qx` for a point `qx /
    /// SUB` and `qy / SUB` into its cell, entry `j * stride + i` for the cell `i - radius`
    /// right of it and `j - radius` above.
    patches: Vec<u8>,
}

/// A kernel's parameters: radius in cells, the bits of the resolution and of sigma.
type KernelKey = (usize, u64, u64);

thread_local! {
    /// The last kernel built on this thread: a front end rebuilds its field at every keyframe
    /// with the same parameters.
    static LAST_KERNEL: std::cell::RefCell<Option<(KernelKey, Rc<Kernel>)>> =
        const { std::cell::RefCell::new(None) };
}

impl Kernel {
    /// [`Kernel::new`], built once per thread for the same parameters.
    fn cached(radius: usize, resolution_m: f64, sigma_m: f64) -> Rc<Self> {
        let key = (radius, resolution_m.to_bits(), sigma_m.to_bits());
        LAST_KERNEL.with_borrow_mut(|last| match last {
            Some((k, kernel)) if *k == key => Rc::clone(kernel),
            _ => {
                let kernel = Rc::new(Self::new(radius, resolution_m, sigma_m));
                *last = Some((key, Rc::clone(&kernel)));
                kernel
            }
        })
    }

    fn new(radius: usize, resolution_m: f64, sigma_m: f64) -> Self {
        let width = 2 * radius + 1;
        let inv = 1.0 / (2.0 * sigma_m * sigma_m);
        let mut factors = Vec::with_capacity((SUB + 1) * width);
        for q in 0..=SUB {
            let f = q as f64 / SUB as f64;
            for j in 0..width {
                let d = (j as f64 - radius as f64 + 0.5 - f) * resolution_m;
                factors.push((-d * d * inv).exp() * (FULL as f64).sqrt());
            }
        }
        let stride = width.div_ceil(LANES) * LANES;
        let mut patches = Vec::with_capacity((SUB + 1) * (SUB + 1) * width * stride);
        for qy in 0..=SUB {
            for qx in 0..=SUB {
                for wy in &factors[qy * width..(qy + 1) * width] {
                    // +0.5 and truncation: rounding without a libm call.
                    patches.extend(
                        factors[qx * width..(qx + 1) * width]
                            .iter()
                            .map(|wx| (wy * wx + 0.5) as u8),
                    );
                    patches.resize(patches.len() + stride - width, 0);
                }
            }
        }
        Self {
            width,
            stride,
            patches,
        }
    }

    /// The patch for a point `fx`, `fy` (0..1) into its cell.
    fn patch(&self, fx: f64, fy: f64) -> &[u8] {
        let q = |f: f64| ((f * SUB as f64 + 0.5) as usize).min(SUB);
        let n = self.width * self.stride;
        let k = q(fy) * (SUB + 1) + q(fx);
        &self.patches[k * n..(k + 1) * n]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_peaks_at_its_cell_and_levels_bound_their_blocks() {
        // One point at the centre of a 0.1 m cell: that cell reads 255, a neighbour
        // 0.1 m away reads 255 exp(-0.01 / 0.02) = 154.7.
        let g = ScoreGrid::new(&[[0.05, 0.05]], 0.1, 0.1, 3, 2).unwrap();
        let c = g.cell([0.05, 0.05]);
        assert_eq!(g.value(0, c[0], c[1]), 255);
        assert_eq!(g.value(0, c[0] + 1, c[1]), 155);
        assert_eq!(g.value(0, -5, 0), 0);
        // Every level-k cell is the max of its block at level 0.
        for k in 1..=g.depth() {
            let s = 1i32 << k;
            for y in 0..g.height as i32 {
                for x in 0..g.width as i32 {
                    let mut m = 0;
                    for yy in y..y + s {
                        for xx in x..x + s {
                            m = m.max(g.value(0, xx, yy));
                        }
                    }
                    assert_eq!(g.value(k, x, y), m, "level {k} at ({x}, {y})");
                }
            }
        }
        assert!(ScoreGrid::new(&[], 0.1, 0.1, 3, 2).is_none());
    }

    #[test]
    fn tabulated_field_follows_the_gaussian() {
        // Points anywhere in their cells: every cell holds the largest
        // 255 exp(-d^2 / (2 sigma^2)) over the points, to within the 1/32-cell placement
        // (the slope is at most 255 / (sigma sqrt e) = 773 per metre for sigma 0.2 m: 2.4
        // for 0.1 / 32 m on each axis, 3.4 on both) and the rounding (0.5): 3.9.
        let pts = [[0.013, 0.771], [0.49, 0.52], [1.234, -0.377], [0.7, 0.7]];
        let (res, sigma) = (0.1, 0.2);
        let g = ScoreGrid::new(&pts, res, sigma, 2, 3).unwrap();
        for y in 0..g.height as i32 {
            for x in 0..g.width as i32 {
                let cx = g.origin[0] + (x as f64 + 0.5) * res;
                let cy = g.origin[1] + (y as f64 + 0.5) * res;
                let radius = 2.5 * sigma / res;
                let want = pts
                    .iter()
                    .filter(|p| {
                        // Only cells within the kernel's square around the point's cell.
                        let px = ((p[0] - g.origin[0]) / res).floor();
                        let py = ((p[1] - g.origin[1]) / res).floor();
                        (x as f64 - px).abs() <= radius.ceil()
                            && (y as f64 - py).abs() <= radius.ceil()
                    })
                    .map(|p| {
                        let d2 = (cx - p[0]).powi(2) + (cy - p[1]).powi(2);
                        255.0 * (-d2 / (2.0 * sigma * sigma)).exp()
                    })
                    .fold(0.0, f64::max);
                let got = f64::from(g.value(0, x, y));
                assert!((got - want).abs() <= 3.9, "({x}, {y}): {got} vs {want}");
            }
        }
    }
}
