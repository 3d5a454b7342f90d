//! The runs of a batch: the worlds it names or generates, each world's own scenario once per
//! seed and its seeded random start/target pairs, for every method.

use std::path::Path;
use std::sync::Arc;

use anyhow::Context;
use scan_types::{Pose2, WorldPoint};
use sim_laser::{PairSampler, SensorPreset, SimSetup, WorldKind, generated_world};

use super::{BatchArgs, MAX_GENERATED_WORLDS, MAX_RUNS, parse_seeds};
use crate::cmd::sim::SimSpec;
use crate::config::{Method, Params};

/// One simulated run of a batch and where it is reported.
pub struct Job {
    /// Group the run is reported in.
    pub group: String,
    /// World kind.
    pub kind: WorldKind,
    /// Pair index within its world (random pairs only).
    pub pair: Option<usize>,
    /// The run.
    pub spec: SimSpec,
}

/// A world of the batch.
struct WorldEntry {
    /// World, name and sensor; start and seed are set per job.
    setup: SimSetup,
    kind: WorldKind,
    /// Index of a generated world (its generator seed; 0 for the paper world and files).
    index: u64,
    /// The world's own scenario (paper's start/target, or the generator's).
    scenario: Option<(Pose2, WorldPoint)>,
}

/// What every world's jobs share.
struct Plan {
    seeds: std::ops::Range<u64>,
    configs: Vec<Params>,
    own_scenario: bool,
    pairs: bool,
    n_pairs: usize,
    min_distance_m: f64,
    /// Clearance of random pair ends: the first method's robot radius plus 0.1 m.
    room_m: f64,
}

/// Every job of `robot-app batch` with `args`, in run order.
pub fn build(args: &BatchArgs) -> anyhow::Result<Vec<Job>> {
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
    if !(args.min_distance.is_finite() && (0.0..=1000.0).contains(&args.min_distance)) {
        anyhow::bail!(
            "--min-distance {}: must be a distance from 0 to 1000 m",
            args.min_distance
        );
    }
    check_size(args, &seeds, configs.len())?;
    let plan = Plan {
        own_scenario: args.scenarios != "pairs",
        pairs: args.scenarios != "paper",
        n_pairs: args
            .random_pairs
            .unwrap_or((seeds.end - seeds.start) as usize),
        min_distance_m: args.min_distance,
        room_m: configs[0].robot.radius_m + 0.1,
        seeds,
        configs,
    };
    let mut jobs = Vec::new();
    for mut w in worlds(args, &plan.configs)? {
        w.setup.sensor = sensor;
        world_jobs(&w, &plan, &mut jobs);
    }
    Ok(jobs)
}

/// Refuses a batch too large to plan: its generated worlds and jobs are held in memory
/// before the first run.
pub(crate) fn check_size(
    args: &BatchArgs,
    seeds: &std::ops::Range<u64>,
    methods: usize,
) -> anyhow::Result<()> {
    let generated =
        args.random_worlds as u64 + args.corridor_worlds as u64 + args.clutter_worlds as u64;
    if generated > MAX_GENERATED_WORLDS {
        anyhow::bail!(
            "--random-worlds {}, --corridor-worlds {}, --clutter-worlds {}: at most \
             {MAX_GENERATED_WORLDS} generated worlds in all (each is held in memory); split \
             the batch",
            args.random_worlds,
            args.corridor_worlds,
            args.clutter_worlds
        );
    }
    let worlds = world_names(args).len() as u64 + generated;
    let seeds_n = seeds.end - seeds.start;
    let per_seed = u64::from(args.scenarios != "pairs") * seeds_n;
    let pairs = if args.scenarios == "paper" {
        0
    } else {
        args.random_pairs.map_or(seeds_n, |n| n as u64)
    };
    let runs = per_seed
        .checked_add(pairs)
        .and_then(|r| r.checked_mul(worlds))
        .and_then(|r| r.checked_mul(methods as u64))
        .unwrap_or(u64::MAX);
    if runs > MAX_RUNS {
        let asked = match args.random_pairs.filter(|_| args.scenarios != "paper") {
            Some(n) => format!("--seeds {} and --random-pairs {n}", args.seeds),
            None => format!("--seeds {}", args.seeds),
        };
        let n = |k: u64, what: &str| format!("{k} {what}{}", if k == 1 { "" } else { "s" });
        anyhow::bail!(
            "{asked}: with {} and {} that is more than {MAX_RUNS} runs, the most one batch \
             holds; split it",
            n(worlds, "world"),
            n(methods as u64, "method")
        );
    }
    Ok(())
}

/// The worlds named by `--worlds`; the paper's when none is named or generated.
fn world_names(args: &BatchArgs) -> Vec<String> {
    if args.worlds.is_empty()
        && args.random_worlds == 0
        && args.corridor_worlds == 0
        && args.clutter_worlds == 0
    {
        vec!["paper".to_string()]
    } else {
        args.worlds.clone()
    }
}

/// The worlds named by `--worlds` (default: the paper's), then the generated ones.
fn worlds(args: &BatchArgs, configs: &[Params]) -> anyhow::Result<Vec<WorldEntry>> {
    let mut worlds: Vec<WorldEntry> = Vec::new();
    for w in &world_names(args) {
        if w == "paper" {
            worlds.push(WorldEntry {
                setup: SimSetup::load(None)?,
                kind: WorldKind::Paper,
                index: 0,
                scenario: Some((sim_laser::paper_start(), sim_laser::paper_target())),
            });
        } else {
            let p = Path::new(w);
            let setup = SimSetup::load(Some(p))
                .with_context(|| format!("cannot load world {}", p.display()))?;
            // A goalseek world file's own start and target, when it has them and they run.
            let has_own = args.scenarios != "pairs"
                && p.extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
            let scenario = if has_own {
                let (start, goal) = sim_laser::file_scenario(Some(p))
                    .with_context(|| format!("reading the scenario of {}", p.display()))?;
                let mut check = setup.clone();
                check.start = start;
                check.robot_radius_m = configs[0].robot.radius_m;
                check
                    .check_scenario(goal)
                    .with_context(|| format!("the scenario of {}", p.display()))?;
                Some((start, goal))
            } else {
                None
            };
            worlds.push(WorldEntry {
                setup,
                kind: WorldKind::File,
                index: 0,
                scenario,
            });
        }
    }
    for (kind, count) in [
        (WorldKind::Random, args.random_worlds),
        (WorldKind::Corridor, args.corridor_worlds),
        (WorldKind::Clutter, args.clutter_worlds),
    ] {
        for k in 0..count as u64 {
            let (world, start, target) =
                generated_world(kind, k).with_context(|| format!("generating {kind} world {k}"))?;
            worlds.push(WorldEntry {
                setup: SimSetup::new(Arc::new(world), format!("{kind}-{k}")),
                kind,
                index: k,
                scenario: Some((start, target)),
            });
        }
    }
    Ok(worlds)
}

/// Appends the jobs of world `w`: its own scenario per seed, then its random pairs.
fn world_jobs(w: &WorldEntry, plan: &Plan, jobs: &mut Vec<Job>) {
    let prefix = match w.kind {
        WorldKind::File => w.setup.world_name.clone(),
        k => k.to_string(),
    };
    let spec = |start: Pose2, goal: WorldPoint, seed: u64, cfg: &Params| {
        let setup = SimSetup {
            start,
            seed,
            ..w.setup.clone()
        };
        SimSpec::new(setup, goal, cfg.clone())
    };
    if let (true, Some((start, goal))) = (plan.own_scenario, w.scenario) {
        for seed in plan.seeds.clone() {
            for cfg in &plan.configs {
                jobs.push(Job {
                    group: format!("{prefix}-scenario"),
                    kind: w.kind,
                    pair: None,
                    spec: spec(start, goal, seed, cfg),
                });
            }
        }
    }
    if !plan.pairs || plan.n_pairs == 0 {
        return;
    }
    let sampler = PairSampler::new(&w.setup.world, w.kind, w.index, plan.room_m);
    let mut missing = 0;
    for i in 0..plan.n_pairs {
        let seed = plan.seeds.start + i as u64;
        let Some((start, goal)) = sampler.pair(seed, plan.min_distance_m) else {
            missing += 1;
            continue;
        };
        for cfg in &plan.configs {
            jobs.push(Job {
                group: format!("{prefix}-pairs"),
                kind: w.kind,
                pair: Some(i),
                spec: spec(start, goal, seed, cfg),
            });
        }
    }
    if missing > 0 {
        // An error, so that `-q` still shows a world that lost its runs.
        tracing::error!(
            world = %w.setup.world_name,
            "{missing} of {} pairs skipped: no start and target {} m apart in one free region; lower --min-distance",
            plan.n_pairs,
            plan.min_distance_m
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        args: BatchArgs,
    }

    fn checked(cli: &[&str]) -> anyhow::Result<()> {
        let a = Cli::try_parse_from(std::iter::once("batch").chain(cli.iter().copied()))
            .unwrap()
            .args;
        check_size(&a, &parse_seeds(&a.seeds)?, a.method.len())
    }

    #[test]
    fn the_run_limit_counts_worlds_scenarios_pairs_and_methods() {
        // The paper's world, its scenario and one pair per seed: 2 runs a seed and method.
        assert!(checked(&["--seeds", "0..25000", "--method", "goalseek,paper"]).is_ok());
        let e = checked(&["--seeds", "0..25001", "--method", "goalseek,paper"]).unwrap_err();
        assert!(e.to_string().contains("1 world and 2 methods"), "{e}");
        // 1000 generated worlds stand without the paper's: 1000 x 100 scenario runs.
        assert!(
            checked(&[
                "--clutter-worlds",
                "1000",
                "--seeds",
                "0..100",
                "--scenarios",
                "paper"
            ])
            .is_ok()
        );
        let e = checked(&[
            "--clutter-worlds",
            "1000",
            "--seeds",
            "0..101",
            "--scenarios",
            "paper",
        ])
        .unwrap_err();
        assert!(e.to_string().contains("1000 worlds and 1 method"), "{e}");
        // The pairs asked for, not the seeds, make this one too large, and are named.
        assert!(checked(&["--scenarios", "pairs", "--random-pairs", "100000"]).is_ok());
        let e = checked(&["--scenarios", "pairs", "--random-pairs", "100001"]).unwrap_err();
        assert!(e.to_string().contains("--random-pairs 100001"), "{e}");
        // Generated worlds are capped in all.
        let e = checked(&[
            "--random-worlds",
            "500",
            "--clutter-worlds",
            "501",
            "--seeds",
            "0..1",
        ])
        .unwrap_err();
        assert!(
            e.to_string().contains("1000 generated worlds in all"),
            "{e}"
        );
    }
}
