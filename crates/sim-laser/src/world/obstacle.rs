//! Obstacles of a vector world and occupancy bitmaps: what a world is built from.

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

    pub(super) fn aabb(&self) -> ([f64; 2], [f64; 2]) {
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

pub(super) fn aabb_of(points: &[[f64; 2]]) -> ([f64; 2], [f64; 2]) {
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

impl Bitmap {
    /// Keeps free only the cells edge-connected to the free cell at `p`; false (no change) if none.
    pub fn keep_region_at(&mut self, p: [f64; 2]) -> bool {
        let fx = (p[0] - self.origin[0]) / self.cell_w_m;
        let fy = (p[1] - self.origin[1]) / self.cell_h_m;
        if !(fx >= 0.0 && fy >= 0.0 && fx < self.width as f64 && fy < self.height as f64) {
            return false;
        }
        let start = fy as usize * self.width + fx as usize;
        if self.occupied[start] {
            return false;
        }
        let mut linked = vec![false; self.occupied.len()];
        linked[start] = true;
        flood_edges(self.width, self.height, start, |n| {
            let enter = !self.occupied[n] && !linked[n];
            linked[n] |= enter;
            enter
        });
        for (cell, linked) in self.occupied.iter_mut().zip(linked) {
            *cell |= !linked;
        }
        true
    }
}

/// Fills from cell `start` of a `w` x `h` row-major grid through edge-sharing cells; `enter(k)`
/// marks cell `k` and says whether the fill goes on through it.
pub(crate) fn flood_edges(w: usize, h: usize, start: usize, mut enter: impl FnMut(usize) -> bool) {
    let mut todo = vec![start];
    while let Some(k) = todo.pop() {
        let (col, row) = (k % w, k / w);
        let next = [
            (col > 0).then(|| k - 1),
            (col + 1 < w).then(|| k + 1),
            (row > 0).then(|| k - w),
            (row + 1 < h).then(|| k + w),
        ];
        for n in next.into_iter().flatten() {
            if enter(n) {
                todo.push(n);
            }
        }
    }
}
