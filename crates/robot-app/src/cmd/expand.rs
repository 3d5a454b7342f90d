//! `robot-app expand`: expands the obstacles of a scan CSV (the form `robot-app scan` writes)
//! by the robot radius and prints each ray's clearance and whether it is blocked.

use std::io::{BufReader, Write};
use std::path::PathBuf;

use anyhow::{Context, bail};
use clap::Args;
use expansion::{Expander, is_blocked};
use scan_log::read_scan_csv;
use scan_types::{RayStatus, ScanGeometry};

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
    let blocked = write_table(
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

/// Writes the per-ray table; returns how many rays are blocked.
fn write_table<W: Write>(
    mut w: W,
    geometry: &ScanGeometry,
    ranges_m: &[f64],
    status: &[RayStatus],
    clearance_m: &[f64],
    travel_m: f64,
) -> std::io::Result<usize> {
    writeln!(w, "index,bearing_rad,range_m,clearance_m,blocked")?;
    let mut blocked_count = 0;
    for (i, &c) in clearance_m.iter().enumerate() {
        let range = match status.get(i) {
            Some(RayStatus::Error(_)) | None => f64::NAN,
            _ => ranges_m[i],
        };
        let blocked = is_blocked(c, travel_m);
        blocked_count += usize::from(blocked);
        writeln!(
            w,
            "{i},{:.9},{:.6},{:.6},{}",
            geometry.bearing_rad(i),
            range,
            c,
            u8::from(blocked)
        )?;
    }
    Ok(blocked_count)
}

#[cfg(test)]
mod tests {
    use super::*;
    use scan_types::Scan;

    #[test]
    fn table_of_a_single_hit() {
        // Rays at -90, 0, +90 deg; a hit 2 m ahead, r = 0.5: the centre ray clears 1.5 m.
        let g = ScanGeometry::centred(3, std::f64::consts::PI, 0.0, 4.0).unwrap();
        let s = Scan::from_ranges(&g, &[4.0, 2.0, f64::NAN], 0.0);
        let mut c = vec![0.0; 3];
        Expander::new(&g).clearances(&s, 0.5, &mut c);
        let mut buf = Vec::new();
        let n = write_table(&mut buf, &g, &s.ranges_m, &s.status, &c, 1.6).unwrap();
        let text = String::from_utf8(buf).unwrap();
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "index,bearing_rad,range_m,clearance_m,blocked");
        assert_eq!(lines[1], "0,-1.570796327,4.000000,4.000000,0");
        assert_eq!(lines[2], "1,0.000000000,2.000000,1.500000,1");
        // The invalid ray has no free length: blocked.
        assert_eq!(lines[3], "2,1.570796327,NaN,0.000000,1");
        assert_eq!(n, 2);
    }
}
