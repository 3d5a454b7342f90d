//! The match target: reference hits with normals in a common frame, and their nearest-point
//! index.

use scan_types::{Pose2, Scan, ScanGeometry};

use super::MatchParams;
use super::surface::{Oriented, oriented_hits};

/// Side of a cell of the nearest-neighbour index, metres.
const CELL_M: f64 = 0.04;

/// Radius of the first, narrow nearest-neighbour search, metres.
const NEAR_M: f64 = 0.02;

/// Reference points (hits with surface normals) in one frame, indexed for nearest-neighbour
/// search.
#[derive(Debug, Clone)]
pub struct MatchTarget {
    pub(super) points: Vec<Oriented>,
    /// Lower-left corner of cell (0, 0) and the grid size.
    pub(super) origin: [f64; 2],
    pub(super) width: usize,
    pub(super) height: usize,
    /// Cell start offsets into `sorted` (width * height + 1 entries).
    pub(super) starts: Vec<u32>,
    /// The points sorted by cell (by index within a cell).
    pub(super) sorted: Vec<Oriented>,
    pub(super) dirty: bool,
}

impl Default for MatchTarget {
    fn default() -> Self {
        Self::new()
    }
}

impl MatchTarget {
    /// An empty target.
    pub fn new() -> Self {
        Self {
            points: Vec::new(),
            origin: [0.0, 0.0],
            width: 0,
            height: 0,
            starts: Vec::new(),
            sorted: Vec::new(),
            dirty: false,
        }
    }

    /// A target holding one scan, in that scan's own frame.
    pub fn from_scan(geometry: &ScanGeometry, scan: &Scan, params: &MatchParams) -> Self {
        let mut t = Self::new();
        t.add_scan(&Pose2::default(), geometry, scan, params);
        t
    }

    /// Number of reference points (hits with a fitted normal).
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// True when the target holds no point.
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// Adds the hits of `scan` taken at `pose` (in the target's frame) that have a surface normal.
    pub fn add_scan(
        &mut self,
        pose: &Pose2,
        geometry: &ScanGeometry,
        scan: &Scan,
        params: &MatchParams,
    ) {
        self.push_moved(pose, oriented_hits(geometry, scan, params, 1));
    }

    /// Adds the reference points of `other` (in its own frame) placed at `pose` in this
    /// target's frame: the same as adding `other`'s scans again, without refitting normals.
    pub fn add_target(&mut self, pose: &Pose2, other: &MatchTarget) {
        self.push_moved(pose, other.points.iter().copied());
    }

    /// Keeps one point per `cell_m` square and 45 deg sector of normal direction: the first
    /// added, so a caller that adds its most trusted scans first keeps theirs. Overlapping
    /// scans of one wall otherwise stack many points per centimetre of it.
    pub fn thin(&mut self, cell_m: f64) {
        if !(cell_m > 0.0 && cell_m.is_finite()) {
            return;
        }
        let mut seen = std::collections::HashSet::new();
        self.points.retain(|o| {
            if !is_finite2(o.p) {
                return false;
            }
            // Sectors -4..3: +180 deg is -180 deg.
            let octant = match (o.n[1].atan2(o.n[0]) / std::f64::consts::FRAC_PI_4).floor() as i64 {
                4 => -4,
                k => k,
            };
            seen.insert((
                (o.p[0] / cell_m).floor() as i64,
                (o.p[1] / cell_m).floor() as i64,
                octant,
            ))
        });
        self.dirty = true;
    }

    fn push_moved(&mut self, pose: &Pose2, points: impl IntoIterator<Item = Oriented>) {
        let (s, c) = pose.theta_rad.sin_cos();
        for o in points {
            self.points.push(Oriented {
                p: [
                    pose.x_m + c * o.p[0] - s * o.p[1],
                    pose.y_m + s * o.p[0] + c * o.p[1],
                ],
                n: [c * o.n[0] - s * o.n[1], s * o.n[0] + c * o.n[1]],
            });
        }
        self.dirty = true;
    }

    pub(super) fn index(&mut self) {
        if !self.dirty {
            return;
        }
        self.dirty = false;
        self.sorted.clear();
        self.starts.clear();
        // Non-finite points can never match: leave them out of the index.
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for o in self.points.iter().filter(|o| is_finite2(o.p)) {
            for k in 0..2 {
                lo[k] = lo[k].min(o.p[k]);
                hi[k] = hi[k].max(o.p[k]);
            }
        }
        if lo[0] > hi[0] {
            self.width = 0;
            self.height = 0;
            return;
        }
        self.origin = lo;
        self.width = floor_nonneg((hi[0] - lo[0]) / CELL_M) + 1;
        self.height = floor_nonneg((hi[1] - lo[1]) / CELL_M) + 1;
        let cells = self.width * self.height;
        // Counting sort: points per cell, then each cell's end, then filled from the back.
        let mut starts = vec![0u32; cells + 1];
        let cell_of: Vec<Option<usize>> = self
            .points
            .iter()
            .map(|o| is_finite2(o.p).then(|| self.cell(o.p)))
            .collect();
        for &c in cell_of.iter().flatten() {
            starts[c] += 1;
        }
        let mut end = 0u32;
        for v in &mut starts {
            end += *v;
            *v = end;
        }
        let placeholder = Oriented {
            p: [0.0; 2],
            n: [0.0; 2],
        };
        self.sorted = vec![placeholder; end as usize];
        for (o, c) in self.points.iter().zip(&cell_of).rev() {
            if let Some(c) = *c {
                starts[c] -= 1;
                self.sorted[starts[c] as usize] = *o;
            }
        }
        // Now `starts[c]` is where cell c begins and `starts[cells]` the total.
        self.starts = starts;
    }

    pub(super) fn cell(&self, p: [f64; 2]) -> usize {
        let cx = floor_nonneg((p[0] - self.origin[0]) / CELL_M).min(self.width - 1);
        let cy = floor_nonneg((p[1] - self.origin[1]) / CELL_M).min(self.height - 1);
        cy * self.width + cx
    }

    /// The reference point nearest `q` within `gate` whose normal agrees with `n`, as an
    /// index into `sorted`, given the index of a point `hint` that is probably near `q` (the
    /// match of the previous iteration).
    ///
    /// First searches the cells within `min(gate, NEAR_M, distance to the hint)` of `q`: a
    /// point found there nearer than that radius is the nearest overall (every point
    /// outside those cells lies farther away). Otherwise the radius doubles (at least one
    /// cell) until such a point is found or the radius reaches `gate`.
    pub(super) fn nearest_hinted(
        &self,
        q: [f64; 2],
        n: [f64; 2],
        gate: f64,
        min_cos: f64,
        hint: Option<usize>,
    ) -> Option<usize> {
        if self.width == 0 || !is_finite2(q) || gate.is_nan() || gate < 0.0 {
            return None;
        }
        let mut near = gate.min(NEAR_M);
        if let Some(o) = hint.and_then(|k| self.sorted.get(k)) {
            let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
            if d2 <= gate * gate && o.n[0] * n[0] + o.n[1] * n[1] >= min_cos {
                // The hint lies within this radius with room for the margin below.
                near = near.min(d2.sqrt() + 2e-9);
            }
        }
        // Rings of doubling reach: most points lie a few centimetres from their match, and
        // a wide gate's whole square holds many keyframes' hits of the same wall.
        let mut reach = near;
        // Beyond this reach the search already covers every cell (worked out only when a
        // first ring does not settle the query).
        let mut whole = None;
        loop {
            let found = self.nearest_in(q, n, reach, gate, min_cos);
            if reach >= gate || whole.is_some_and(|w| reach >= w) {
                return found.map(|(_, k)| k);
            }
            // Margin for the rounding of cell assignment.
            let sure = (reach - 1e-9).max(0.0);
            if let Some((d2, k)) = found
                && d2 < sure * sure
            {
                return Some(k);
            }
            let whole = *whole.get_or_insert_with(|| self.grid_reach(q));
            if reach >= whole {
                return found.map(|(_, k)| k);
            }
            reach = (2.0 * reach).max(CELL_M).min(gate);
        }
    }

    /// The reach from `q` beyond which a search covers every cell of the index.
    fn grid_reach(&self, q: [f64; 2]) -> f64 {
        [(0, self.width), (1, self.height)]
            .iter()
            .map(|&(a, cells)| {
                let lo = q[a] - self.origin[a];
                lo.abs().max((cells as f64 * CELL_M - lo).abs()) + CELL_M
            })
            .fold(0.0, f64::max)
    }

    /// The nearest point within `gate` (squared distance and index into `sorted`) among the
    /// cells within `reach` of `q`.
    pub(super) fn nearest_in(
        &self,
        q: [f64; 2],
        n: [f64; 2],
        reach: f64,
        gate: f64,
        min_cos: f64,
    ) -> Option<(f64, usize)> {
        let fx = (q[0] - self.origin[0]) / CELL_M;
        let fy = (q[1] - self.origin[1]) / CELL_M;
        let r = reach / CELL_M;
        let (wmax, hmax) = ((self.width - 1) as f64, (self.height - 1) as f64);
        let x1 = floor(fx + r);
        let y1 = floor(fy + r);
        if x1 < 0.0 || y1 < 0.0 {
            return None;
        }
        let x0 = floor(fx - r).max(0.0);
        let y0 = floor(fy - r).max(0.0);
        if x0 > wmax || y0 > hmax {
            return None;
        }
        let (x0, x1) = (x0 as usize, x1.min(wmax) as usize);
        let (y0, y1) = (y0 as usize, y1.min(hmax) as usize);
        let g2 = gate * gate;
        let mut best: Option<(f64, usize)> = None;
        for cy in y0..=y1 {
            let row = cy * self.width;
            // The cells of one row are contiguous in `sorted`.
            let first = self.starts[row + x0] as usize;
            let span = first..self.starts[row + x1 + 1] as usize;
            for (k, o) in self.sorted[span].iter().enumerate() {
                let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
                if d2 > g2 || o.n[0] * n[0] + o.n[1] * n[1] < min_cos {
                    continue;
                }
                if best.is_none_or(|(b, _)| d2 < b) {
                    best = Some((d2, first + k));
                }
            }
        }
        best
    }
}

/// True when both coordinates are finite.
fn is_finite2(p: [f64; 2]) -> bool {
    p[0].is_finite() && p[1].is_finite()
}

/// `x.floor()` for finite `x` of magnitude below 2^52 without a libm call (the baseline
/// x86-64 target has no rounding instruction).
fn floor(x: f64) -> f64 {
    let t = x as i64 as f64;
    if t > x { t - 1.0 } else { t }
}

/// `floor(x)` as an index, for finite `x >= 0`.
fn floor_nonneg(x: f64) -> usize {
    x as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn index_finds_the_brute_force_nearest() {
        // Points on a few hand-placed segments (normals up or right) plus scattered ones.
        let mut t = MatchTarget::new();
        for k in 0..200 {
            let u = k as f64 * 0.01;
            t.points.push(Oriented {
                p: [-1.0 + u, 0.5],
                n: [0.0, 1.0],
            });
            t.points.push(Oriented {
                p: [0.7, -1.0 + 0.013 * k as f64],
                n: [1.0, 0.0],
            });
        }
        let mut noise = scan_types::testkit::Noise::new(12345);
        let mut uniform = || noise.uniform();
        for _ in 0..100 {
            let a = uniform() * std::f64::consts::TAU;
            t.points.push(Oriented {
                p: [uniform() * 3.0 - 1.5, uniform() * 3.0 - 1.5],
                n: [a.cos(), a.sin()],
            });
        }
        t.dirty = true;
        t.index();
        let min_cos = 0.5;
        for _ in 0..2000 {
            let q = [uniform() * 4.0 - 2.0, uniform() * 4.0 - 2.0];
            let a = uniform() * std::f64::consts::TAU;
            let n = [a.cos(), a.sin()];
            for gate in [0.0, 0.01, 0.05, 0.06, 0.12, 0.3, 1.0, 10.0, f64::INFINITY] {
                // Brute force: the first point of least squared distance within the gate.
                let mut want: Option<(f64, &Oriented)> = None;
                for o in &t.points {
                    let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
                    if d2 <= gate * gate
                        && o.n[0] * n[0] + o.n[1] * n[1] >= min_cos
                        && want.is_none_or(|(b, _)| d2 < b)
                    {
                        want = Some((d2, o));
                    }
                }
                // Without a hint, with a random one and with the answer as the hint.
                let some = Some((uniform() * t.len() as f64) as usize);
                let right = t.nearest_hinted(q, n, gate, min_cos, None);
                for hint in [None, some, right] {
                    let got = t.nearest_hinted(q, n, gate, min_cos, hint);
                    assert_eq!(got.map(|k| &t.sorted[k]), want.map(|w| w.1), "{q:?} {gate}");
                }
            }
        }
        assert_eq!(
            t.nearest_hinted([f64::NAN, 0.0], [1.0, 0.0], 0.3, 0.5, Some(0)),
            None
        );
    }

    #[test]
    fn thinning_keeps_one_point_per_cell_and_side_of_a_wall() {
        // Both faces of a 1 m wall along y = 0.01, hits every 5 mm: 200 points a face.
        let mut t = MatchTarget::new();
        for side in [1.0, -1.0] {
            for k in 0..200 {
                t.points.push(Oriented {
                    p: [0.0025 + k as f64 * 0.005, 0.01],
                    n: [0.0, side],
                });
            }
        }
        t.points.push(Oriented {
            p: [f64::NAN, 0.0],
            n: [1.0, 0.0],
        });
        t.thin(0.02);
        // 1 m / 0.02 m = 50 cells a face; the first point of each cell is kept.
        assert_eq!(t.len(), 100);
        assert!(
            (t.points[1].p[0] - 0.0225).abs() < 1e-12,
            "{:?}",
            t.points[1]
        );
        assert_eq!(t.points.iter().filter(|o| o.n[1] < 0.0).count(), 50);
        // A thinned target still finds the wall's point nearest a query.
        t.index();
        let k = t
            .nearest_hinted([0.5, 0.0], [0.0, 1.0], 0.06, 0.5, None)
            .unwrap();
        assert!(
            (t.sorted[k].p[0] - 0.5025).abs() < 1e-12,
            "{:?}",
            t.sorted[k]
        );
        let before = t.len();
        t.thin(0.0);
        assert_eq!(t.len(), before);
    }

    #[test]
    fn floor_matches_std() {
        for x in [
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            1e-300,
            0.5,
            1.0,
            3.999,
            1e15 + 0.5,
        ] {
            assert_eq!(floor(x), x.floor(), "{x}");
        }
    }
}
