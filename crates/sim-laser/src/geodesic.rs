//! Evaluation only: the shortest path a disc robot can drive between two points of the true
//! world (the geodesic), the `l` of Success weighted by Path Length. The navigator never sees
//! it.
//!
//! The free space is [`FreeSpace`]'s grid (cells whose centre is at least the robot radius
//! from every obstacle); the path is found by Lazy Theta* (A* whose nodes may take any
//! visible earlier node as parent), so it runs at any angle rather than along 8 directions.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use scan_types::WorldPoint;

use crate::{FreeSpace, SimError, World};

/// Grid cell of the geodesic, metres.
pub const GEODESIC_CELL_M: f64 = 0.025;

/// Most grid cells a geodesic may use (a 75 m x 75 m world at [`GEODESIC_CELL_M`]).
pub const GEODESIC_MAX_CELLS: usize = 9_000_000;

/// Farthest a start or goal is moved to reach a free cell, metres.
pub const GEODESIC_SNAP_M: f64 = 0.25;

/// The free space of a world for a disc robot, for shortest paths between its points.
///
/// ```
/// use scan_types::WorldPoint;
/// use sim_laser::{GeodesicMap, World};
/// let map = GeodesicMap::new(&World::paper(), 0.3).unwrap();
/// let l = map.length_m(WorldPoint::new(-3.92, -4.26), WorldPoint::new(4.0, 4.0)).unwrap();
/// // Never shorter than the straight line (11.47 m).
/// assert!(l >= 11.47);
/// ```
pub struct GeodesicMap {
    free: FreeSpace,
}

impl GeodesicMap {
    /// The free space of `world` for a disc of `radius_m`, on cells of [`GEODESIC_CELL_M`].
    pub fn new(world: &World, radius_m: f64) -> Result<Self, SimError> {
        Self::with_cell(world, radius_m, GEODESIC_CELL_M)
    }

    /// As [`GeodesicMap::new`] on cells of `cell_m`; an error for a bad radius or cell, or a
    /// world needing more than [`GEODESIC_MAX_CELLS`] cells.
    pub fn with_cell(world: &World, radius_m: f64, cell_m: f64) -> Result<Self, SimError> {
        if !(radius_m.is_finite() && radius_m >= 0.0) {
            return Err(SimError::InvalidConfig {
                field: "robot radius",
                message: format!("must be finite and >= 0, got {radius_m}"),
            });
        }
        if !(cell_m.is_finite() && cell_m > 0.0) {
            return Err(SimError::InvalidConfig {
                field: "geodesic cell",
                message: format!("must be finite and > 0, got {cell_m}"),
            });
        }
        let (lo, hi) = world.bounds();
        let (w, h) = (hi.x_m() - lo.x_m(), hi.y_m() - lo.y_m());
        let cells = (w / cell_m).ceil().max(1.0) * (h / cell_m).ceil().max(1.0);
        if cells.is_nan() || cells > GEODESIC_MAX_CELLS as f64 {
            return Err(SimError::WorldTooLarge {
                world: world.name().to_string(),
                width_m: w,
                height_m: h,
                cell_m,
                max_cells: GEODESIC_MAX_CELLS,
            });
        }
        Ok(Self {
            free: FreeSpace::new(world, radius_m, cell_m),
        })
    }

    /// The shortest free path from `start` to `goal`, both ends included, or `None` when
    /// either end is more than [`GEODESIC_SNAP_M`] from free space or no free path joins them.
    pub fn path(&self, start: WorldPoint, goal: WorldPoint) -> Option<Vec<WorldPoint>> {
        let s = self.snap(start)?;
        let g = self.snap(goal)?;
        if self.free.region(s) != self.free.region(g) {
            return None;
        }
        let cells = self.search(s, g)?;
        let mut points: Vec<WorldPoint> = cells.iter().map(|&k| self.free.centre(k)).collect();
        // The path runs from and to the given points, not their cells' centres.
        if points.len() < 2 {
            return Some(vec![start, goal]);
        }
        points[0] = start;
        let last = points.len() - 1;
        points[last] = goal;
        Some(points)
    }

    /// The length of [`GeodesicMap::path`], metres.
    pub fn length_m(&self, start: WorldPoint, goal: WorldPoint) -> Option<f64> {
        let p = self.path(start, goal)?;
        Some(p.windows(2).map(|w| w[0].distance_m(&w[1])).sum())
    }

    /// The free cell whose centre is nearest `p`, within [`GEODESIC_SNAP_M`].
    fn snap(&self, p: WorldPoint) -> Option<usize> {
        if !(p.x_m().is_finite() && p.y_m().is_finite()) {
            return None;
        }
        let (nx, ny) = self.free.dims();
        let cell = self.free.cell_m();
        let lo = self.free.origin();
        let reach = (GEODESIC_SNAP_M / cell).ceil() as i64;
        // Saturating casts: a point far outside the grid finds no cell.
        let cx = ((p.x_m() - lo.x_m()) / cell).floor() as i64;
        let cy = ((p.y_m() - lo.y_m()) / cell).floor() as i64;
        let xs = cx.saturating_sub(reach).max(0)..=cx.saturating_add(reach).min(nx as i64 - 1);
        let ys = cy.saturating_sub(reach).max(0)..=cy.saturating_add(reach).min(ny as i64 - 1);
        let mut best: Option<(f64, usize)> = None;
        for y in ys {
            for x in xs.clone() {
                let k = y as usize * nx + x as usize;
                if !self.free.is_free(k) {
                    continue;
                }
                let d = self.free.centre(k).distance_m(&p);
                if d <= GEODESIC_SNAP_M && best.is_none_or(|(b, _)| d < b) {
                    best = Some((d, k));
                }
            }
        }
        best.map(|(_, k)| k)
    }

    /// Lazy Theta* from cell `s` to cell `g`: the path's corner cells, `s` first.
    fn search(&self, s: usize, g: usize) -> Option<Vec<usize>> {
        let (nx, ny) = self.free.dims();
        let n = nx * ny;
        let xy = |k: usize| ((k % nx) as f64, (k / nx) as f64);
        let dist = |a: usize, b: usize| {
            let ((ax, ay), (bx, by)) = (xy(a), xy(b));
            (ax - bx).hypot(ay - by)
        };
        // Non-negative f64s order as their bit patterns.
        let key = |f: f64| f.to_bits();
        let mut cost = vec![f64::INFINITY; n];
        let mut parent = vec![usize::MAX; n];
        let mut closed = vec![false; n];
        let mut open = BinaryHeap::new();
        cost[s] = 0.0;
        parent[s] = s;
        open.push(Reverse((key(dist(s, g)), s)));
        while let Some(Reverse((_, k))) = open.pop() {
            if closed[k] {
                continue;
            }
            // k was reached assuming its parent sees it; if not, its best expanded neighbour
            // (the one it was reached from is one) becomes its parent.
            let p = parent[k];
            if p != k && !self.visible(p, k) {
                let mut best = (f64::INFINITY, k);
                for m in self.neighbours(k).into_iter().flatten() {
                    let c = cost[m] + dist(m, k);
                    if closed[m] && c < best.0 {
                        best = (c, m);
                    }
                }
                (cost[k], parent[k]) = best;
            }
            closed[k] = true;
            if k == g {
                break;
            }
            let p = parent[k];
            for m in self.neighbours(k).into_iter().flatten() {
                if closed[m] {
                    continue;
                }
                let c = cost[p] + dist(p, m);
                if c < cost[m] {
                    cost[m] = c;
                    parent[m] = p;
                    open.push(Reverse((key(c + dist(m, g)), m)));
                }
            }
        }
        if !closed[g] {
            return None;
        }
        let mut cells = vec![g];
        let mut k = g;
        while k != s {
            k = parent[k];
            if k >= n || cells.len() > n {
                return None;
            }
            cells.push(k);
        }
        cells.reverse();
        Some(cells)
    }

    /// The free 8-neighbours of cell `k`; a diagonal only when both cells beside it are free.
    fn neighbours(&self, k: usize) -> [Option<usize>; 8] {
        let (nx, ny) = self.free.dims();
        let (x, y) = ((k % nx) as i64, (k / nx) as i64);
        let at = |dx: i64, dy: i64| {
            let (xx, yy) = (x + dx, y + dy);
            let inside = xx >= 0 && yy >= 0 && xx < nx as i64 && yy < ny as i64;
            let kk = yy as usize * nx + xx as usize;
            (inside && self.free.is_free(kk)).then_some(kk)
        };
        let (e, w, north, south) = (at(1, 0), at(-1, 0), at(0, 1), at(0, -1));
        let diag = |a: Option<usize>, b: Option<usize>, dx, dy| {
            if a.is_some() && b.is_some() {
                at(dx, dy)
            } else {
                None
            }
        };
        [
            e,
            w,
            north,
            south,
            diag(e, north, 1, 1),
            diag(w, north, -1, 1),
            diag(e, south, 1, -1),
            diag(w, south, -1, -1),
        ]
    }

    /// Whether the segment between the centres of cells `a` and `b` crosses only free cells
    /// (through a cell corner, both cells beside the corner must be free).
    fn visible(&self, a: usize, b: usize) -> bool {
        let (nx, _) = self.free.dims();
        let free = |x: i64, y: i64| self.free.is_free(y as usize * nx + x as usize);
        let (mut x, mut y) = ((a % nx) as i64, (a / nx) as i64);
        let (dx, dy) = ((b % nx) as i64 - x, (b / nx) as i64 - y);
        let (sx, sy) = (dx.signum(), dy.signum());
        let (ax, ay) = (dx.abs(), dy.abs());
        let (mut i, mut j) = (0, 0);
        while i < ax || j < ay {
            // From the centre, the segment crosses its (i+1)-th column border at parameter
            // (i + 1/2)/ax and its (j+1)-th row border at (j + 1/2)/ay.
            let (tx, ty) = ((2 * i + 1) * ay, (2 * j + 1) * ax);
            if tx == ty {
                if !free(x + sx, y) || !free(x, y + sy) {
                    return false;
                }
                x += sx;
                y += sy;
                i += 1;
                j += 1;
            } else if tx < ty {
                x += sx;
                i += 1;
            } else {
                y += sy;
                j += 1;
            }
            if !free(x, y) {
                return false;
            }
        }
        true
    }
}

/// The geodesic from `start` to `goal` in `world` for a disc of `radius_m` (see
/// [`GeodesicMap`]); `Ok(None)` when no free path joins them.
pub fn geodesic_m(
    world: &World,
    radius_m: f64,
    start: WorldPoint,
    goal: WorldPoint,
) -> Result<Option<f64>, SimError> {
    Ok(GeodesicMap::new(world, radius_m)?.length_m(start, goal))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Obstacle, WorldParts};

    /// A closed box (-5, -5)..(5, 5) of zero-thickness walls with `inner` walls inside.
    fn boxed(inner: &[([f64; 2], [f64; 2])]) -> World {
        let corners = [[-5.0, -5.0], [5.0, -5.0], [5.0, 5.0], [-5.0, 5.0]];
        let mut obstacles: Vec<Obstacle> = (0..4)
            .map(|i| Obstacle::Segment {
                a: corners[i],
                b: corners[(i + 1) % 4],
            })
            .collect();
        obstacles.extend(inner.iter().map(|&(a, b)| Obstacle::Segment { a, b }));
        World::from_parts(WorldParts {
            name: "test".into(),
            obstacles,
            ..WorldParts::default()
        })
        .unwrap()
    }

    fn pt(x: f64, y: f64) -> WorldPoint {
        WorldPoint::new(x, y)
    }

    #[test]
    fn wraps_around_the_eroded_end_of_a_wall() {
        // Wall (0, -5)..(0, 1); start S = (-2, 0), goal G = (2, 0). For a disc of radius r the
        // wall grows by r, so its free end is the circle of radius r about C = (0, 1). The
        // shortest path is the tangent from S to that circle, the arc over its top, and the
        // symmetric tangent down to G. With d = |SC| = sqrt(5):
        //   tangent  t = sqrt(d^2 - r^2)                       (right angle at the tangent point)
        //   angle at C between CS and the tangent point: alpha = acos(r / d)
        //   angle at C between CS and straight up (+y):  phi   = acos(CS.y / d) = acos(-1 / d)
        //   each half's arc spans phi - alpha, so  L = 2 t + 2 r (phi - alpha).
        // r = 0.3: L = 4.7906 m (the straight line, 4 m, is blocked; 2 d = 4.472 m is only
        // the zero-radius limit).
        let world = boxed(&[([0.0, -5.0], [0.0, 1.0])]);
        for r in [0.3, 0.5] {
            let d = 5f64.sqrt();
            let t = (d * d - r * r).sqrt();
            let (phi, alpha) = ((-1.0 / d).acos(), (r / d).acos());
            let hand = 2.0 * t + 2.0 * r * (phi - alpha);
            let map = GeodesicMap::new(&world, r).unwrap();
            let got = map.length_m(pt(-2.0, 0.0), pt(2.0, 0.0)).unwrap();
            assert!(
                (got - hand).abs() / hand < 0.015,
                "r {r}: geodesic {got}, by hand {hand}"
            );
            // It passes above the wall's end, at least r from it.
            let path = map.path(pt(-2.0, 0.0), pt(2.0, 0.0)).unwrap();
            assert!(path.iter().any(|p| p.y_m() > 1.0 + r * 0.9), "{path:?}");
        }
    }

    #[test]
    fn open_space_is_the_straight_line() {
        let world = boxed(&[]);
        let map = GeodesicMap::new(&world, 0.3).unwrap();
        for (a, b) in [
            (pt(-3.0, 0.0), pt(3.0, 0.0)),
            (pt(-3.0, -2.0), pt(3.0, 2.5)),
            (pt(1.0, 4.0), pt(-2.5, -4.1)),
        ] {
            let straight = a.distance_m(&b);
            let got = map.length_m(a, b).unwrap();
            assert!((got - straight).abs() < 1e-9, "{got} vs {straight}");
        }
        // Start and goal in one cell.
        let got = map.length_m(pt(0.0, 0.0), pt(0.01, 0.0)).unwrap();
        assert!((got - 0.01).abs() < 1e-12);
    }

    #[test]
    fn enclosed_goal_and_narrow_gap() {
        // The goal inside a closed 1 m square: no path.
        let square = [
            ([2.0, 2.0], [3.0, 2.0]),
            ([3.0, 2.0], [3.0, 3.0]),
            ([3.0, 3.0], [2.0, 3.0]),
            ([2.0, 3.0], [2.0, 2.0]),
        ];
        let world = boxed(&square);
        let map = GeodesicMap::new(&world, 0.3).unwrap();
        assert_eq!(map.length_m(pt(-3.0, -3.0), pt(2.5, 2.5)), None);
        // A wall across the box at x = 0 with a 0.5 m gap at y in (0, 0.5): a 0.2 m disc
        // passes straight through (6 m), a 0.3 m disc cannot pass at all.
        let world = boxed(&[([0.0, -5.0], [0.0, 0.0]), ([0.0, 0.5], [0.0, 5.0])]);
        let (a, b) = (pt(-3.0, 0.25), pt(3.0, 0.25));
        let thin = GeodesicMap::new(&world, 0.2)
            .unwrap()
            .length_m(a, b)
            .unwrap();
        assert!((thin - 6.0).abs() < 1e-9, "{thin}");
        assert_eq!(GeodesicMap::new(&world, 0.3).unwrap().length_m(a, b), None);
    }

    #[test]
    fn bad_input_is_an_error_or_none() {
        let world = boxed(&[]);
        assert!(GeodesicMap::new(&world, -0.1).is_err());
        assert!(GeodesicMap::new(&world, f64::NAN).is_err());
        assert!(GeodesicMap::with_cell(&world, 0.3, 0.0).is_err());
        let map = GeodesicMap::new(&world, 0.3).unwrap();
        assert_eq!(map.length_m(pt(f64::NAN, 0.0), pt(1.0, 0.0)), None);
        assert_eq!(map.length_m(pt(0.0, 0.0), pt(1e300, -1e300)), None);
        // Inside the box's wall band (within r of the wall) but within the snap radius.
        assert!(map.length_m(pt(-4.9, 0.0), pt(0.0, 0.0)).is_some());
        // 2 km x 2 km: 6.4e9 cells of 0.025 m.
        let huge = World::from_parts(WorldParts {
            name: "huge".into(),
            obstacles: vec![Obstacle::Segment {
                a: [-1000.0, -1000.0],
                b: [1000.0, 1000.0],
            }],
            ..WorldParts::default()
        })
        .unwrap();
        let e = GeodesicMap::new(&huge, 0.3).err().unwrap().to_string();
        assert!(
            e.contains("huge") && e.contains("2000.0 m x 2000.0 m"),
            "{e}"
        );
    }
}
