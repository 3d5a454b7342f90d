//! `robot-app world`: generate seeded random worlds and describe world files.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::{Context, bail};
use clap::{Args, Subcommand};
use sim_laser::{GenParams, World, generate_world};

/// Arguments of `robot-app world`.
#[derive(Debug, Args)]
pub struct WorldArgs {
    #[command(subcommand)]
    command: WorldCommand,
}

#[derive(Debug, Subcommand)]
enum WorldCommand {
    /// Generate a seeded random world (rooms, doors, a corridor, clutter; or, with
    /// --clutter-only, an open area with sparse clutter) and write it.
    Generate(GenerateArgs),
    /// Load a world file and print its size, obstacles and the scenario it stores.
    Info(InfoArgs),
}

/// Arguments of `robot-app world generate`.
#[derive(Debug, Args)]
struct GenerateArgs {
    /// Seed: the same seed and parameters give the same world.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output file: .toml (native vector format), .yaml (map_server YAML + PGM beside it) or
    /// .png (Stage bitmap). Use {seed} in the name to write several seeds.
    #[arg(long)]
    out: PathBuf,
    /// Number of consecutive seeds to generate (needs {seed} in --out when > 1).
    #[arg(long, default_value_t = 1)]
    count: u64,
    /// Clutter-only: an open walled area with sparse boxes and discs, no rooms, corridor or
    /// doors (the batch's `--clutter-worlds`: 20 m x 12 m, 5 boxes, 5 discs, unless the options
    /// below say otherwise). Same as `--rooms 0` with those defaults.
    #[arg(long)]
    clutter_only: bool,
    /// World width, metres [default: 16, or 20 with --clutter-only].
    #[arg(long)]
    width: Option<f64>,
    /// World height, metres [default: 10, or 12 with --clutter-only].
    #[arg(long)]
    height: Option<f64>,
    /// Rooms on each side of the corridor; 0 gives a clutter-only world [default: 3, or 0
    /// with --clutter-only].
    #[arg(long)]
    rooms: Option<usize>,
    /// Corridor width, metres.
    #[arg(long, default_value_t = GenParams::default().corridor_width_m)]
    corridor: f64,
    /// Door width, metres.
    #[arg(long, default_value_t = GenParams::default().door_width_m)]
    door: f64,
    /// Clutter boxes [default: 8, or 5 with --clutter-only].
    #[arg(long)]
    boxes: Option<usize>,
    /// Round clutter obstacles [default: 6, or 5 with --clutter-only].
    #[arg(long)]
    circles: Option<usize>,
    /// Pixel size of .yaml/.png outputs, metres.
    #[arg(long, default_value_t = 0.02)]
    resolution: f64,
}

/// Arguments of `robot-app world info`.
#[derive(Debug, Args)]
struct InfoArgs {
    /// World file (.toml, .yaml, .png); omit for the paper's world.
    path: Option<PathBuf>,
}

/// Runs `robot-app world`.
pub fn run(args: WorldArgs) -> anyhow::Result<()> {
    match args.command {
        WorldCommand::Generate(a) => generate(a),
        WorldCommand::Info(a) => info(a),
    }
}

fn generate(a: GenerateArgs) -> anyhow::Result<()> {
    let base = if a.clutter_only || a.rooms == Some(0) {
        sim_laser::clutter_world_params()
    } else {
        GenParams::default()
    };
    let params = GenParams {
        width_m: a.width.unwrap_or(base.width_m),
        height_m: a.height.unwrap_or(base.height_m),
        rooms_per_side: a.rooms.unwrap_or(base.rooms_per_side),
        corridor_width_m: a.corridor,
        door_width_m: a.door,
        boxes: a.boxes.unwrap_or(base.boxes),
        circles: a.circles.unwrap_or(base.circles),
        ..base
    };
    if a.clutter_only && params.rooms_per_side != 0 {
        bail!(
            "--clutter-only makes a world without rooms: drop --rooms {}",
            params.rooms_per_side
        );
    }
    let template = a.out.to_string_lossy().into_owned();
    if a.count > 1 && !template.contains("{seed}") {
        bail!("--count {} needs {{seed}} in --out ({template})", a.count);
    }
    for seed in a.seed..a.seed.saturating_add(a.count.max(1)) {
        // The worlds written so far are whole (each file is written atomically).
        crate::interrupt::check()?;
        let path = PathBuf::from(template.replace("{seed}", &seed.to_string()));
        let desc = generate_world(seed, &params)?;
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("--out: cannot create {}", dir.display()))?;
        }
        let ext = path
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase())
            .unwrap_or_default();
        match ext.as_str() {
            "toml" => desc.write_toml(&path)?,
            "yaml" | "yml" => desc
                .write_map_server(&path, a.resolution)
                .map_err(|e| resolution_named(e, a.resolution))?,
            "png" => desc
                .write_png(&path, a.resolution)
                .map_err(|e| resolution_named(e, a.resolution))?,
            _ => bail!("{}: --out must end in .toml, .yaml or .png", path.display()),
        }
        let s = desc.start.unwrap_or_default();
        let t = desc.target.unwrap_or_default();
        crate::say!(
            "{}: seed {seed}, {} obstacles, {} m x {} m, start {:.2},{:.2},{:.1} target {:.2},{:.2}{}",
            path.display(),
            desc.obstacles.len(),
            params.width_m,
            params.height_m,
            s[0],
            s[1],
            s[2].to_degrees(),
            t[0],
            t[1],
            if ext == "png" {
                format!(" (load with size {},{})", params.width_m, params.height_m)
            } else {
                String::new()
            }
        );
    }
    Ok(())
}

/// A raster error that comes from `--resolution` names the option.
fn resolution_named(e: sim_laser::SimError, resolution: f64) -> anyhow::Error {
    let from_resolution = matches!(
        &e,
        sim_laser::SimError::InvalidConfig {
            field: "resolution_m",
            ..
        }
    );
    let e = anyhow::Error::new(e);
    if from_resolution {
        e.context(format!("--resolution {resolution}"))
    } else {
        e
    }
}

fn info(a: InfoArgs) -> anyhow::Result<()> {
    let world = match &a.path {
        None => World::paper(),
        Some(p) => World::load(p).with_context(|| format!("loading world {}", p.display()))?,
    };
    let (lo, hi) = world.bounds();
    // The paper's world is the paper's scenario; another world without one falls back to it.
    let path = a.path.as_deref().map(Path::new);
    let (start, target) = sim_laser::stored_scenario(path)?;
    let stored = (
        path.is_none() || start.is_some(),
        path.is_none() || target.is_some(),
    );
    let start = start.unwrap_or_else(sim_laser::paper_start);
    let target = target.unwrap_or_else(sim_laser::paper_target);
    let fallback = |stored: bool| {
        if stored {
            ""
        } else {
            " (none stored: the paper's)"
        }
    };
    let mut out = std::io::stdout().lock();
    writeln!(out, "world: {}", world.name())?;
    writeln!(
        out,
        "bounds: ({:.3}, {:.3}) to ({:.3}, {:.3}) m",
        lo.x_m(),
        lo.y_m(),
        hi.x_m(),
        hi.y_m()
    )?;
    writeln!(out, "vector obstacles: {}", world.obstacle_count())?;
    writeln!(
        out,
        "start: {:.3},{:.3},{:.2}{}  target: {:.3},{:.3}{}",
        start.x_m,
        start.y_m,
        start.theta_rad.to_degrees(),
        fallback(stored.0),
        target.x_m(),
        target.y_m(),
        fallback(stored.1)
    )?;
    Ok(())
}
