//! `robot-app info --port PATH`: a Hokuyo's version (VV), parameters (PP) and state (II).

use std::io::Write;

use anyhow::Context;
use clap::Args;
use urg_driver::{AcquisitionMode, Urg, UrgConfig};

/// Arguments of `robot-app info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Serial device of the sensor (/dev/ttyACM0, /dev/hokuyo, or the path `robot-app emulate` prints), or tcp:HOST:PORT for an Ethernet model (tcp:192.168.0.10:10940).
    #[arg(long)]
    pub port: String,
}

/// Runs `robot-app info`, printing to stdout.
pub fn run(args: InfoArgs) -> anyhow::Result<()> {
    let stdout = std::io::stdout();
    run_to(&args, &mut stdout.lock())
}

/// Connects to the sensor at `args.port` and writes its VV, PP and II as readable text.
pub fn run_to<W: Write>(args: &InfoArgs, out: &mut W) -> anyhow::Result<()> {
    let config = UrgConfig {
        // No BM and no clock synchronisation: only read the sensor.
        mode: AcquisitionMode::Streaming,
        time_sync_rounds: 0,
        ..UrgConfig::default()
    };
    let spec = urg_driver::PortSpec::parse(&args.port)?;
    let mut urg = Urg::open_spec(&spec, config)
        .with_context(|| format!("connecting to the sensor at {}", args.port))?;
    let version = urg.version().context("reading the version (VV)")?;
    let state = urg.state().context("reading the state (II)")?;
    writeln!(out, "Sensor at {}", args.port)?;
    write!(
        out,
        "\nVersion (VV)\n{version}\nParameters (PP)\n{}\nState (II)\n{state}",
        urg.params()
    )?;
    Ok(())
}
