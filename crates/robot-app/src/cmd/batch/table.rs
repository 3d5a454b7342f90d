//! Rows of `batch.json`, their aggregates per group and method, and the summary table.

use serde::Serialize;
use sim_laser::WorldKind;

use crate::outputs::Reason;
use slam::eval::{median, percentile};

/// One row of batch.json.
#[derive(Debug, Clone, Serialize)]
pub struct BatchRow {
    /// Group the run is reported in.
    pub group: String,
    /// World kind: `paper`, `random`, `corridor`, `clutter` or `file`.
    pub kind: WorldKind,
    /// World name.
    pub world: String,
    /// Pair index within its world (random pairs only).
    pub pair: Option<usize>,
    /// Method.
    pub method: String,
    /// Seed.
    pub seed: u64,
    /// Start pose.
    pub start: crate::outputs::PoseOut,
    /// Target.
    pub goal: crate::outputs::PointOut,
    /// Success: true position within 0.3 m of the target, no collision.
    pub reached: bool,
    /// Why the run ended.
    pub reason: Reason,
    /// Legs.
    pub legs: usize,
    /// Scans.
    pub scans: usize,
    /// Collisions.
    pub collisions: usize,
    /// Final localisation error, metres.
    pub final_position_error_m: Option<f64>,
    /// Final heading error, degrees.
    pub final_heading_error_deg: Option<f64>,
    /// ATE RMSE over the legs, metres.
    pub ate_rmse_m: Option<f64>,
    /// True distance to the target at the end, metres.
    pub goal_distance_m: Option<f64>,
    /// Distance commanded, metres.
    pub commanded_path_length_m: f64,
    /// Distance truly driven, metres.
    pub true_path_length_m: Option<f64>,
    /// Shortest free path from start to target, metres (`null`: none found).
    pub geodesic_m: Option<f64>,
    /// Success weighted by path length of the run (`null` without a geodesic).
    pub spl: Option<f64>,
    /// CPU time, seconds.
    pub cpu_time_s: f64,
    /// The navigator's position uncertainty at the end, metres (its own error model).
    pub final_position_sigma_m: Option<f64>,
    /// How it ended.
    pub note: String,
}

/// Aggregates of one group and method.
#[derive(Debug, Clone, Serialize)]
pub struct Aggregate {
    /// Group.
    pub group: String,
    /// World kind of the group's runs.
    pub kind: WorldKind,
    /// Method.
    pub method: String,
    /// Runs.
    pub runs: usize,
    /// Successful runs.
    pub reached: usize,
    /// Share of the runs that succeeded, 0 to 1.
    pub success_share: f64,
    /// SPL: the mean of the runs' SPL over the runs with a geodesic (`null` if none has one).
    pub spl: Option<f64>,
    /// Runs with a geodesic, the ones `spl` averages.
    pub spl_runs: usize,
    /// Runs with a collision.
    pub runs_with_collision: usize,
    /// Median final localisation error, metres.
    pub median_final_error_m: f64,
    /// 90th percentile of the final localisation error, metres.
    pub p90_final_error_m: f64,
    /// Median of the navigator's final position uncertainty, metres.
    pub median_final_sigma_m: Option<f64>,
    /// Share of the runs with both whose final error lies within their final uncertainty.
    pub within_final_sigma_share: Option<f64>,
    /// Median ATE RMSE, metres.
    pub median_ate_rmse_m: f64,
    /// Median legs.
    pub median_legs: f64,
    /// Median CPU time per run, seconds.
    pub median_cpu_time_s: f64,
    /// Count of runs per end reason (`false_arrival`: the estimate reached the target, the
    /// robot did not).
    pub reasons: std::collections::BTreeMap<String, usize>,
}

/// Aggregates rows per group and method, in first-seen order.
pub fn aggregate(rows: &[BatchRow]) -> Vec<Aggregate> {
    let mut keys: Vec<(String, String, WorldKind)> = Vec::new();
    for r in rows {
        let k = (r.group.clone(), r.method.clone(), r.kind);
        if !keys.iter().any(|(g, m, _)| *g == k.0 && *m == k.1) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(group, method, kind)| {
            let sel: Vec<&BatchRow> = rows
                .iter()
                .filter(|r| r.group == group && r.method == method)
                .collect();
            let runs = sel.len();
            let reached = sel.iter().filter(|r| r.reached).count();
            let mut fe: Vec<f64> = sel
                .iter()
                .filter_map(|r| r.final_position_error_m)
                .collect();
            let mut ate: Vec<f64> = sel.iter().filter_map(|r| r.ate_rmse_m).collect();
            let mut legs: Vec<f64> = sel.iter().map(|r| r.legs as f64).collect();
            let mut cpu: Vec<f64> = sel.iter().map(|r| r.cpu_time_s).collect();
            let spls: Vec<f64> = sel.iter().filter_map(|r| r.spl).collect();
            let mut sigmas: Vec<f64> = sel
                .iter()
                .filter_map(|r| r.final_position_sigma_m)
                .collect();
            let judged: Vec<bool> = sel
                .iter()
                .filter_map(|r| Some(r.final_position_error_m? <= r.final_position_sigma_m?))
                .collect();
            let mut reasons = std::collections::BTreeMap::new();
            for r in &sel {
                *reasons.entry(r.reason.to_string()).or_insert(0) += 1;
            }
            Aggregate {
                runs,
                reached,
                success_share: if runs == 0 {
                    0.0
                } else {
                    reached as f64 / runs as f64
                },
                spl: (!spls.is_empty()).then(|| spls.iter().sum::<f64>() / spls.len() as f64),
                spl_runs: spls.len(),
                runs_with_collision: sel.iter().filter(|r| r.collisions > 0).count(),
                median_final_error_m: median(&mut fe),
                p90_final_error_m: percentile(&mut fe, 0.9),
                median_final_sigma_m: (!sigmas.is_empty()).then(|| median(&mut sigmas)),
                within_final_sigma_share: (!judged.is_empty())
                    .then(|| judged.iter().filter(|&&w| w).count() as f64 / judged.len() as f64),
                median_ate_rmse_m: median(&mut ate),
                median_legs: median(&mut legs),
                median_cpu_time_s: median(&mut cpu),
                reasons,
                group,
                kind,
                method,
            }
        })
        .collect()
}

/// The summary table printed on stdout.
pub fn table(aggs: &[Aggregate]) -> String {
    use std::fmt::Write as _;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<20} {:<8} {:<9} {:>5} {:>8} {:>6} {:>6} {:>10} {:>9} {:>9} {:>6} {:>8}  reasons",
        "group",
        "kind",
        "method",
        "runs",
        "success",
        "SPL",
        "coll.",
        "med.err m",
        "p90 err m",
        "med.ATE m",
        "legs",
        "cpu s"
    );
    for a in aggs {
        let reasons: Vec<String> = a.reasons.iter().map(|(k, v)| format!("{k}:{v}")).collect();
        let _ = writeln!(
            s,
            "{:<20} {:<8} {:<9} {:>5} {:>7.1}% {:>6} {:>6} {:>10.3} {:>9.3} {:>9.3} {:>6.1} {:>8.3}  {}",
            a.group,
            a.kind,
            a.method,
            a.runs,
            100.0 * a.success_share,
            a.spl.map_or_else(|| "-".into(), |v| format!("{v:.3}")),
            a.runs_with_collision,
            a.median_final_error_m,
            a.p90_final_error_m,
            a.median_ate_rmse_m,
            a.median_legs,
            a.median_cpu_time_s,
            reasons.join(" ")
        );
    }
    s
}
