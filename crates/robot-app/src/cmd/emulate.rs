//! `robot-app emulate`: serves an emulated SCIP 2.0 Hokuyo on a pseudo-terminal or, as an
//! Ethernet model does, over TCP.

use std::io::{Read, Write};
use std::net::SocketAddr;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use scan_types::LaserSource;
use urg_driver::{FixedSource, Model, Profile, PtyServer, TcpServer, serve_pty, serve_tcp};

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
    /// Serve over TCP at ADDR:PORT (or a bare PORT on 127.0.0.1) instead of a pseudo-terminal,
    /// as an Ethernet Hokuyo does; without a value 127.0.0.1:10940. One client at a time.
    #[arg(
        long,
        value_name = "ADDR:PORT",
        num_args = 0..=1,
        default_missing_value = "127.0.0.1:10940",
        value_parser = parse_tcp_addr
    )]
    pub tcp: Option<SocketAddr>,
}

/// Reads `--tcp`: `ADDR:PORT`, `HOST:PORT` (its first address) or a bare `PORT` on 127.0.0.1.
fn parse_tcp_addr(s: &str) -> Result<SocketAddr, String> {
    use std::net::{Ipv4Addr, ToSocketAddrs};
    if let Ok(a) = s.parse::<SocketAddr>() {
        return Ok(a);
    }
    if let Ok(port) = s.parse::<u16>() {
        return Ok(SocketAddr::from((Ipv4Addr::LOCALHOST, port)));
    }
    s.to_socket_addrs()
        .map_err(|e| format!("{s:?} is not ADDR:PORT or PORT ({e})"))?
        .next()
        .ok_or_else(|| format!("{s:?} resolves to no address"))
}

/// A running emulator: on a pseudo-terminal or on a TCP address.
pub enum Served {
    /// On a pseudo-terminal (its stable path).
    Pty(PtyServer),
    /// On a TCP address.
    Tcp(TcpServer),
}

impl Served {
    /// Where a client finds it: the device path, or `tcp:ADDR:PORT` as `--port` takes it.
    pub fn location(&self) -> String {
        match self {
            Served::Pty(s) => s.path().to_string(),
            Served::Tcp(s) => format!("{}{}", urg_driver::TCP_PREFIX, s.local_addr()),
        }
    }

    /// Stops serving.
    pub fn stop(self) {
        match self {
            Served::Pty(s) => s.stop(),
            Served::Tcp(s) => s.stop(),
        }
    }
}

/// Serves `source` as `profile` on a pseudo-terminal, or over TCP at `tcp`.
fn serve<S: LaserSource + Send + 'static>(
    profile: Profile,
    source: S,
    tcp: Option<SocketAddr>,
) -> anyhow::Result<Served> {
    match tcp {
        Some(addr) => serve_tcp(addr, profile, source)
            .map(Served::Tcp)
            .with_context(|| format!("listening on {addr}")),
        None => serve_pty(profile, source)
            .map(Served::Pty)
            .context("opening a pseudo-terminal"),
    }
}

/// Starts the emulator described by `args` (the caller keeps it alive).
pub fn start(args: &EmulateArgs) -> anyhow::Result<Served> {
    let mut profile = Profile::of(args.model);
    profile.scip1_at_power_up = args.scip1;
    if let Some(log) = &args.source {
        let source = scan_log::LoopingLog::open_topic(log, None, args.topic.as_deref())
            .with_context(|| format!("opening the log {}", log.display()))?;
        serve(profile, source, args.tcp)
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
        serve(profile, source, args.tcp)
    } else {
        let source = FixedSource::room(profile.params.geometry());
        serve(profile, source, args.tcp)
    }
}

/// What the emulator described by `args` serves, for its announcement.
fn served(args: &EmulateArgs) -> String {
    match &args.source {
        Some(log) => format!("ranges of the log {}", log.display()),
        None if args.sim => "simulated ranges".into(),
        None => "fixed scan".into(),
    }
}

/// Runs `robot-app emulate`: prints the device path (or `tcp:ADDR:PORT`) and serves until Ctrl-C or end of stdin.
pub fn run(args: EmulateArgs) -> anyhow::Result<()> {
    let server = start(&args)?;
    {
        let mut out = std::io::stdout().lock();
        writeln!(out, "{}", server.location())?;
        out.flush()?;
    }
    tracing::info!(
        "emulated {} on {} ({}); stop with Ctrl-C{}",
        args.model.name(),
        server.location(),
        served(&args),
        if args.no_stdin {
            ""
        } else {
            " or end of input"
        }
    );
    // Standard input is read on a thread of its own, so that Ctrl-C is heard while it waits.
    let (ended, input_end) = std::sync::mpsc::channel();
    if !args.no_stdin {
        std::thread::spawn(move || {
            let mut sink = [0u8; 256];
            let mut stdin = std::io::stdin().lock();
            while stdin.read(&mut sink).map(|n| n > 0).unwrap_or(false) {}
            let _ = ended.send(());
        });
    }
    let interrupted = loop {
        if crate::interrupt::requested() {
            break true;
        }
        if input_end
            .recv_timeout(std::time::Duration::from_millis(50))
            .is_ok()
        {
            tracing::info!("end of input: stopping the emulator");
            break false;
        }
    };
    server.stop();
    if interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    Ok(())
}
