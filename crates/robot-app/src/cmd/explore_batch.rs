//! `robot-app explore --seeds A..B`: one simulated exploration per seed, each in its own
//! folder, and `explore-batch.json` with every run and their minimum and median figures.

use std::path::Path;

use anyhow::Context;
use serde::Serialize;
use serde_json::Value;

use super::explore::ExploreArgs;
use crate::outputs::write_atomic;

/// Coverage and map accuracy bars of the exploration issue (counted in the table).
const COVERAGE_BAR: f64 = 0.95;
const ACCURACY_BAR: f64 = 0.98;

/// `explore-batch.json`.
#[derive(Debug, Serialize)]
struct BatchFile {
    command: String,
    aggregates: Aggregates,
    /// Every run's `explore.json`, seed order.
    runs: Vec<Value>,
}

/// Minimum and median over the runs that have the figure (`null` when none has).
#[derive(Debug, Serialize)]
struct Aggregates {
    runs: usize,
    runs_with_collision: usize,
    min_coverage_share: Option<f64>,
    median_coverage_share: Option<f64>,
    min_map_accuracy_share: Option<f64>,
    median_map_accuracy_share: Option<f64>,
    min_slam_map_coverage_share: Option<f64>,
    median_slam_map_coverage_share: Option<f64>,
    min_slam_map_accuracy_share: Option<f64>,
    median_slam_map_accuracy_share: Option<f64>,
    median_final_position_error_m: Option<f64>,
    max_final_position_error_m: Option<f64>,
}

/// Runs the exploration of `args` once per seed of `seeds`.
pub fn run(args: ExploreArgs, seeds: &str) -> anyhow::Result<()> {
    let range = super::batch::parse_seeds(seeds)?;
    let max = super::batch::MAX_RUNS;
    if range.end - range.start > max {
        anyhow::bail!("--seeds {seeds}: at most {max} explorations at once; split the range");
    }
    let out = args.options.out.clone();
    std::fs::create_dir_all(&out).with_context(|| format!("cannot create {}", out.display()))?;
    let mut runs = Vec::new();
    let mut interrupted = false;
    for seed in range {
        if crate::interrupt::requested() {
            interrupted = true;
            break;
        }
        let mut one = args.clone();
        one.seeds = None;
        one.sim.seed = seed;
        one.options.out = out.join(format!("seed-{seed}"));
        let result = super::explore::run(one.clone());
        // A failed exploration still wrote its explore.json; anything else stops the batch.
        let summary = one.options.out.join("explore.json");
        match read_json(&summary) {
            Ok(v) => runs.push(v),
            Err(read) => {
                return Err(result.err().unwrap_or(read)).with_context(|| format!("seed {seed}"));
            }
        }
        if let Err(e) = result {
            if e.downcast_ref::<crate::interrupt::Interrupted>().is_some() {
                interrupted = true;
                break;
            }
            tracing::warn!("seed {seed}: {e:#}");
        }
    }
    // The seeds done so far are written, also after Ctrl-C.
    let aggregates = aggregate(&runs);
    let file = BatchFile {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        aggregates,
        runs,
    };
    let mut text = serde_json::to_string_pretty(&file)?;
    text.push('\n');
    let path = out.join("explore-batch.json");
    write_atomic(&path, text.as_bytes())?;
    print_table(&file);
    crate::say!("explore-batch.json: {}", path.display());
    if interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    Ok(())
}

fn read_json(path: &Path) -> anyhow::Result<Value> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("reading {}", path.display()))?;
    serde_json::from_str(&text).with_context(|| format!("parsing {}", path.display()))
}

/// The finite values of `key` over the runs, sorted.
fn values(runs: &[Value], key: &str) -> Vec<f64> {
    let mut v: Vec<f64> = runs
        .iter()
        .filter_map(|r| r[key].as_f64())
        .filter(|x| x.is_finite())
        .collect();
    v.sort_by(f64::total_cmp);
    v
}

/// The median of sorted `v` (the mean of the middle two for an even count).
fn median(v: &[f64]) -> Option<f64> {
    let n = v.len();
    match n {
        0 => None,
        _ if n % 2 == 1 => Some(v[n / 2]),
        _ => Some(0.5 * (v[n / 2 - 1] + v[n / 2])),
    }
}

fn aggregate(runs: &[Value]) -> Aggregates {
    let of = |key: &str| {
        let v = values(runs, key);
        (v.first().copied(), median(&v), v.last().copied())
    };
    let (min_cov, med_cov, _) = of("coverage_share");
    let (min_acc, med_acc, _) = of("map_accuracy_share");
    let (min_scov, med_scov, _) = of("slam_map_coverage_share");
    let (min_sacc, med_sacc, _) = of("slam_map_accuracy_share");
    let (_, med_err, max_err) = of("final_position_error_m");
    Aggregates {
        runs: runs.len(),
        runs_with_collision: runs
            .iter()
            .filter(|r| r["collisions"].as_u64().unwrap_or(0) > 0)
            .count(),
        min_coverage_share: min_cov,
        median_coverage_share: med_cov,
        min_map_accuracy_share: min_acc,
        median_map_accuracy_share: med_acc,
        min_slam_map_coverage_share: min_scov,
        median_slam_map_coverage_share: med_scov,
        min_slam_map_accuracy_share: min_sacc,
        median_slam_map_accuracy_share: med_sacc,
        median_final_position_error_m: med_err,
        max_final_position_error_m: max_err,
    }
}

fn print_table(file: &BatchFile) {
    let pct = |v: Option<f64>| v.map_or("-".into(), |v| format!("{:.1} %", 100.0 * v));
    let at_least = |key: &str, bar: f64| {
        let v = values(&file.runs, key);
        if v.is_empty() {
            "-".to_string()
        } else {
            format!("{} of {}", v.iter().filter(|x| **x >= bar).count(), v.len())
        }
    };
    let a = &file.aggregates;
    crate::say!(
        "{:<10} {:>9} {:>9} {:>8} {:>9} {:>9} {:>8} {:>10}",
        "map",
        "cov. min",
        "cov. med",
        ">= 95 %",
        "acc. min",
        "acc. med",
        ">= 98 %",
        "collisions"
    );
    crate::say!(
        "{:<10} {:>9} {:>9} {:>8} {:>9} {:>9} {:>8} {:>10}",
        "own",
        pct(a.min_coverage_share),
        pct(a.median_coverage_share),
        at_least("coverage_share", COVERAGE_BAR),
        pct(a.min_map_accuracy_share),
        pct(a.median_map_accuracy_share),
        at_least("map_accuracy_share", ACCURACY_BAR),
        a.runs_with_collision
    );
    if a.median_slam_map_accuracy_share.is_some() {
        crate::say!(
            "{:<10} {:>9} {:>9} {:>8} {:>9} {:>9} {:>8} {:>10}",
            "slam",
            pct(a.min_slam_map_coverage_share),
            pct(a.median_slam_map_coverage_share),
            at_least("slam_map_coverage_share", COVERAGE_BAR),
            pct(a.min_slam_map_accuracy_share),
            pct(a.median_slam_map_accuracy_share),
            at_least("slam_map_accuracy_share", ACCURACY_BAR),
            ""
        );
    }
    let m = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.3} m"));
    crate::say!(
        "{} runs; final localisation error median {}, max {}",
        a.runs,
        m(a.median_final_position_error_m),
        m(a.max_final_position_error_m)
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn minimum_median_and_maximum_by_hand() {
        let runs: Vec<Value> = [
            (0.9, 0.2, 0),
            (1.0, 0.1, 1),
            (0.95, 0.4, 0),
            (0.97, f64::NAN, 0),
        ]
        .iter()
        .map(|&(c, e, k)| {
            serde_json::json!({
                "coverage_share": c,
                "final_position_error_m": if e.is_nan() { Value::Null } else { e.into() },
                "collisions": k,
                "slam_map_accuracy_share": null,
            })
        })
        .collect();
        let a = aggregate(&runs);
        assert_eq!(a.runs, 4);
        assert_eq!(a.runs_with_collision, 1);
        assert_eq!(a.min_coverage_share, Some(0.9));
        // 0.9, 0.95, 0.97, 1.0: the middle two's mean.
        assert!((a.median_coverage_share.unwrap() - 0.96).abs() < 1e-12);
        // Errors 0.1, 0.2, 0.4 (one run without): median 0.2, max 0.4.
        assert_eq!(a.median_final_position_error_m, Some(0.2));
        assert_eq!(a.max_final_position_error_m, Some(0.4));
        assert_eq!(a.median_slam_map_accuracy_share, None);
    }
}
