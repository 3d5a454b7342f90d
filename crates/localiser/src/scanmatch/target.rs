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

    /// Makes room for `additional` more reference points.
    pub fn reserve(&mut self, additional: usize) {
        self.points.reserve(additional);
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
    /// index into `sorted` (`None`: there is none), given the index of a point `hint` that is
    /// probably near `q` (the match of the previous iteration); with what [`Self::recheck`]
    /// needs to answer for a query moved a little without searching again. `None` when
    /// nothing could be searched (an empty index, a query that is not finite, a gate that is
    /// negative or not a number).
    ///
    /// First searches the cells within `min(gate, NEAR_M, distance to the hint)` of `q`: a
    /// point found there nearer than that radius is the nearest overall (every point
    /// outside those cells lies farther away). Otherwise the radius doubles (at least one
    /// cell) until such a point is found or the radius reaches `gate`.
    pub(super) fn nearest_held(
        &self,
        q: [f64; 2],
        n: [f64; 2],
        gate: f64,
        min_cos: f64,
        hint: Option<usize>,
    ) -> Option<(Option<usize>, Hold)> {
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
            let answer = || Some((found.best.map(|(_, k)| k), found.hold()));
            if reach >= gate || whole.is_some_and(|w| reach >= w) {
                return answer();
            }
            // Margin for the rounding of cell assignment.
            let sure = (reach - 1e-9).max(0.0);
            if found.best.is_some_and(|(d2, _)| d2 < sure * sure) {
                return answer();
            }
            let whole = *whole.get_or_insert_with(|| self.grid_reach(q));
            if reach >= whole {
                return answer();
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

    /// The nearest point within `gate` among the cells within `reach` of `q`, with what
    /// else the search saw.
    pub(super) fn nearest_in(
        &self,
        q: [f64; 2],
        n: [f64; 2],
        reach: f64,
        gate: f64,
        min_cos: f64,
    ) -> Nearest {
        let mut found = Nearest {
            best: None,
            kept: [(f64::INFINITY, 0); KEEP],
            covered_m: f64::INFINITY,
        };
        let fx = (q[0] - self.origin[0]) / CELL_M;
        let fy = (q[1] - self.origin[1]) / CELL_M;
        let r = reach / CELL_M;
        let (wmax, hmax) = ((self.width - 1) as f64, (self.height - 1) as f64);
        let x1 = floor(fx + r);
        let y1 = floor(fy + r);
        if x1 < 0.0 || y1 < 0.0 {
            // The block misses the grid: nothing was searched.
            found.covered_m = 0.0;
            return found;
        }
        let x0 = floor(fx - r).max(0.0);
        let y0 = floor(fy - r).max(0.0);
        if x0 > wmax || y0 > hmax {
            found.covered_m = 0.0;
            return found;
        }
        let (x1, y1) = (x1.min(wmax), y1.min(hmax));
        // Distance from q to the nearest side of the searched block that has cells beyond
        // it: no point outside the block lies nearer.
        let sides = [
            (x0 > 0.0).then_some(fx - x0),
            (x1 < wmax).then_some(x1 + 1.0 - fx),
            (y0 > 0.0).then_some(fy - y0),
            (y1 < hmax).then_some(y1 + 1.0 - fy),
        ];
        found.covered_m = sides.into_iter().flatten().fold(f64::INFINITY, f64::min) * CELL_M;
        let (x0, x1) = (x0 as usize, x1 as usize);
        let (y0, y1) = (y0 as usize, y1 as usize);
        let g2 = gate * gate;
        for cy in y0..=y1 {
            let row = cy * self.width;
            // The cells of one row are contiguous in `sorted`.
            let first = self.starts[row + x0] as usize;
            let span = first..self.starts[row + x1 + 1] as usize;
            for (k, o) in self.sorted[span].iter().enumerate() {
                let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
                let cos = o.n[0] * n[0] + o.n[1] * n[1];
                // A point whose normal could turn into agreement may answer a moved query.
                if cos >= min_cos - HOLD_TURN {
                    found.keep(d2, first + k);
                }
                if d2 > g2 || cos < min_cos {
                    continue;
                }
                if found.best.is_none_or(|(b, _)| d2 < b) {
                    found.best = Some((d2, first + k));
                }
            }
        }
        found
    }
}

/// A [`Hold`] lapses once the query's normal turns by this much, radians; the turn bounds the
/// change of its cosine with any other unit normal, so this is also that cosine's slack.
const HOLD_TURN: f64 = 0.05;

/// The nearest points a search keeps for [`MatchTarget::recheck`].
const KEEP: usize = 3;

/// What one nearest-point search over a block of cells saw.
#[derive(Debug, Clone, Copy)]
pub(super) struct Nearest {
    /// Squared distance and index of the nearest point within the gate whose normal agrees.
    pub(super) best: Option<(f64, usize)>,
    /// The nearest points (squared distance, index; nearest first; infinite distance for
    /// none) that answer or could after a turn of the normal by less than `HOLD_TURN`,
    /// whatever the gate. No other such point of the searched cells lies nearer than the last.
    kept: [(f64, usize); KEEP],
    /// Distance from the query within which every cell was searched, metres.
    covered_m: f64,
}

impl Nearest {
    /// Keeps the point `k` at squared distance `d2` if it is among the `KEEP` nearest.
    #[inline]
    fn keep(&mut self, d2: f64, k: usize) {
        if d2 >= self.kept[KEEP - 1].0 {
            return;
        }
        let mut i = KEEP - 1;
        while i > 0 && self.kept[i - 1].0 > d2 {
            self.kept[i] = self.kept[i - 1];
            i -= 1;
        }
        self.kept[i] = (d2, k);
    }

    /// The kept points and how near any other point lies.
    fn hold(&self) -> Hold {
        let mut kept = [0; KEEP];
        for (dst, src) in kept.iter_mut().zip(&self.kept) {
            *dst = src.1;
        }
        Hold {
            kept,
            kept_len: self.kept.iter().filter(|c| c.0.is_finite()).count(),
            limit_m: self.kept[KEEP - 1].0.sqrt().min(self.covered_m),
        }
    }
}

/// What a search saw around its query: the nearest points (indices into `sorted`) that
/// answer or could after a small turn, and the distance within which no other point that
/// could answer lies.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Hold {
    kept: [usize; KEEP],
    kept_len: usize,
    limit_m: f64,
}

impl MatchTarget {
    /// What [`Self::nearest_held`] would answer (a point, or `Some(None)`: no point) for a
    /// query `moved_m` from the one whose search gave `hold` and its normal turned by
    /// `turn_rad`, when the kept points prove it: one lies nearer than anything else can, or
    /// none answers and nothing else can lie within the gate. `None` when they do not: search
    /// again.
    pub(super) fn recheck(
        &self,
        hold: &Hold,
        (q, n): ([f64; 2], [f64; 2]),
        (moved_m, turn_rad): (f64, f64),
        gate: f64,
        min_cos: f64,
    ) -> Option<Option<usize>> {
        // A NaN cosine bound keeps nothing yet lets a search take any point: search.
        if gate.is_nan() || gate < 0.0 || min_cos.is_nan() || turn_rad.abs() >= HOLD_TURN - 1e-9 {
            return None;
        }
        let g2 = gate * gate;
        let mut best: Option<(f64, usize)> = None;
        for &k in &hold.kept[..hold.kept_len] {
            let o = &self.sorted[k];
            let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
            if d2 > g2 || o.n[0] * n[0] + o.n[1] * n[1] < min_cos {
                continue;
            }
            // Ties go to the first point in index order, as in a search.
            if best.is_none_or(|(b, bk)| d2 < b || (d2 == b && k < bk)) {
                best = Some((d2, k));
            }
        }
        // Every point not kept lies at least `limit_m - moved_m` from the moved query.
        let beyond = hold.limit_m - moved_m - 1e-9;
        match best {
            Some((d2, k)) => (d2.sqrt() < beyond).then_some(Some(k)),
            None => (gate < beyond).then_some(None),
        }
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

    impl MatchTarget {
        /// [`MatchTarget::nearest_held`]'s point alone.
        fn nearest_hinted(
            &self,
            q: [f64; 2],
            n: [f64; 2],
            (gate, min_cos): (f64, f64),
            hint: Option<usize>,
        ) -> Option<usize> {
            self.nearest_held(q, n, gate, min_cos, hint)
                .and_then(|(k, _)| k)
        }
    }

    /// Points on a few hand-placed segments (normals up or right) plus scattered ones,
    /// indexed, and the random source that placed them.
    fn segments_and_scatter() -> (MatchTarget, scan_types::testkit::Noise) {
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
        (t, noise)
    }

    /// The first point of least squared distance within `gate` whose normal agrees with `n`.
    fn brute_force(t: &MatchTarget, q: [f64; 2], n: [f64; 2], gate: f64) -> Option<&Oriented> {
        let mut want: Option<(f64, &Oriented)> = None;
        for o in &t.points {
            let d2 = (o.p[0] - q[0]).powi(2) + (o.p[1] - q[1]).powi(2);
            if d2 <= gate * gate
                && o.n[0] * n[0] + o.n[1] * n[1] >= MIN_COS
                && want.is_none_or(|(b, _)| d2 < b)
            {
                want = Some((d2, o));
            }
        }
        want.map(|w| w.1)
    }

    const MIN_COS: f64 = 0.5;

    #[test]
    fn index_finds_the_brute_force_nearest() {
        let (t, mut noise) = segments_and_scatter();
        let mut uniform = || noise.uniform();
        let min_cos = MIN_COS;
        for _ in 0..2000 {
            let q = [uniform() * 4.0 - 2.0, uniform() * 4.0 - 2.0];
            let a = uniform() * std::f64::consts::TAU;
            let n = [a.cos(), a.sin()];
            for gate in [0.0, 0.01, 0.05, 0.06, 0.12, 0.3, 1.0, 10.0, f64::INFINITY] {
                let want = brute_force(&t, q, n, gate);
                // Without a hint, with a random one and with the answer as the hint.
                let some = Some((uniform() * t.len() as f64) as usize);
                let right = t.nearest_hinted(q, n, (gate, min_cos), None);
                for hint in [None, some, right] {
                    let got = t.nearest_hinted(q, n, (gate, min_cos), hint);
                    assert_eq!(got.map(|k| &t.sorted[k]), want, "{q:?} {gate}");
                }
            }
        }
        assert_eq!(
            t.nearest_hinted([f64::NAN, 0.0], [1.0, 0.0], (0.3, 0.5), Some(0)),
            None
        );
    }

    #[test]
    fn a_recheck_answers_only_what_a_search_would() {
        let (t, mut noise) = segments_and_scatter();
        let mut uniform = || noise.uniform();
        let (mut answered, mut other_point, mut declined) = (0, 0, 0);
        // Proven empty: searches that found nothing, and matches that no longer answer.
        let (mut none_held, mut none_lost) = (0, 0);
        for _ in 0..4000 {
            // Queries near the segments (where kept points crowd) and anywhere.
            let q = if uniform() < 0.5 {
                [-1.0 + 2.0 * uniform(), 0.5 + 0.1 * (uniform() - 0.5)]
            } else {
                [uniform() * 4.0 - 2.0, uniform() * 4.0 - 2.0]
            };
            let a = uniform() * std::f64::consts::TAU;
            let gate = [0.06, 0.12, 0.3][(uniform() * 3.0) as usize];
            let hint = Some((uniform() * t.len() as f64) as usize);
            let n = [a.cos(), a.sin()];
            let (k, hold) = t.nearest_held(q, n, gate, MIN_COS, hint).unwrap();
            // Moves of up to 3 cm and turns of up to 4 deg, under the same or a narrower gate.
            for _ in 0..20 {
                let (m, dir) = (0.03 * uniform().powi(3), uniform() * std::f64::consts::TAU);
                let q2 = [q[0] + m * dir.cos(), q[1] + m * dir.sin()];
                let turn = (2.0 * uniform() - 1.0) * 4f64.to_radians();
                let n2 = [(a + turn).cos(), (a + turn).sin()];
                let gate2 = gate * (0.7 + 0.3 * uniform());
                let moved = (q2[0] - q[0]).hypot(q2[1] - q[1]);
                match t.recheck(&hold, (q2, n2), (moved, turn), gate2, MIN_COS) {
                    Some(got) => {
                        answered += 1;
                        match (k, got) {
                            (None, None) => none_held += 1,
                            (Some(_), None) => none_lost += 1,
                            (k, got) => other_point += usize::from(got != k),
                        }
                        let want = brute_force(&t, q2, n2, gate2);
                        assert_eq!(
                            got.map(|g| &t.sorted[g]),
                            want,
                            "{q:?} -> {q2:?}, turn {turn}"
                        );
                    }
                    None => declined += 1,
                }
            }
        }
        // Unmoved, a recheck gives the search's answer; under a gate or cosine bound no search
        // takes, it declines (search again).
        let (q, n) = ([0.003, 0.52], [0.0, 1.0]);
        let (k, hold) = t.nearest_held(q, n, 0.3, MIN_COS, None).unwrap();
        assert!(k.is_some());
        assert_eq!(t.recheck(&hold, (q, n), (0.0, 0.0), 0.3, MIN_COS), Some(k));
        for gate in [-0.1, f64::NAN] {
            assert_eq!(t.recheck(&hold, (q, n), (0.0, 0.0), gate, MIN_COS), None);
        }
        assert_eq!(t.recheck(&hold, (q, n), (0.0, 0.0), 0.3, f64::NAN), None);
        // Facing away from every segment 1 cm above the upper one: no match, and none for a
        // small move either.
        let (q, n) = ([0.0, 0.51], [0.0, -1.0]);
        let near_scatter = t.points.iter().any(|o| {
            (o.p[0] - q[0]).hypot(o.p[1] - q[1]) < 0.1 && o.n[0] * n[0] + o.n[1] * n[1] >= 0.4
        });
        assert!(!near_scatter);
        let (k, hold) = t.nearest_held(q, n, 0.06, MIN_COS, None).unwrap();
        assert_eq!(k, None);
        assert_eq!(
            t.recheck(&hold, ([0.0, 0.512], n), (0.002, 0.0), 0.06, MIN_COS),
            Some(None)
        );
        // Many points answered, some of them another kept point than the first search's,
        // many proven empty, and many moves declined (beyond what the kept points prove).
        let points = answered - none_held - none_lost;
        assert!(
            points > 5_000 && other_point > 200 && declined > 5_000,
            "{points} {other_point} {declined}"
        );
        assert!(
            none_held > 10_000 && none_lost > 1_000,
            "{none_held} {none_lost}"
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
            .nearest_hinted([0.5, 0.0], [0.0, 1.0], (0.06, 0.5), None)
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
