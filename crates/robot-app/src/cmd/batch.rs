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
use sim_laser::{GenParams, SensorPreset, World, generate_world};

use super::sim::{SimSpec, load_world, simulate};
use crate::config::{Method, Params};
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
    /// Also run in K seeded random worlds: rooms on both sides of a 1.6 m corridor, doors,
    /// clutter (sim-laser's generator, seeds 0..K).
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub random_worlds: usize,
    /// Also run in K seeded wide-corridor worlds (a 4 m wide, 24 m long empty corridor between
    /// rooms; pairs lie in the corridor), reported apart as `corridor`.
    #[arg(long, default_value_t = 0, value_name = "K")]
    pub corridor_worlds: usize,
    /// Random start/target pairs per world (default: one per seed). Pair i uses noise seed
    /// A+i, so pairs are the same for every method.
    #[arg(long, value_name = "N")]
    pub random_pairs: Option<usize>,
    /// Scenarios: `paper` (the paper's start and target in the paper world, or a generated
    /// world's own start and target, once per seed), `pairs` (random start/target pairs at least
    /// --min-distance apart in free space), or both.
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
    /// World kind: `paper`, `random`, `corridor` or `file`.
    pub kind: WorldKind,
    /// World name.
    pub world: String,
    /// Pair index within its world (random pairs only).
    pub pair: Option<usize>,
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
    /// World kind of the group's runs.
    pub kind: WorldKind,
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
    /// Count of runs per end reason (`false_arrival`: the estimate reached the target, the
    /// robot did not).
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
    kind: WorldKind,
    pair: Option<usize>,
    spec: SimSpec,
}

/// What kind of world a run is in (batch rows and groups carry it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum WorldKind {
    /// The paper's world.
    Paper,
    /// A generated rooms-and-corridor world ([`random_world_params`]).
    Random,
    /// A generated wide-corridor world ([`corridor_world_params`]).
    Corridor,
    /// A world loaded from a file.
    File,
}

impl std::fmt::Display for WorldKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        // `pad` so that table widths apply.
        f.pad(match self {
            Self::Paper => "paper",
            Self::Random => "random",
            Self::Corridor => "corridor",
            Self::File => "file",
        })
    }
}

/// Generator parameters of the random worlds: sim-laser's defaults (16 m x 10 m, three rooms
/// on each side of a 1.6 m corridor, doors, 8 boxes and 6 discs of clutter).
pub fn random_world_params() -> GenParams {
    GenParams::default()
}

/// Generator parameters of the wide-corridor worlds: 24 m x 12 m, a 4 m wide corridor with
/// nothing in it between four rooms on each side (the case the paper warns about: long
/// parallel walls with few range jumps).
pub fn corridor_world_params() -> GenParams {
    GenParams {
        width_m: 24.0,
        height_m: 12.0,
        rooms_per_side: 4,
        corridor_width_m: 4.0,
        ..GenParams::default()
    }
}

/// A generated world of `kind` (`Random` or `Corridor`) from seed `k`, with its own start and
/// target.
pub fn generated_world(kind: WorldKind, k: u64) -> anyhow::Result<(World, Pose2, WorldPoint)> {
    let params = match kind {
        WorldKind::Corridor => corridor_world_params(),
        _ => random_world_params(),
    };
    let d = generate_world(k, &params).with_context(|| format!("generating {kind} world {k}"))?;
    let world = d
        .to_world()
        .with_context(|| format!("building {kind} world {k}"))?;
    let [sx, sy, st] = d.start.unwrap_or([0.0; 3]);
    let [tx, ty] = d.target.unwrap_or([0.0; 2]);
    Ok((world, Pose2::new(sx, sy, st), WorldPoint::new(tx, ty)))
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
        self.random_pair_where(rng, min_m, |_| true)
    }

    /// The centre of cell `k`.
    fn centre(&self, k: usize) -> WorldPoint {
        WorldPoint::new(
            self.lo.x_m() + ((k % self.nx) as f64 + 0.5) * self.cell_m,
            self.lo.y_m() + ((k / self.nx) as f64 + 0.5) * self.cell_m,
        )
    }

    /// Free cells (centres) in connected region order.
    pub fn free_cells(&self) -> impl Iterator<Item = WorldPoint> + '_ {
        (0..self.component.len())
            .filter(|&k| self.component[k] != 0)
            .map(|k| self.centre(k))
    }

    /// Whether `p` is a free cell, and its region.
    pub fn region_of(&self, p: WorldPoint) -> Option<u32> {
        let fx = (p.x_m() - self.lo.x_m()) / self.cell_m;
        let fy = (p.y_m() - self.lo.y_m()) / self.cell_m;
        if !(fx >= 0.0 && fy >= 0.0) {
            return None;
        }
        let (ix, iy) = (fx as usize, fy as usize);
        if ix >= self.nx || iy >= self.ny {
            return None;
        }
        Some(self.component[iy * self.nx + ix]).filter(|&c| c != 0)
    }

    /// As [`FreeSpace::random_pair`], with both ends where `keep` holds.
    pub fn random_pair_where(
        &self,
        rng: &mut ChaCha8Rng,
        min_m: f64,
        keep: impl Fn(WorldPoint) -> bool,
    ) -> Option<(Pose2, WorldPoint)> {
        let cells: Vec<usize> = (0..self.component.len())
            .filter(|&k| self.component[k] != 0 && keep(self.centre(k)))
            .collect();
        if cells.is_empty() {
            return None;
        }
        let centre = |k: usize| self.centre(k);
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
            let mut reasons = std::collections::BTreeMap::new();
            for r in &sel {
                // The estimate said "reached" but the robot is not at the target.
                let key = if r.reason == Reason::Reached && !r.reached {
                    "false_arrival".to_string()
                } else {
                    r.reason.to_string()
                };
                *reasons.entry(key).or_insert(0) += 1;
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
        "{:<20} {:<8} {:<9} {:>5} {:>8} {:>6} {:>10} {:>9} {:>9} {:>6} {:>8}  reasons",
        "group",
        "kind",
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
            "{:<20} {:<8} {:<9} {:>5} {:>7.1}% {:>6} {:>10.3} {:>9.3} {:>9.3} {:>6.0} {:>8.3}  {}",
            a.group,
            a.kind,
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
    let configs: Vec<Params> = methods
        .iter()
        .map(|m| crate::config::load(args.config.as_deref(), Some(*m)))
        .collect::<anyhow::Result<_>>()?;
    let own_scenario = args.scenarios != "pairs";
    let pairs = args.scenarios != "paper";
    let n_pairs = args
        .random_pairs
        .unwrap_or((seeds.end - seeds.start) as usize);

    struct WorldEntry {
        world: Arc<World>,
        name: String,
        kind: WorldKind,
        /// The world's own scenario (paper's start/target, or the generator's).
        scenario: Option<(Pose2, WorldPoint)>,
        /// Salt of the pair generator (0 for the paper world and files).
        salt: u64,
        /// Corridor half-width (pairs must lie inside the corridor), metres.
        corridor_half_m: Option<f64>,
    }
    let mut worlds: Vec<WorldEntry> = Vec::new();
    let names = if args.worlds.is_empty() && args.random_worlds == 0 && args.corridor_worlds == 0 {
        vec!["paper".to_string()]
    } else {
        args.worlds.clone()
    };
    for w in &names {
        if w == "paper" {
            let (world, name) = load_world(None)?;
            worlds.push(WorldEntry {
                world,
                name,
                kind: WorldKind::Paper,
                scenario: Some((
                    crate::simsetup::paper_start(),
                    crate::simsetup::paper_target(),
                )),
                salt: 0,
                corridor_half_m: None,
            });
        } else {
            let (world, name) = load_world(Some(std::path::Path::new(w)))?;
            worlds.push(WorldEntry {
                world,
                name,
                kind: WorldKind::File,
                scenario: None,
                salt: 0,
                corridor_half_m: None,
            });
        }
    }
    let room = configs[0].robot.radius_m + 0.1;
    for (kind, count) in [
        (WorldKind::Random, args.random_worlds),
        (WorldKind::Corridor, args.corridor_worlds),
    ] {
        for k in 0..count as u64 {
            let (world, start, target) = generated_world(kind, k)?;
            let salt = (k + 1) << 32
                | if kind == WorldKind::Corridor {
                    1 << 31
                } else {
                    0
                };
            worlds.push(WorldEntry {
                world: Arc::new(world),
                name: format!("{kind}-{k}"),
                kind,
                scenario: Some((start, target)),
                salt,
                corridor_half_m: (kind == WorldKind::Corridor)
                    .then(|| corridor_world_params().corridor_width_m / 2.0 - room),
            });
        }
    }

    let mut jobs: Vec<Job> = Vec::new();
    for w in &worlds {
        let prefix = match w.kind {
            WorldKind::File => w.name.clone(),
            k => k.to_string(),
        };
        let spec = |start: Pose2, goal: WorldPoint, seed: u64, cfg: &Params| SimSpec {
            world: w.world.clone(),
            world_name: w.name.clone(),
            start,
            goal,
            sensor,
            seed,
            noise: true,
            config: cfg.clone(),
        };
        if let (true, Some((start, goal))) = (own_scenario, w.scenario) {
            for seed in seeds.clone() {
                for cfg in &configs {
                    jobs.push(Job {
                        group: format!("{prefix}-scenario"),
                        kind: w.kind,
                        pair: None,
                        spec: spec(start, goal, seed, cfg),
                    });
                }
            }
        }
        if !pairs || n_pairs == 0 {
            continue;
        }
        let free = FreeSpace::new(&w.world, room, 0.1);
        for i in 0..n_pairs {
            let seed = seeds.start + i as u64;
            let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_0000_0000 ^ w.salt);
            let pair = match w.corridor_half_m {
                Some(h) => {
                    free.random_pair_where(&mut rng, args.min_distance, |p| p.y_m().abs() <= h)
                }
                None => free.random_pair(&mut rng, args.min_distance),
            };
            let Some((start, goal)) = pair else {
                tracing::warn!(world = %w.name, seed, "no start/target pair far enough apart");
                continue;
            };
            for cfg in &configs {
                jobs.push(Job {
                    group: format!("{prefix}-pairs"),
                    kind: w.kind,
                    pair: Some(i),
                    spec: spec(start, goal, seed, cfg),
                });
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
                let run = simulate(&job.spec, None)?;
                if let Some(dir) = &keep {
                    let sub = dir.join(format!(
                        "{}-{}-{}-{}",
                        job.group, job.spec.world_name, job.spec.config.method, job.spec.seed
                    ));
                    super::sim::write_outputs(&sub, &run, &sub.display().to_string())?;
                }
                bar.inc(1);
                let s = run.summary;
                Ok(BatchRow {
                    group: job.group.clone(),
                    kind: job.kind,
                    world: job.spec.world_name.clone(),
                    pair: job.pair,
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
            kind: WorldKind::Paper,
            world: "w".into(),
            pair: None,
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
        let t = table(&a);
        assert!(t.lines().count() == 3);
        // The kind column is padded: "paper" then three spaces before the method.
        assert!(t.contains("paper    goalseek"), "{t}");
    }

    #[test]
    fn random_pairs_are_free_far_apart_and_in_the_corridor() {
        for kind in [WorldKind::Random, WorldKind::Corridor] {
            let (world, start, target) = generated_world(kind, 3).unwrap();
            // The generator's own scenario is free for a 0.3 m robot.
            assert!(!world.disc_collides(start.position(), 0.3));
            assert!(!world.disc_collides(target, 0.3));
            let free = FreeSpace::new(&world, 0.4, 0.1);
            let half = corridor_world_params().corridor_width_m / 2.0 - 0.4;
            for i in 0..5u64 {
                let mut rng = ChaCha8Rng::seed_from_u64(i);
                let (s, g) = if kind == WorldKind::Corridor {
                    free.random_pair_where(&mut rng, 6.0, |p| p.y_m().abs() <= half)
                } else {
                    free.random_pair(&mut rng, 6.0)
                }
                .unwrap();
                assert!(s.position().distance_m(&g) >= 6.0);
                // At least the robot radius plus 0.1 m from every obstacle.
                assert!(!world.disc_collides(s.position(), 0.4));
                assert!(!world.disc_collides(g, 0.4));
                assert_eq!(free.region_of(s.position()), free.region_of(g));
                if kind == WorldKind::Corridor {
                    // The corridor is 4 m wide around y = 0.
                    assert!(s.y_m.abs() <= 1.6 && g.y_m().abs() <= 1.6);
                }
            }
        }
    }
}
