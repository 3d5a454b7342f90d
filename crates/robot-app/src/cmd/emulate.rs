//! `robot-app emulate`: serves an emulated SCIP 2.0 Hokuyo on a pseudo-terminal.

use std::io::{Read, Write};
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use urg_driver::{FixedSource, Model, Profile, PtyServer, serve_pty};

/// Arguments of `robot-app emulate`.
#[derive(Debug, Args)]
pub struct EmulateArgs {
    /// Sensor model: urg-04lx, utm-30lx or ust-10lx.
    #[arg(long, default_value = "urg-04lx", value_parser = str::parse::<Model>)]
    pub model: Model,
    /// Start in SCIP 1.1, as a factory URG-04LX does (clients must send SCIP2.0).
    #[arg(long)]
    pub scip1: bool,
    /// Take ranges from the simulator (a robot standing at --pose) instead of the fixed scan.
    #[arg(long)]
    pub sim: bool,
    /// World file for --sim (.toml, .yaml, .png); default: the paper's world.
    #[arg(long, requires = "sim")]
    pub world: Option<PathBuf>,
    /// Robot pose for --sim: X,Y,THETA_DEG (default: the paper's start).
    #[arg(long, requires = "sim", allow_hyphen_values = true)]
    pub pose: Option<String>,
    /// Seed of the simulated laser noise.
    #[arg(long, default_value_t = 0, requires = "sim")]
    pub seed: u64,
    /// Simulated laser noise: on (or default) or off.
    #[arg(long, value_enum, default_value = "on", requires = "sim")]
    pub noise: super::Noise,
    /// Do not stop at end of standard input; serve until killed (for background use).
    #[arg(long)]
    pub no_stdin: bool,
    /// Take ranges from a recorded log (CARMEN, BreezySLAM, MCAP, rosbag2), looping at its end.
    #[arg(long, conflicts_with = "sim")]
    pub source: Option<PathBuf>,
    /// With --source: the laser topic to read when a bag or MCAP file holds several.
    #[arg(long, value_name = "NAME", requires = "source")]
    pub topic: Option<String>,
}

/// Starts the emulator described by `args` (the caller keeps it alive).
pub fn start(args: &EmulateArgs) -> anyhow::Result<PtyServer> {
    let mut profile = Profile::of(args.model);
    profile.scip1_at_power_up = args.scip1;
    let server = if let Some(log) = &args.source {
        let source = scan_log::LoopingLog::open_topic(log, None, args.topic.as_deref())
            .with_context(|| format!("opening the log {}", log.display()))?;
        serve_pty(profile, source)
    } else if args.sim {
        let pose = match &args.pose {
            Some(p) => crate::simsetup::parse_pose(p)?,
            None => crate::simsetup::paper_start(),
        };
        let source = crate::simsetup::sim_scan_source(
            args.world.as_deref(),
            pose,
            args.model.name(),
            args.seed,
            args.noise.is_on(),
        )?;
        serve_pty(profile, source)
    } else {
        let source = FixedSource::room(profile.params.geometry());
        serve_pty(profile, source)
    };
    server.context("opening a pseudo-terminal")
}

/// What the emulator described by `args` serves, for its announcement.
fn served(args: &EmulateArgs) -> String {
    match &args.source {
        Some(log) => format!("ranges of the log {}", log.display()),
        None if args.sim => "simulated ranges".into(),
        None => "fixed scan".into(),
    }
}

/// Runs `robot-app emulate`: prints the device path and serves until Ctrl-C or end of stdin.
pub fn run(args: EmulateArgs) -> anyhow::Result<()> {
    let server = start(&args)?;
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{}", server.path())?;
        out.flush()?;
    }
    tracing::info!(
        "emulated {} on {} ({}); stop with Ctrl-C{}",
        args.model.name(),
        server.path(),
        served(&args),
        if args.no_stdin {
            ""
        } else {
            " or end of input"
        }
    );
    if args.no_stdin {
        loop {
            std::thread::park();
        }
    }
    let mut sink = [0u8; 256];
    let mut stdin = std::io::stdin().lock();
    while stdin.read(&mut sink).map(|n| n > 0).unwrap_or(false) {}
    tracing::info!("end of input: stopping the emulator");
    server.stop();
    Ok(())
}
