//! `robot-app batch`: many simulated runs in parallel, a summary table and `batch.json`.

use std::path::PathBuf;
use std::sync::Arc;

use anyhow::{Context, bail};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use scan_types::{Pose2, WorldPoint};
use serde::Serialize;
use sim_laser::{SensorPreset, World};

use super::sim::{SimSpec, load_world, simulate};
use crate::config::{Config, Method};
use crate::outputs::{Reason, write_atomic};

/// Arguments of `robot-app batch`.
#[derive(Debug, Args)]
pub struct BatchArgs {
    /// Worlds to run in: `paper` or world files (default: paper).
    #[arg(long, num_args = 1.., value_name = "W")]
    pub worlds: Vec<String>,
    /// Seeds A..B (B excluded): each seed gives one run per scenario and world.
    #[arg(long, default_value = "0..50", value_name = "A..B")]
    pub seeds: String,
    /// Also run in K seeded random worlds (generated; corridors reported apart).
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub random_worlds: usize,
    /// Scenarios per seed: `paper` (the paper's start and target, paper world only),
    /// `pairs` (a random start/target pair at least --min-distance apart), or both.
    #[arg(long, default_value = "both", value_parser = ["paper", "pairs", "both"])]
    pub scenarios: String,
    /// Smallest start-target distance of a random pair, metres.
    #[arg(long, default_value_t = 6.0)]
    pub min_distance: f64,
    /// Methods to run, comma-separated (e.g. goalseek,paper for a side-by-side table).
    #[arg(long, default_value = "goalseek", value_delimiter = ',')]
    pub method: Vec<Method>,
    /// TOML file overriding tuning parameters (applied to every method's preset).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Sensor preset.
    #[arg(long, default_value = "paper")]
    pub sensor: String,
    /// Output folder for batch.json.
    #[arg(long, default_value = "goalseek-batch")]
    pub out: PathBuf,
    /// Also write each run's outputs under OUT/runs/.
    #[arg(long)]
    pub keep_runs: bool,
    /// Worker threads (default: all cores).
    #[arg(long)]
    pub jobs: Option<usize>,
}

/// One row of batch.json.
#[derive(Debug, Clone, Serialize)]
pub struct BatchRow {
    /// Group the run is reported in.
    pub group: String,
    /// World name.
    pub world: String,
    /// Method.
    pub method: String,
    /// Seed.
    pub seed: u64,
    /// Start `[x, y, theta_deg]`.
    pub start: [f64; 3],
    /// Target `[x, y]`.
    pub goal: [f64; 2],
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
    /// Distance driven, metres.
    pub path_length_m: f64,
    /// CPU time, seconds.
    pub cpu_time_s: f64,
    /// How it ended.
    pub note: String,
}

/// Aggregates of one group and method.
#[derive(Debug, Clone, Serialize)]
pub struct Aggregate {
    /// Group.
    pub group: String,
    /// Method.
    pub method: String,
    /// Runs.
    pub runs: usize,
    /// Successful runs.
    pub reached: usize,
    /// Success rate, percent.
    pub success_pct: f64,
    /// Runs with a collision.
    pub runs_with_collision: usize,
    /// Median final localisation error, metres.
    pub median_final_error_m: f64,
    /// 90th percentile of the final localisation error, metres.
    pub p90_final_error_m: f64,
    /// Median ATE RMSE, metres.
    pub median_ate_rmse_m: f64,
    /// Median legs.
    pub median_legs: f64,
    /// Median CPU time per run, seconds.
    pub median_cpu_time_s: f64,
    /// Count of runs per end reason.
    pub reasons: std::collections::BTreeMap<String, usize>,
}

#[derive(Serialize)]
struct BatchFile<'a> {
    command: String,
    aggregates: &'a [Aggregate],
    rows: &'a [BatchRow],
}

struct Job {
    group: String,
    spec: SimSpec,
}

/// The seeded random world `k` and the group it is reported in.
pub fn random_world(k: u64) -> anyhow::Result<(World, String)> {
    let _ = k;
    bail!("--random-worlds: the world generator is not available in this build")
}

/// Parses `A..B` (B excluded) or a single seed.
pub fn parse_seeds(s: &str) -> anyhow::Result<std::ops::Range<u64>> {
    let bad = || format!("--seeds '{s}': expected A..B (B excluded) or N");
    if let Some((a, b)) = s.split_once("..") {
        let a: u64 = a.trim().parse().with_context(bad)?;
        let b: u64 = b.trim().parse().with_context(bad)?;
        if b <= a {
            bail!("--seeds '{s}': the range is empty");
        }
        Ok(a..b)
    } else {
        let a: u64 = s.trim().parse().with_context(bad)?;
        Ok(a..a + 1)
    }
}

/// Free cells (robot centre positions with room for the robot) of `world` on a grid, with
/// the connected component each belongs to.
pub struct FreeSpace {
    lo: WorldPoint,
    cell_m: f64,
    nx: usize,
    ny: usize,
    component: Vec<u32>,
}

impl FreeSpace {
    /// Rasterises `world` at `cell_m`, keeping cells at least `room_m` from any obstacle.
    pub fn new(world: &World, room_m: f64, cell_m: f64) -> Self {
        let (lo, hi) = world.bounds();
        let nx = ((hi.x_m() - lo.x_m()) / cell_m).ceil().max(1.0) as usize;
        let ny = ((hi.y_m() - lo.y_m()) / cell_m).ceil().max(1.0) as usize;
        let centre = |ix: usize, iy: usize| {
            WorldPoint::new(
                lo.x_m() + (ix as f64 + 0.5) * cell_m,
                lo.y_m() + (iy as f64 + 0.5) * cell_m,
            )
        };
        let free: Vec<bool> = (0..nx * ny)
            .map(|k| {
                let p = centre(k % nx, k / nx);
                !world.is_occupied(p) && world.clearance(p, room_m + 0.01) >= room_m
            })
            .collect();
        let mut component = vec![0u32; nx * ny];
        let mut next = 1u32;
        for startk in 0..nx * ny {
            if !free[startk] || component[startk] != 0 {
                continue;
            }
            let mut stack = vec![startk];
            component[startk] = next;
            while let Some(k) = stack.pop() {
                let (x, y) = (k % nx, k / nx);
                let mut push = |xx: usize, yy: usize| {
                    let kk = yy * nx + xx;
                    if free[kk] && component[kk] == 0 {
                        component[kk] = next;
                        stack.push(kk);
                    }
                };
                if x > 0 {
                    push(x - 1, y);
                }
                if x + 1 < nx {
                    push(x + 1, y);
                }
                if y > 0 {
                    push(x, y - 1);
                }
                if y + 1 < ny {
                    push(x, y + 1);
                }
            }
            next += 1;
        }
        Self {
            lo,
            cell_m,
            nx,
            ny,
            component,
        }
    }

    /// A random start pose and target in one connected free region, at least `min_m` apart.
    pub fn random_pair(&self, rng: &mut ChaCha8Rng, min_m: f64) -> Option<(Pose2, WorldPoint)> {
        let cells: Vec<usize> = (0..self.component.len())
            .filter(|&k| self.component[k] != 0)
            .collect();
        if cells.is_empty() {
            return None;
        }
        let centre = |k: usize| {
            WorldPoint::new(
                self.lo.x_m() + ((k % self.nx) as f64 + 0.5) * self.cell_m,
                self.lo.y_m() + ((k / self.nx) as f64 + 0.5) * self.cell_m,
            )
        };
        for _ in 0..10_000 {
            let a = cells[rng.random_range(0..cells.len())];
            let b = cells[rng.random_range(0..cells.len())];
            if self.component[a] != self.component[b] {
                continue;
            }
            let (pa, pb) = (centre(a), centre(b));
            if pa.distance_m(&pb) < min_m {
                continue;
            }
            let heading = rng.random_range(-std::f64::consts::PI..std::f64::consts::PI);
            return Some((Pose2::new(pa.x_m(), pa.y_m(), heading), pb));
        }
        let _ = self.ny;
        None
    }
}

fn median(v: &mut [f64]) -> f64 {
    percentile(v, 0.5)
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let pos = q * (v.len() - 1) as f64;
    let (i, f) = (pos.floor() as usize, pos.fract());
    if i + 1 < v.len() {
        v[i] * (1.0 - f) + v[i + 1] * f
    } else {
        v[i]
    }
}

/// Aggregates rows per group and method, in first-seen order.
pub fn aggregate(rows: &[BatchRow]) -> Vec<Aggregate> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.group.clone(), r.method.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(group, method)| {
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
            let mut reasons = std::collections::BTreeMap::new();
            for r in &sel {
                *reasons.entry(r.reason.to_string()).or_insert(0) += 1;
            }
            Aggregate {
                runs,
                reached,
                success_pct: if runs == 0 {
                    0.0
                } else {
                    100.0 * reached as f64 / runs as f64
                },
                runs_with_collision: sel.iter().filter(|r| r.collisions > 0).count(),
                median_final_error_m: median(&mut fe),
                p90_final_error_m: percentile(&mut fe, 0.9),
                median_ate_rmse_m: median(&mut ate),
                median_legs: median(&mut legs),
                median_cpu_time_s: median(&mut cpu),
                reasons,
                group,
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
        "{:<22} {:<9} {:>5} {:>8} {:>6} {:>10} {:>9} {:>9} {:>6} {:>8}  reasons",
        "group",
        "method",
        "runs",
        "success",
        "coll.",
        "med.err m",
        "p90 err",
        "med.ATE",
        "legs",
        "cpu s"
    );
    for a in aggs {
        let reasons: Vec<String> = a.reasons.iter().map(|(k, v)| format!("{k}:{v}")).collect();
        let _ = writeln!(
            s,
            "{:<22} {:<9} {:>5} {:>7.1}% {:>6} {:>10.3} {:>9.3} {:>9.3} {:>6.0} {:>8.3}  {}",
            a.group,
            a.method,
            a.runs,
            a.success_pct,
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

/// Runs `robot-app batch`.
pub fn run(args: BatchArgs) -> anyhow::Result<()> {
    let seeds = parse_seeds(&args.seeds)?;
    let sensor: SensorPreset = args
        .sensor
        .parse()
        .map_err(|e| anyhow::anyhow!("--sensor {}: {e}", args.sensor))?;
    let methods = if args.method.is_empty() {
        vec![Method::Goalseek]
    } else {
        args.method.clone()
    };
    let configs: Vec<Config> = methods
        .iter()
        .map(|m| Config::load(args.config.as_deref(), Some(*m)))
        .collect::<anyhow::Result<_>>()?;
    let paper_scenario = args.scenarios != "pairs";
    let pairs = args.scenarios != "paper";

    // Worlds: (world, name, group prefix, is the paper's world).
    let mut worlds: Vec<(Arc<World>, String, String, bool)> = Vec::new();
    let names = if args.worlds.is_empty() && args.random_worlds == 0 {
        vec!["paper".to_string()]
    } else {
        args.worlds.clone()
    };
    for w in &names {
        if w == "paper" {
            let (world, name) = load_world(None)?;
            worlds.push((world, name, "paper".into(), true));
        } else {
            let (world, name) = load_world(Some(std::path::Path::new(w)))?;
            worlds.push((world, name.clone(), name, false));
        }
    }
    for k in 0..args.random_worlds {
        let (world, group) = random_world(k as u64)?;
        worlds.push((Arc::new(world), format!("random-{k}"), group, false));
    }

    let room = configs[0].robot.radius_m + 0.1;
    let mut jobs: Vec<Job> = Vec::new();
    for (world, name, group, is_paper) in &worlds {
        let free = if pairs {
            Some(FreeSpace::new(world, room, 0.1))
        } else {
            None
        };
        for seed in seeds.clone() {
            for cfg in &configs {
                if *is_paper && paper_scenario {
                    let mut spec = SimSpec::paper(seed, cfg.clone());
                    spec.sensor = sensor;
                    spec.world = world.clone();
                    jobs.push(Job {
                        group: "paper-scenario".into(),
                        spec,
                    });
                }
                if let Some(free) = &free {
                    let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_0000_0000);
                    let Some((start, goal)) = free.random_pair(&mut rng, args.min_distance) else {
                        tracing::warn!(world = %name, seed, "no start/target pair far enough apart");
                        continue;
                    };
                    jobs.push(Job {
                        group: format!("{group}-pairs"),
                        spec: SimSpec {
                            world: world.clone(),
                            world_name: name.clone(),
                            start,
                            goal,
                            sensor,
                            seed,
                            noise: true,
                            config: cfg.clone(),
                        },
                    });
                }
            }
        }
    }
    if jobs.is_empty() {
        bail!("nothing to run: no worlds, seeds or scenarios");
    }
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.jobs.unwrap_or(0))
        .build()
        .context("cannot start the worker threads")?;
    let bar = ProgressBar::new(jobs.len() as u64);
    bar.set_style(
        ProgressStyle::with_template("{bar:40} {pos}/{len} runs, {elapsed} elapsed, eta {eta}")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let keep = args.keep_runs.then(|| args.out.join("runs"));
    let rows: Vec<anyhow::Result<BatchRow>> = pool.install(|| {
        jobs.par_iter()
            .map(|job| {
                let run = simulate(&job.spec, None);
                if let Some(dir) = &keep {
                    let sub = dir.join(format!(
                        "{}-{}-{}",
                        job.group, job.spec.config.method, job.spec.seed
                    ));
                    super::sim::write_outputs(&sub, &run, &sub.display().to_string())?;
                }
                bar.inc(1);
                let s = run.summary;
                Ok(BatchRow {
                    group: job.group.clone(),
                    world: job.spec.world_name.clone(),
                    method: s.method,
                    seed: job.spec.seed,
                    start: s.start,
                    goal: s.goal,
                    reached: s.reached,
                    reason: s.reason,
                    legs: s.legs,
                    scans: s.scans,
                    collisions: s.collisions,
                    final_position_error_m: s.final_position_error_m,
                    final_heading_error_deg: s.final_heading_error_deg,
                    ate_rmse_m: s.ate_rmse_m,
                    goal_distance_m: s.goal_distance_m,
                    path_length_m: s.path_length_m,
                    cpu_time_s: s.cpu_time_s,
                    note: s.note,
                })
            })
            .collect()
    });
    bar.finish_and_clear();
    let rows: Vec<BatchRow> = rows.into_iter().collect::<anyhow::Result<_>>()?;
    let aggs = aggregate(&rows);
    let file = BatchFile {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        aggregates: &aggs,
        rows: &rows,
    };
    let mut text = serde_json::to_string_pretty(&file)?;
    text.push('\n');
    write_atomic(&args.out.join("batch.json"), text.as_bytes())?;
    #[allow(clippy::print_stdout)]
    {
        print!("{}", table(&aggs));
        println!("batch.json: {}", args.out.join("batch.json").display());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seeds_parse() {
        assert_eq!(parse_seeds("0..50").unwrap(), 0..50);
        assert_eq!(parse_seeds("7").unwrap(), 7..8);
        assert!(parse_seeds("5..5").is_err());
        assert!(parse_seeds("a..b").is_err());
    }

    #[test]
    fn percentiles_by_hand() {
        let mut v = vec![4.0, 1.0, 3.0, 2.0];
        assert_eq!(median(&mut v), 2.5);
        let mut v = vec![0.0, 10.0];
        assert!((percentile(&mut v, 0.9) - 9.0).abs() < 1e-12);
        assert!(median(&mut []).is_nan());
    }

    fn row(group: &str, reached: bool, err: f64) -> BatchRow {
        BatchRow {
            group: group.into(),
            world: "w".into(),
            method: "goalseek".into(),
            seed: 0,
            start: [0.0; 3],
            goal: [0.0; 2],
            reached,
            reason: if reached {
                Reason::Reached
            } else {
                Reason::LegLimit
            },
            legs: 3,
            scans: 10,
            collisions: 0,
            final_position_error_m: Some(err),
            final_heading_error_deg: Some(0.0),
            ate_rmse_m: Some(err),
            goal_distance_m: Some(0.1),
            path_length_m: 1.0,
            cpu_time_s: 0.1,
            note: String::new(),
        }
    }

    #[test]
    fn aggregates_per_group() {
        let rows = vec![
            row("a", true, 0.01),
            row("a", false, 0.03),
            row("b", true, 0.5),
            row("a", true, 0.02),
        ];
        let a = aggregate(&rows);
        assert_eq!(a.len(), 2);
        assert_eq!((a[0].group.as_str(), a[0].runs, a[0].reached), ("a", 3, 2));
        assert!((a[0].success_pct - 200.0 / 3.0).abs() < 1e-9);
        assert!((a[0].median_final_error_m - 0.02).abs() < 1e-12);
        assert_eq!(a[0].reasons["leg_limit"], 1);
        assert!(table(&a).lines().count() == 3);
    }
}
