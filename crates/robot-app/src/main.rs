//! `robot-app`: the goalseek command-line program.

use std::process::ExitCode;

use clap::{ArgAction, CommandFactory, FromArgMatches, Parser, Subcommand};
use robot_app::cmd;

/// Goal seeking, localisation and mapping with nothing but a 2D laser range finder.
#[derive(Debug, Parser)]
#[command(name = "robot-app", version, about, propagate_version = true)]
struct Cli {
    /// More logging (-v debug, -vv trace); RUST_LOG overrides.
    #[arg(short, long, action = ArgAction::Count, global = true)]
    verbose: u8,
    /// Less logging (-q errors only, -qq nothing).
    #[arg(short, long, action = ArgAction::Count, global = true)]
    quiet: u8,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Run goal seeking in the simulator (default: the paper's scenario).
    Sim(cmd::sim::SimArgs),
    /// Map an unknown world with no target: drive to the frontiers of the map until none is
    /// left (simulator), with coverage and map accuracy.
    Explore(cmd::explore::ExploreArgs),
    /// Run goal seeking on a real Hokuyo and a robot base.
    Run(cmd::run::RunArgs),
    /// Run many simulated runs in parallel and summarise them.
    Batch(cmd::batch::BatchArgs),
    /// Serve an emulated SCIP 2.0 Hokuyo on a pseudo-terminal (or over TCP with --tcp).
    Emulate(cmd::emulate::EmulateArgs),
    /// Print a Hokuyo's version, parameters and state (VV, PP, II).
    Info(cmd::info::InfoArgs),
    /// Print scans from a Hokuyo or the simulator as CSV or JSON.
    Scan(cmd::scan::ScanArgs),
    /// Expand the obstacles of a scan CSV and print each ray's clearance.
    Expand(cmd::expand::ExpandArgs),
    /// Stream a recorded log through the live-sensor code path.
    Replay(cmd::replay::ReplayArgs),
    /// Build an occupancy grid from a log that carries poses.
    Map(cmd::map::MapArgs),
    /// Estimate a trajectory and a map from a log's scans (laser-only SLAM; --motion-prior adds the log's poses).
    Slam(cmd::slam::SlamArgs),
    /// Run landmark detection and tracking over a log and report statistics.
    Landmarks(cmd::landmarks::LandmarksArgs),
    /// Generate seeded random worlds for batch evaluation.
    World(cmd::world::WorldArgs),
}

fn main() -> ExitCode {
    // A negative number is a value (`--max-range -5`), so that the option's own check names it.
    let command = Cli::command().mut_subcommands(|c| {
        c.allow_negative_numbers(true)
            .mut_subcommands(|c| c.allow_negative_numbers(true))
    });
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    robot_app::logging::init(cli.verbose, cli.quiet);
    robot_app::interrupt::install();
    let result = match cli.command {
        Command::Sim(a) => cmd::sim::run(a),
        Command::Explore(a) => cmd::explore::run(a),
        Command::Run(a) => cmd::run::run(a),
        Command::Batch(a) => cmd::batch::run(a),
        Command::Emulate(a) => cmd::emulate::run(a),
        Command::Info(a) => cmd::info::run(a),
        Command::Scan(a) => cmd::scan::run(a),
        Command::Expand(a) => cmd::expand::run(a),
        Command::Replay(a) => cmd::replay::run(a),
        Command::Map(a) => cmd::map::run(a),
        Command::Landmarks(a) => cmd::landmarks::run(a),
        Command::Slam(a) => cmd::slam::run(a),
        Command::World(a) => cmd::world::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if e.is::<robot_app::interrupt::Interrupted>() => {
            ExitCode::from(robot_app::interrupt::EXIT_CODE)
        }
        Err(e) if is_broken_pipe(&e) => ExitCode::SUCCESS,
        // A command that failed once a stop was asked for (a sensor given up while it was
        // being reconnected) ends as an interrupted one.
        Err(e) if robot_app::interrupt::requested() => {
            tracing::warn!("after the stop request: {}", one_line(&e));
            ExitCode::from(robot_app::interrupt::EXIT_CODE)
        }
        Err(e) => {
            #[allow(clippy::print_stderr)]
            {
                eprintln!("robot-app: {}", one_line(&e));
            }
            ExitCode::FAILURE
        }
    }
}

/// True when the error is a bare write to a closed stdout (`robot-app ... | head`): command-line
/// tools exit quietly then. A device's broken pipe comes wrapped in its crate's error.
fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().count() == 1
        && e.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
}

/// One line for an error: its causes joined with ': ', each said once (an I/O error wrapped
/// by a crate's error often repeats its cause's text).
fn one_line(e: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if parts.last().is_some_and(|p| p.ends_with(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}
