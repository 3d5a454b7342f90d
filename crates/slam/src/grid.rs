//! A likelihood field over a submap's points, with max-pooled copies for branch and bound.

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
        let mut base = vec![0u8; width * height];
        let r = radius as i64;
        let inv = 1.0 / (2.0 * sigma_m * sigma_m);
        for p in points {
            let cx = ((p[0] - origin[0]) / resolution_m).floor() as i64;
            let cy = ((p[1] - origin[1]) / resolution_m).floor() as i64;
            for y in (cy - r).max(0)..=(cy + r).min(height as i64 - 1) {
                let dy = origin[1] + (y as f64 + 0.5) * resolution_m - p[1];
                for x in (cx - r).max(0)..=(cx + r).min(width as i64 - 1) {
                    let dx = origin[0] + (x as f64 + 0.5) * resolution_m - p[0];
                    let v = (FULL as f64 * (-(dx * dx + dy * dy) * inv).exp()).round() as u8;
                    let cell = &mut base[y as usize * width + x as usize];
                    *cell = (*cell).max(v);
                }
            }
        }
        let mut levels = vec![base];
        for k in 1..=depth {
            let prev = &levels[k - 1];
            let s = 1usize << (k - 1);
            let at = |x: usize, y: usize| {
                if x < width && y < height {
                    prev[y * width + x]
                } else {
                    0
                }
            };
            let mut cur = vec![0u8; width * height];
            for y in 0..height {
                for x in 0..width {
                    cur[y * width + x] = at(x, y)
                        .max(at(x + s, y))
                        .max(at(x, y + s))
                        .max(at(x + s, y + s));
                }
            }
            levels.push(cur);
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

    /// The cell holding world point `p` (may lie outside the grid).
    #[inline]
    pub(crate) fn cell(&self, p: [f64; 2]) -> [i32; 2] {
        [
            ((p[0] - self.origin[0]) / self.resolution_m).floor() as i32,
            ((p[1] - self.origin[1]) / self.resolution_m).floor() as i32,
        ]
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
}
