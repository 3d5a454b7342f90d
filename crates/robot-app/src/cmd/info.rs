//! `robot-app info --port PATH`: a Hokuyo's version (VV), parameters (PP) and state (II).

use std::io::Write;

use anyhow::Context;
use clap::Args;
use urg_driver::{AcquisitionMode, Urg, UrgConfig};

/// Arguments of `robot-app info`.
#[derive(Debug, Args)]
pub struct InfoArgs {
    /// Serial device of the sensor (/dev/ttyACM0, /dev/hokuyo, or the path `robot-app emulate` prints).
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
    let mut urg = Urg::open(&args.port, config)
        .with_context(|| format!("connecting to the sensor at {}", args.port))?;
    let v = urg.version().context("reading the version (VV)")?;
    let st = urg.state().context("reading the state (II)")?;
    let p = urg.params().clone();
    let g = p.geometry();
    writeln!(out, "Sensor at {}", args.port)?;
    writeln!(out, "\nVersion (VV)")?;
    for (k, val) in &v.lines {
        writeln!(out, "  {k}  {val}")?;
    }
    writeln!(out, "\nParameters (PP)")?;
    writeln!(out, "  MODL  {}", p.model)?;
    writeln!(
        out,
        "  DMIN  {} mm (smaller values are error codes)",
        p.dmin_mm
    )?;
    writeln!(out, "  DMAX  {} mm", p.dmax_mm)?;
    writeln!(
        out,
        "  ARES  {} steps per turn ({:.7} deg per step)",
        p.ares,
        360.0 / f64::from(p.ares)
    )?;
    writeln!(
        out,
        "  AMIN  step {} ({:.3} deg)",
        p.amin,
        p.step_bearing_rad(f64::from(p.amin)).to_degrees()
    )?;
    writeln!(
        out,
        "  AMAX  step {} ({:.3} deg)",
        p.amax,
        p.step_bearing_rad(f64::from(p.amax)).to_degrees()
    )?;
    writeln!(out, "  AFRT  step {} (straight ahead)", p.afrt)?;
    writeln!(
        out,
        "  SCAN  {} rpm ({} ms per scan)",
        p.scan_rpm,
        p.scan_period().as_secs_f64() * 1000.0
    )?;
    writeln!(
        out,
        "  geometry: {} rays from {:.3} to {:.3} deg, ranges {} to {} m",
        g.ray_count,
        g.first_bearing_rad.to_degrees(),
        g.last_bearing_rad().to_degrees(),
        g.min_range_m,
        g.max_range_m
    )?;
    writeln!(out, "\nState (II)")?;
    for (k, val) in &st.lines {
        if k == "TIME" {
            match st.time_ms {
                Some(ms) => writeln!(out, "  {k}  {val} ({ms} ms on the sensor clock)")?,
                None => writeln!(out, "  {k}  {val}")?,
            }
        } else {
            writeln!(out, "  {k}  {val}")?;
        }
    }
    Ok(())
}
