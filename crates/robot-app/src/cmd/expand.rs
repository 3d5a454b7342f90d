//! `robot-app expand`: expands the obstacles of a scan CSV (the form `robot-app scan` writes)
//! by the robot radius and prints each ray's clearance and whether it is blocked.

use std::io::BufReader;
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use expansion::{Expander, write_clearance_csv};
use scan_log::read_scan_csv;

/// Arguments of `robot-app expand`.
#[derive(Debug, Args)]
pub struct ExpandArgs {
    /// Scan CSV to read (as written by `robot-app scan`); `-` reads standard input.
    #[arg(long)]
    pub scan: PathBuf,
    /// Robot radius (plus any safety margin) to grow every hit by, metres.
    #[arg(long)]
    pub radius: f64,
    /// Leg length: a ray whose clearance is below it is blocked, metres.
    #[arg(long, default_value_t = 1.0)]
    pub travel: f64,
}

/// Runs `robot-app expand`.
pub fn run(args: ExpandArgs) -> anyhow::Result<()> {
    if !(args.radius.is_finite() && args.radius >= 0.0) {
        bail!(
            "--radius {} must be a finite number >= 0 (metres)",
            args.radius
        );
    }
    if !(args.travel.is_finite() && args.travel >= 0.0) {
        bail!(
            "--travel {} must be a finite number >= 0 (metres)",
            args.travel
        );
    }
    let (geometry, scan) = if args.scan.as_os_str() == "-" {
        read_scan_csv(std::io::stdin().lock(), "<stdin>")?
    } else {
        let name = args.scan.display().to_string();
        let file =
            std::fs::File::open(&args.scan).with_context(|| format!("cannot open {name}"))?;
        read_scan_csv(BufReader::new(file), &name)?
    };
    let mut clearance = vec![0.0; geometry.ray_count];
    Expander::new(&geometry).clearances(&scan, args.radius, &mut clearance);
    let blocked = write_clearance_csv(
        std::io::stdout().lock(),
        &geometry,
        &scan.ranges_m,
        &scan.status,
        &clearance,
        args.travel,
    )
    .context("cannot write to standard output")?;
    tracing::info!(
        rays = geometry.ray_count,
        blocked,
        radius_m = args.radius,
        travel_m = args.travel,
        "expanded"
    );
    Ok(())
}
