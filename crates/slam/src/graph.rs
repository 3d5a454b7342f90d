//! A 2D pose graph and its optimisation: Gauss-Newton over every pose at once, the normal
//! equations solved by faer's sparse Cholesky factorisation (with its fill-reducing
//! ordering), and a Cauchy loss on the edges marked robust, so that a wrong loop closure is
//! weighed down instead of tearing the map.

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{Mat, Side};
use scan_types::{Pose2, normalize_angle_rad};

use crate::SlamError;

/// A measured relative pose between two nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Edge {
    /// The node the measurement is taken from.
    pub from: usize,
    /// The node measured.
    pub to: usize,
    /// Pose of `to` in the frame of `from`.
    pub measured: Pose2,
    /// Standard deviations of the measurement: along x and y (metres) and of the heading
    /// (radians), in the frame of `from`.
    pub sigma: [f64; 3],
    /// A Cauchy loss applies (loop closures): the edge may be an outlier.
    pub robust: bool,
}

/// A robust edge removed as an outlier by [`PoseGraph::drop_outliers`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dropped {
    /// Its index among the robust edges the graph held when `drop_outliers` was called.
    pub robust_index: usize,
    /// Its weight under the loss when it was removed.
    pub weight: f64,
    /// Its whitened residual then (x, y, heading).
    pub residual_sigmas: [f64; 3],
}

/// Tuning of [`PoseGraph::optimise`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimiseParams {
    /// Most Gauss-Newton iterations.
    pub max_iterations: usize,
    /// Stop when no pose moves more than this (metres, and radians for the heading).
    pub tolerance: f64,
    /// Scale of the Cauchy loss of robust edges, in standard deviations.
    pub cauchy_scale: f64,
}

impl Default for OptimiseParams {
    /// 20 iterations, 1e-6 tolerance, Cauchy scale 1 standard deviation.
    fn default() -> Self {
        Self {
            max_iterations: 20,
            tolerance: 1e-6,
            cauchy_scale: 1.0,
        }
    }
}

/// What an optimisation did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OptimiseReport {
    /// Iterations run.
    pub iterations: usize,
    /// Sum of squared whitened residuals before and after (robust edges as weighted).
    pub cost: [f64; 2],
}

/// Poses (nodes) and relative-pose measurements between them (edges); node 0 is held fixed.
#[derive(Debug, Clone, Default)]
pub struct PoseGraph {
    /// The poses, in a common frame.
    pub nodes: Vec<Pose2>,
    /// The measurements.
    pub edges: Vec<Edge>,
}

impl PoseGraph {
    /// A graph of `nodes` without edges.
    pub fn new(nodes: Vec<Pose2>) -> Self {
        Self {
            nodes,
            edges: Vec::new(),
        }
    }

    /// Adds a measurement; an edge naming a missing node, or with a standard deviation that is
    /// not a positive number, is refused.
    pub fn add_edge(&mut self, edge: Edge) -> Result<(), SlamError> {
        let n = self.nodes.len();
        if edge.from >= n || edge.to >= n || edge.from == edge.to {
            return Err(SlamError::BadEdge {
                from: edge.from,
                to: edge.to,
                nodes: n,
            });
        }
        if !edge.sigma.iter().all(|s| s.is_finite() && *s > 0.0) {
            return Err(SlamError::InvalidParam {
                key: "edge sigma",
                value: format!("{:?}", edge.sigma),
                requirement: "must be positive numbers",
            });
        }
        self.edges.push(edge);
        Ok(())
    }

    /// The whitened residual of `edge` at the current poses (x, y, heading).
    pub fn residual(&self, edge: &Edge) -> [f64; 3] {
        let e = error(&self.nodes[edge.from], &self.nodes[edge.to], &edge.measured);
        [
            e[0] / edge.sigma[0],
            e[1] / edge.sigma[1],
            e[2] / edge.sigma[2],
        ]
    }

    /// The weight the Cauchy loss gives `edge` at the current poses (1 for a non-robust edge).
    pub fn weight(&self, edge: &Edge, params: &OptimiseParams) -> f64 {
        if !edge.robust {
            return 1.0;
        }
        let r = self.residual(edge);
        let s2 = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]) / params.cauchy_scale.powi(2);
        1.0 / (1.0 + s2)
    }

    /// Moves every node but the first to minimise the weighted squared residuals.
    pub fn optimise(&mut self, params: &OptimiseParams) -> Result<OptimiseReport, SlamError> {
        let n = self.nodes.len();
        let before = self.cost(params);
        if n < 2 || self.edges.is_empty() {
            return Ok(OptimiseReport {
                iterations: 0,
                cost: [before, before],
            });
        }
        let mut iterations = 0;
        for _ in 0..params.max_iterations.max(1) {
            iterations += 1;
            let dx = self.step(params)?;
            let mut largest = 0.0f64;
            for (k, node) in self.nodes.iter_mut().enumerate().skip(1) {
                let d = [dx[3 * k - 3], dx[3 * k - 2], dx[3 * k - 1]];
                largest = largest.max(d[0].abs()).max(d[1].abs()).max(d[2].abs());
                *node = Pose2::new(
                    node.x_m + d[0],
                    node.y_m + d[1],
                    normalize_angle_rad(node.theta_rad + d[2]),
                );
            }
            if largest < params.tolerance {
                break;
            }
        }
        Ok(OptimiseReport {
            iterations,
            cost: [before, self.cost(params)],
        })
    }

    /// Removes the robust edges that the loss weighs below `reject_weight` at the current
    /// poses and optimises again, until none is left below it: an outlier weighed down still
    /// pulls. Returns each removed edge's index among the robust edges as they were before,
    /// with its weight and residual when it was removed, and the optimisations run.
    pub fn drop_outliers(
        &mut self,
        params: &OptimiseParams,
        reject_weight: f64,
    ) -> Result<(Vec<Dropped>, usize), SlamError> {
        // Each robust edge still in the graph, by its index among the robust edges.
        let mut robust: Vec<usize> = (0..self.edges.iter().filter(|e| e.robust).count()).collect();
        let (mut dropped, mut optimisations) = (Vec::new(), 0);
        loop {
            // One pass: which edges stay, and the robust ones that do.
            let (mut stays, mut kept) = (Vec::with_capacity(self.edges.len()), Vec::new());
            let mut robust_index = robust.iter();
            for e in &self.edges {
                let mut stay = true;
                if let Some(&index) = e.robust.then(|| robust_index.next()).flatten() {
                    let weight = self.weight(e, params);
                    stay = weight >= reject_weight;
                    if stay {
                        kept.push(index);
                    } else {
                        dropped.push(Dropped {
                            robust_index: index,
                            weight,
                            residual_sigmas: self.residual(e),
                        });
                    }
                }
                stays.push(stay);
            }
            if kept.len() == robust.len() {
                return Ok((dropped, optimisations));
            }
            robust = kept;
            let mut stays = stays.into_iter();
            self.edges.retain(|_| stays.next().unwrap_or(true));
            self.optimise(params)?;
            optimisations += 1;
        }
    }

    /// Sum over edges of weight times squared whitened residual.
    fn cost(&self, params: &OptimiseParams) -> f64 {
        self.edges
            .iter()
            .map(|e| {
                let r = self.residual(e);
                self.weight(e, params) * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
            })
            .sum()
    }

    /// One Gauss-Newton step for nodes 1.. (node 0 fixed): solves H dx = -g.
    fn step(&self, params: &OptimiseParams) -> Result<Vec<f64>, SlamError> {
        let dim = 3 * (self.nodes.len() - 1);
        // The lower triangle of H (faer sums repeated entries).
        let mut h: Vec<Triplet<usize, usize, f64>> =
            Vec::with_capacity(dim + 36 * self.edges.len());
        let mut g = vec![0.0f64; dim];
        // A small damping keeps H positive definite for nodes no edge reaches.
        h.extend((0..dim).map(|k| Triplet::new(k, k, 1e-9)));
        for edge in &self.edges {
            let (xi, xj) = (&self.nodes[edge.from], &self.nodes[edge.to]);
            let e = error(xi, xj, &edge.measured);
            let (a, b) = jacobians(xi, xj, &edge.measured);
            let w = self.weight(edge, params);
            let info = [
                w / edge.sigma[0].powi(2),
                w / edge.sigma[1].powi(2),
                w / edge.sigma[2].powi(2),
            ];
            let blocks = [(edge.from, &a), (edge.to, &b)];
            for &(ni, ji) in &blocks {
                if ni == 0 {
                    continue;
                }
                let oi = 3 * (ni - 1);
                for (r, gr) in g[oi..oi + 3].iter_mut().enumerate() {
                    *gr += (0..3).map(|k| ji[k][r] * info[k] * e[k]).sum::<f64>();
                }
                for &(nj, jj) in &blocks {
                    if nj == 0 {
                        continue;
                    }
                    let oj = 3 * (nj - 1);
                    for (r, row) in weighted_product(ji, &info, jj).iter().enumerate() {
                        for (c, &v) in row.iter().enumerate() {
                            if v != 0.0 && oi + r >= oj + c {
                                h.push(Triplet::new(oi + r, oj + c, v));
                            }
                        }
                    }
                }
            }
        }
        let h = SparseColMat::<usize, f64>::try_new_from_triplets(dim, dim, &h)
            .map_err(|_| SlamError::SingularGraph)?;
        let llt = h
            .sp_cholesky(Side::Lower)
            .map_err(|_| SlamError::SingularGraph)?;
        let mut dx = Mat::<f64>::from_fn(dim, 1, |i, _| -g[i]);
        llt.solve_in_place(dx.as_mut());
        let dx: Vec<f64> = (0..dim).map(|i| dx[(i, 0)]).collect();
        if dx.iter().all(|v| v.is_finite()) {
            Ok(dx)
        } else {
            Err(SlamError::SingularGraph)
        }
    }
}

/// `ji^T diag(info) jj` for 3 x 3 Jacobians.
fn weighted_product(ji: &[[f64; 3]; 3], info: &[f64; 3], jj: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut out = [[0.0; 3]; 3];
    for (r, row) in out.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = (0..3).map(|k| ji[k][r] * info[k] * jj[k][c]).sum();
        }
    }
    out
}

/// The error of measurement `z` between poses `xi` and `xj`: `z^-1 (xi^-1 xj)` as (x, y,
/// heading).
fn error(xi: &Pose2, xj: &Pose2, z: &Pose2) -> [f64; 3] {
    let (si, ci) = xi.theta_rad.sin_cos();
    let (sz, cz) = z.theta_rad.sin_cos();
    let (dx, dy) = (xj.x_m - xi.x_m, xj.y_m - xi.y_m);
    // xj in the frame of xi, less the measurement, in the measurement's frame.
    let (lx, ly) = (ci * dx + si * dy - z.x_m, -si * dx + ci * dy - z.y_m);
    [
        cz * lx + sz * ly,
        -sz * lx + cz * ly,
        normalize_angle_rad(xj.theta_rad - xi.theta_rad - z.theta_rad),
    ]
}

/// The Jacobians of [`error`] with respect to `xi` and `xj` (rows: error components; columns:
/// x, y, heading).
fn jacobians(xi: &Pose2, xj: &Pose2, z: &Pose2) -> ([[f64; 3]; 3], [[f64; 3]; 3]) {
    let (si, ci) = xi.theta_rad.sin_cos();
    let (sz, cz) = z.theta_rad.sin_cos();
    let (dx, dy) = (xj.x_m - xi.x_m, xj.y_m - xi.y_m);
    // Rows of Rz^T Ri^T, and of Rz^T d(Ri^T)/d theta_i applied to (dx, dy).
    let m = [
        [cz * ci - sz * si, cz * si + sz * ci],
        [-sz * ci - cz * si, -sz * si + cz * ci],
    ];
    let (ux, uy) = (-si * dx + ci * dy, -ci * dx - si * dy);
    let dtheta = [cz * ux + sz * uy, -sz * ux + cz * uy];
    let a = [
        [-m[0][0], -m[0][1], dtheta[0]],
        [-m[1][0], -m[1][1], dtheta[1]],
        [0.0, 0.0, -1.0],
    ];
    let b = [
        [m[0][0], m[0][1], 0.0],
        [m[1][0], m[1][1], 0.0],
        [0.0, 0.0, 1.0],
    ];
    (a, b)
}

/// The largest position error of `graph`'s nodes against `truth`, metres (for tests).
#[cfg(test)]
pub(crate) fn worst_position_error(graph: &PoseGraph, truth: &[Pose2]) -> f64 {
    graph
        .nodes
        .iter()
        .zip(truth)
        .map(|(a, b)| a.position().distance_m(&b.position()))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn edge(from: usize, to: usize, measured: Pose2, robust: bool) -> Edge {
        Edge {
            from,
            to,
            measured,
            sigma: [0.05, 0.05, 0.02],
            robust,
        }
    }

    /// The square of side 2 m, driven anticlockwise: (0,0,0), (2,0,90), (2,2,180), (0,2,270).
    fn square() -> Vec<Pose2> {
        (0..4)
            .map(|k| {
                let (x, y) = [(0.0, 0.0), (2.0, 0.0), (2.0, 2.0), (0.0, 2.0)][k];
                Pose2::new(
                    x,
                    y,
                    normalize_angle_rad(k as f64 * std::f64::consts::FRAC_PI_2),
                )
            })
            .collect()
    }

    /// Each leg of the square measured as 2 m ahead and a quarter turn left.
    fn leg() -> Pose2 {
        Pose2::new(2.0, 0.0, std::f64::consts::FRAC_PI_2)
    }

    #[test]
    fn jacobians_match_finite_differences() {
        let xi = Pose2::new(0.3, -1.2, 0.7);
        let xj = Pose2::new(1.9, 0.4, -2.5);
        let z = Pose2::new(1.1, 0.2, 2.9);
        let (a, b) = jacobians(&xi, &xj, &z);
        let h = 1e-7;
        for c in 0..3 {
            let bump = |p: &Pose2, s: f64| {
                let mut v = [p.x_m, p.y_m, p.theta_rad];
                v[c] += s;
                Pose2::new(v[0], v[1], v[2])
            };
            let di: Vec<f64> = (0..3)
                .map(|r| {
                    (error(&bump(&xi, h), &xj, &z)[r] - error(&bump(&xi, -h), &xj, &z)[r])
                        / (2.0 * h)
                })
                .collect();
            let dj: Vec<f64> = (0..3)
                .map(|r| {
                    (error(&xi, &bump(&xj, h), &z)[r] - error(&xi, &bump(&xj, -h), &z)[r])
                        / (2.0 * h)
                })
                .collect();
            for r in 0..3 {
                assert!((a[r][c] - di[r]).abs() < 1e-6, "A[{r}][{c}]");
                assert!((b[r][c] - dj[r]).abs() < 1e-6, "B[{r}][{c}]");
            }
        }
    }

    #[test]
    fn a_closed_square_is_recovered_from_a_drifted_start() {
        // Exact measurements around the square; the initial poses drift (each leg 10 % long
        // and 5 deg over-turned), as a front end's would. The optimum is the square itself.
        let truth = square();
        let mut drifted = vec![Pose2::default()];
        let bad_leg = Pose2::new(2.2, 0.0, std::f64::consts::FRAC_PI_2 + 0.087);
        for _ in 1..4 {
            let last = *drifted.last().unwrap();
            drifted.push(last.compose(&bad_leg));
        }
        let mut g = PoseGraph::new(drifted);
        for k in 0..3 {
            g.add_edge(edge(k, k + 1, leg(), false)).unwrap();
        }
        // The closure: node 0 seen from node 3 is again one leg on.
        g.add_edge(edge(3, 0, leg(), true)).unwrap();
        let report = g.optimise(&OptimiseParams::default()).unwrap();
        assert!(report.cost[1] < 1e-12 && report.cost[0] > 1.0, "{report:?}");
        for (got, want) in g.nodes.iter().zip(&truth) {
            assert!(
                got.position().distance_m(&want.position()) < 1e-6,
                "{got:?}"
            );
            assert!(
                normalize_angle_rad(got.theta_rad - want.theta_rad).abs() < 1e-6,
                "{got:?}"
            );
        }
    }

    /// The square driven twice (8 nodes, the truth) and its graph of exact odometry edges.
    fn two_laps() -> (Vec<Pose2>, PoseGraph) {
        let one = square();
        let truth: Vec<Pose2> = one.iter().chain(one.iter()).copied().collect();
        let mut g = PoseGraph::new(truth.clone());
        for k in 0..7 {
            g.add_edge(edge(k, k + 1, leg(), false)).unwrap();
        }
        (truth, g)
    }

    #[test]
    fn a_false_closure_is_weighed_down_by_the_cauchy_loss() {
        // A square driven twice (8 nodes), odometry exact; true closures 4 -> 0 style (node
        // k + 4 is node k) and one false closure claiming node 6 sits 1.5 m from node 2's
        // place (a symmetric corridor's mistake).
        let (truth, mut g) = two_laps();
        for k in 0..4 {
            g.add_edge(edge(k, k + 4, Pose2::default(), true)).unwrap();
        }
        let wrong = Pose2::new(1.5, 0.0, 0.0);
        g.add_edge(edge(2, 6, wrong, true)).unwrap();
        let mut plain = g.clone();
        for e in &mut plain.edges {
            e.robust = false;
        }
        let params = OptimiseParams::default();
        g.optimise(&params).unwrap();
        plain.optimise(&params).unwrap();
        let worst = |g: &PoseGraph| worst_position_error(g, &truth);
        // Without the loss the false edge pulls the poses by decimetres. With it, an edge 30
        // sigma off (1.5 m / 0.05 m) keeps weight 1 / (1 + 30^2) = 0.0011 and pulls by
        // millimetres.
        assert!(worst(&plain) > 0.1, "{}", worst(&plain));
        assert!(worst(&g) < 0.005, "{}", worst(&g));
        let false_edge = g.edges.last().unwrap();
        assert!(g.weight(false_edge, &params) < 0.002);
        // Dropped as an outlier, it pulls no longer: the poses are those of the graph
        // without it, which are the truth (every other edge is exact).
        let (dropped, optimisations) = g.drop_outliers(&params, 0.3).unwrap();
        assert_eq!(optimisations, 1);
        assert_eq!(dropped.len(), 1);
        assert_eq!(dropped[0].robust_index, 4);
        assert!(dropped[0].weight < 0.002, "{dropped:?}");
        assert_eq!(g.edges.iter().filter(|e| e.robust).count(), 4);
        assert!(worst(&g) < 1e-6, "{}", worst(&g));
    }

    #[test]
    fn outliers_among_the_closures_are_dropped_by_their_index() {
        // The square driven twice, exact odometry; robust edges in this order: 0 -> 4 true,
        // 1 -> 5 false (1.5 m off), 1 -> 5 true, 2 -> 6 true, 3 -> 7 true, 2 -> 6 false (1.2 m
        // off sideways).
        let (truth, mut g) = two_laps();
        let same = Pose2::default();
        for (from, measured) in [
            (0, same),
            (1, Pose2::new(1.5, 0.0, 0.0)),
            (1, same),
            (2, same),
            (3, same),
            (2, Pose2::new(0.0, 1.2, 0.0)),
        ] {
            g.add_edge(edge(from, from + 4, measured, true)).unwrap();
        }
        let params = OptimiseParams::default();
        g.optimise(&params).unwrap();
        let (dropped, _) = g.drop_outliers(&params, 0.3).unwrap();
        let mut indices: Vec<usize> = dropped.iter().map(|d| d.robust_index).collect();
        indices.sort_unstable();
        assert_eq!(indices, [1, 5], "{dropped:?}");
        // What is left is the true closures, and the poses are the truth.
        let robust: Vec<&Edge> = g.edges.iter().filter(|e| e.robust).collect();
        assert_eq!(robust.len(), 4);
        assert!(robust.iter().all(|e| e.measured == same));
        assert!(worst_position_error(&g, &truth) < 1e-6);
    }

    #[test]
    fn bad_edges_are_refused() {
        let mut g = PoseGraph::new(square());
        assert!(g.add_edge(edge(0, 4, leg(), false)).is_err());
        assert!(g.add_edge(edge(1, 1, leg(), false)).is_err());
        let mut e = edge(0, 1, leg(), false);
        e.sigma[2] = 0.0;
        assert!(g.add_edge(e).is_err());
    }
}
