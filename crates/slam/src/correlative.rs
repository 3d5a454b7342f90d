//! Correlative scan matching by branch and bound: the pose in a window around a guess whose
//! scan points score highest in a submap's likelihood field.

use scan_types::Pose2;

use crate::grid::{FULL, ScoreGrid};

/// The search window around the guess, and the cost of straying from the guess.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Window {
    /// Half-width of the translation window, metres.
    pub(crate) linear_m: f64,
    /// Half-width of the rotation window, radians.
    pub(crate) angular_rad: f64,
    /// Quality lost per square metre away from the guess.
    pub(crate) translation_cost: f64,
    /// Quality lost per square radian away from the guess.
    pub(crate) rotation_cost: f64,
}

/// The best pose and its score: the mean field value of the points, 0..1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Found {
    pub(crate) pose: Pose2,
    pub(crate) quality: f64,
    /// True when the pose lies on the window's outermost shift or angle (the best pose may
    /// then lie beyond it).
    pub(crate) on_edge: bool,
}

#[derive(Debug, Clone, Copy)]
struct Candidate {
    /// The field score less the cost of straying (a bound for a block above level 0).
    score: i64,
    /// The field score alone.
    raw: u32,
    angle: usize,
    ix: i32,
    iy: i32,
    level: usize,
}

/// The points' cells for every angle of the window.
struct Rotated {
    /// Per angle, the cell index (`y * width + x`) of every point that stays inside the grid
    /// at every shift of the window ...
    inner: Vec<Vec<usize>>,
    /// ... and the cells of those that may leave it (read with a bounds check). Points that
    /// lie outside at every shift score 0 and are left out.
    edge: Vec<Vec<[i32; 2]>>,
    width: i32,
    /// Heading of each angle, and its offset from the guess.
    thetas: Vec<f64>,
    offsets: Vec<f64>,
}

impl Rotated {
    fn new(
        grid: &ScoreGrid,
        points: &[[f64; 2]],
        guess: &Pose2,
        window: &Window,
        half: i32,
    ) -> Self {
        // The angular step moves most points (nine in ten) by at most about one cell; ICP
        // refines the angle afterwards.
        let mut ranges: Vec<f64> = points.iter().map(|p| p[0].hypot(p[1])).collect();
        let k = (ranges.len() * 9 / 10).min(ranges.len().saturating_sub(1));
        let reach = if ranges.is_empty() {
            grid.resolution_m
        } else {
            *ranges.select_nth_unstable_by(k, f64::total_cmp).1
        }
        .max(grid.resolution_m);
        let step = (grid.resolution_m / reach).min(window.angular_rad.max(1e-9));
        let n = (window.angular_rad / step).ceil() as i64;
        let [w, h] = grid.size().map(|v| v as i32);
        let angles = 2 * n as usize + 1;
        let mut inner = Vec::with_capacity(angles);
        let mut edge = Vec::with_capacity(angles);
        let mut thetas = Vec::with_capacity(angles);
        let mut offsets = Vec::with_capacity(angles);
        // Shifts reach `half` cells either way: a point at x is read from x - half to x + half.
        let inside = |v: i32, size: i32| v >= half && v < size - half;
        let never = |v: i32, size: i32| v < -half || v >= size + half;
        for a in -n..=n {
            let theta = guess.theta_rad + a as f64 * step;
            let (s, c) = theta.sin_cos();
            thetas.push(theta);
            offsets.push(a as f64 * step);
            let mut inn = Vec::with_capacity(points.len());
            let mut edg = Vec::new();
            for p in points {
                let q = grid.cell([
                    guess.x_m + c * p[0] - s * p[1],
                    guess.y_m + s * p[0] + c * p[1],
                ]);
                if inside(q[0], w) && inside(q[1], h) {
                    inn.push(q[1] as usize * w as usize + q[0] as usize);
                } else if !(never(q[0], w) || never(q[1], h)) {
                    edg.push(q);
                }
            }
            inner.push(inn);
            edge.push(edg);
        }
        Self {
            inner,
            edge,
            width: w,
            thetas,
            offsets,
        }
    }

    fn raw(&self, grid: &ScoreGrid, c: &Candidate) -> u32 {
        let level = grid.level(c.level);
        // A shift within the window keeps every inner cell on the grid.
        let shift = (c.iy * self.width + c.ix) as isize;
        let inner: u32 = self.inner[c.angle]
            .iter()
            .map(|&q| u32::from(level[(q as isize + shift) as usize]))
            .sum();
        let edge: u32 = self.edge[c.angle]
            .iter()
            .map(|q| grid.value(c.level, q[0] + c.ix, q[1] + c.iy))
            .sum();
        inner + edge
    }
}

/// Scores candidates: field score less the least cost of straying within the block.
struct Scorer<'a> {
    grid: &'a ScoreGrid,
    rotated: Rotated,
    half: i32,
    /// Score units per square cell and per square radian.
    per_cell2: f64,
    per_rad2: f64,
}

impl Scorer<'_> {
    fn score(&self, mut c: Candidate) -> Candidate {
        c.raw = self.rotated.raw(self.grid, &c);
        // The block's offsets nearest the guess.
        let size = (1i32 << c.level) - 1;
        let near = |lo: i32| 0.clamp(lo, (lo + size).min(self.half)) as f64;
        let (dx, dy) = (near(c.ix), near(c.iy));
        let th = self.rotated.offsets[c.angle];
        let cost = self.per_cell2 * (dx * dx + dy * dy) + self.per_rad2 * th * th;
        c.score = i64::from(c.raw) - cost.ceil() as i64;
        c
    }
}

/// The pose within `window` of `guess` for `points` (robot frame) that scores best less
/// its cost of straying, if its field score reaches `min_quality`.
pub(crate) fn search(
    grid: &ScoreGrid,
    points: &[[f64; 2]],
    guess: &Pose2,
    window: &Window,
    min_quality: f64,
) -> Option<Found> {
    if points.is_empty() {
        return None;
    }
    let full = FULL as f64 * points.len() as f64;
    let res = grid.resolution_m;
    let half = (window.linear_m / res).ceil() as i32;
    let scorer = Scorer {
        grid,
        rotated: Rotated::new(grid, points, guess, window, half),
        half,
        per_cell2: full * window.translation_cost * res * res,
        per_rad2: full * window.rotation_cost,
    };
    let top = grid.depth();
    let step = 1i32 << top;
    let mut roots = Vec::new();
    for angle in 0..scorer.rotated.thetas.len() {
        let mut ix = -scorer.half;
        while ix <= scorer.half {
            let mut iy = -scorer.half;
            while iy <= scorer.half {
                roots.push(scorer.score(Candidate {
                    score: 0,
                    raw: 0,
                    angle,
                    ix,
                    iy,
                    level: top,
                }));
                iy += step;
            }
            ix += step;
        }
    }
    let mut best: Option<Candidate> = None;
    branch(&scorer, roots, &mut best);
    let b = best?;
    let quality = b.raw as f64 / full;
    let last = scorer.rotated.thetas.len() - 1;
    (quality >= min_quality).then(|| Found {
        pose: Pose2::new(
            guess.x_m + b.ix as f64 * res,
            guess.y_m + b.iy as f64 * res,
            scorer.rotated.thetas[b.angle],
        ),
        quality,
        on_edge: b.ix.abs() >= scorer.half
            || b.iy.abs() >= scorer.half
            || (last > 0 && (b.angle == 0 || b.angle == last)),
    })
}

/// The mean field value (0..1) of `points` (robot frame) placed at `pose`.
pub(crate) fn quality(grid: &ScoreGrid, points: &[[f64; 2]], pose: &Pose2) -> f64 {
    let (s, c) = pose.theta_rad.sin_cos();
    let sum: u32 = points
        .iter()
        .map(|p| {
            let q = grid.cell([
                pose.x_m + c * p[0] - s * p[1],
                pose.y_m + s * p[0] + c * p[1],
            ]);
            grid.value(0, q[0], q[1])
        })
        .sum();
    sum as f64 / (FULL as f64 * points.len().max(1) as f64)
}

/// Depth-first over `candidates`, best first, skipping every block whose bound cannot beat
/// the best leaf found.
fn branch(scorer: &Scorer, mut candidates: Vec<Candidate>, best: &mut Option<Candidate>) {
    candidates.sort_unstable_by_key(|c| std::cmp::Reverse(c.score));
    for c in candidates {
        if best.is_some_and(|b| c.score <= b.score) {
            return;
        }
        if c.level == 0 {
            *best = Some(c);
            return;
        }
        let s = 1i32 << (c.level - 1);
        let mut children = Vec::with_capacity(4);
        for (dx, dy) in [(0, 0), (s, 0), (0, s), (s, s)] {
            if c.ix + dx > scorer.half || c.iy + dy > scorer.half {
                continue;
            }
            children.push(scorer.score(Candidate {
                ix: c.ix + dx,
                iy: c.iy + dy,
                level: c.level - 1,
                ..c
            }));
        }
        branch(scorer, children, best);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An L of points: 4 m along x at y = 0 and 3 m along y at x = 0, every 5 cm.
    fn ell() -> Vec<[f64; 2]> {
        let mut v: Vec<[f64; 2]> = (0..80).map(|i| [i as f64 * 0.05, 0.0]).collect();
        v.extend((1..60).map(|i| [0.0, i as f64 * 0.05]));
        v
    }

    #[test]
    fn finds_a_known_offset_from_a_wrong_guess() {
        let map = ell();
        let grid = ScoreGrid::new(&map, 0.1, 0.1, 4, 10).unwrap();
        // The scan is the map seen from (0.7, -0.4) heading 20 deg; the guess is the origin.
        let truth = Pose2::new(0.7, -0.4, 20f64.to_radians());
        let scan: Vec<[f64; 2]> = map
            .iter()
            .map(|p| {
                let q = truth.inverse_transform_point(scan_types::WorldPoint::new(p[0], p[1]));
                [q.x_m(), q.y_m()]
            })
            .collect();
        let window = Window {
            linear_m: 1.0,
            angular_rad: 30f64.to_radians(),
            translation_cost: 0.0,
            rotation_cost: 0.0,
        };
        let f = search(&grid, &scan, &Pose2::default(), &window, 0.5).unwrap();
        // Within about a cell and two angular steps (0.1 m / 3.7 m = 1.55 deg) of the truth:
        // the field's cells make poses that close score alike.
        assert!(
            (f.pose.x_m - 0.7).abs() <= 0.15 && (f.pose.y_m + 0.4).abs() <= 0.15,
            "{f:?}"
        );
        assert!(
            (f.pose.theta_rad - truth.theta_rad).abs() <= 3.1f64.to_radians(),
            "{f:?}"
        );
        assert!(f.quality > 0.8, "{f:?}");
        // Outside a window that does not hold the truth, nothing scores well enough.
        let narrow = Window {
            linear_m: 0.2,
            angular_rad: 2f64.to_radians(),
            ..window
        };
        assert!(search(&grid, &scan, &Pose2::default(), &narrow, 0.8).is_none());
    }

    #[test]
    fn a_best_pose_beyond_the_window_is_reported_on_its_edge() {
        // The scan is the L seen from 0.5 m further along x: only that shift brings its
        // y-wall onto the map's, and a shift toward it keeps more of its x-wall on the map's.
        let map = ell();
        let grid = ScoreGrid::new(&map, 0.1, 0.1, 4, 10).unwrap();
        let scan: Vec<[f64; 2]> = map.iter().map(|p| [p[0] - 0.5, p[1]]).collect();
        let window = |linear_m: f64| Window {
            linear_m,
            angular_rad: 5f64.to_radians(),
            translation_cost: 0.0,
            rotation_cost: 0.0,
        };
        let near = search(&grid, &scan, &Pose2::default(), &window(0.2), 0.0).unwrap();
        assert!(near.on_edge, "{near:?}");
        let wide = search(&grid, &scan, &Pose2::default(), &window(1.0), 0.0).unwrap();
        assert!(!wide.on_edge, "{wide:?}");
        // Within about a cell: points on a cell border score alike a cell either way.
        assert!(
            (wide.pose.x_m - 0.5).abs() <= 0.15 && wide.pose.y_m.abs() <= 0.15,
            "{wide:?}"
        );
    }

    #[test]
    fn scores_equal_direct_lookups_on_and_off_the_grid() {
        // Points on the L, beside it, and far beyond the grid's edge (which no shift of the
        // window reaches), at every shift, angle and level.
        let grid = ScoreGrid::new(&ell(), 0.1, 0.1, 3, 5).unwrap();
        let mut scan = ell();
        scan.extend([
            [-2.4, 0.3],
            [5.9, -1.7],
            [0.2, 6.3],
            [30.0, 2.0],
            [-1.0, -40.0],
        ]);
        let guess = Pose2::new(0.2, -0.1, 0.1);
        let window = Window {
            linear_m: 0.5,
            angular_rad: 4f64.to_radians(),
            translation_cost: 0.0,
            rotation_cost: 0.0,
        };
        let rotated = Rotated::new(&grid, &scan, &guess, &window, 5);
        for (angle, theta) in rotated.thetas.iter().enumerate() {
            let (s, c) = theta.sin_cos();
            for level in 0..=grid.depth() {
                for ix in -5..=5 {
                    for iy in -5..=5 {
                        let want: u32 = scan
                            .iter()
                            .map(|p| {
                                let q = grid.cell([
                                    guess.x_m + c * p[0] - s * p[1],
                                    guess.y_m + s * p[0] + c * p[1],
                                ]);
                                grid.value(level, q[0] + ix, q[1] + iy)
                            })
                            .sum();
                        let cand = Candidate {
                            score: 0,
                            raw: 0,
                            angle,
                            ix,
                            iy,
                            level,
                        };
                        assert_eq!(rotated.raw(&grid, &cand), want, "{angle} {level} {ix} {iy}");
                    }
                }
            }
        }
    }

    #[test]
    fn branch_and_bound_agrees_with_exhaustive_search() {
        let map = ell();
        let grid = ScoreGrid::new(&map, 0.1, 0.1, 4, 11).unwrap();
        let scan: Vec<[f64; 2]> = map
            .iter()
            .step_by(3)
            .map(|p| [p[0] - 0.33, p[1] + 0.21])
            .collect();
        let guess = Pose2::new(0.1, 0.0, 0.05);
        for (tc, rc) in [(0.0, 0.0), (0.3, 0.5)] {
            let window = Window {
                linear_m: 1.0,
                angular_rad: 6f64.to_radians(),
                translation_cost: tc,
                rotation_cost: rc,
            };
            let f = search(&grid, &scan, &guess, &window, 0.0).unwrap();
            let full = FULL as f64 * scan.len() as f64;
            let scorer = Scorer {
                grid: &grid,
                rotated: Rotated::new(&grid, &scan, &guess, &window, 10),
                half: 10,
                per_cell2: full * tc * 0.01,
                per_rad2: full * rc,
            };
            let mut best: Option<Candidate> = None;
            for angle in 0..scorer.rotated.thetas.len() {
                for ix in -10..=10 {
                    for iy in -10..=10 {
                        let c = scorer.score(Candidate {
                            score: 0,
                            raw: 0,
                            angle,
                            ix,
                            iy,
                            level: 0,
                        });
                        if best.is_none_or(|b| c.score > b.score) {
                            best = Some(c);
                        }
                    }
                }
            }
            let expected = best.unwrap().raw as f64 / full;
            assert!(
                (f.quality - expected).abs() < 1e-12,
                "{} vs {expected}",
                f.quality
            );
        }
    }
}
