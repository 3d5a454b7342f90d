//! `robot-app map`: an occupancy grid from a log that carries poses (e.g. the CARMEN
//! corrected logs), written as `map.pgm` + `map.yaml` (map_server) and `map.png`; the grid and
//! its consistency figure are [`localiser::build_map`]'s.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use localiser::build_map;
use scan_types::{LaserSource, ScanGeometry};

/// Arguments of `robot-app map`.
#[derive(Debug, Args)]
pub struct MapArgs {
    /// The log (with poses): CARMEN .log/.log.gz or a goalseek .mcap recording.
    #[arg(long)]
    pub log: PathBuf,
    /// The laser topic to read when a bag or MCAP file holds several (e.g. /scan).
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// Sensor preset whose geometry replaces the log's: paper, urg-04lx, utm-30lx or ust-10lx.
    #[arg(long, value_name = "PRESET")]
    pub sensor: Option<String>,
    /// Cell side, metres.
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f64,
    /// Output directory (created if missing).
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// Rays are used up to this range, metres: farther hits and no-return rays are left out
    /// (see --clear-no-return).
    #[arg(long, default_value_t = 20.0)]
    pub max_range: f64,
    /// Spread the log's rays evenly over this many degrees instead of the log's geometry
    /// (e.g. 180 for the other reading of CARMEN's FLASER beams).
    #[arg(long)]
    pub spread_deg: Option<f64>,
    /// Let no-return rays (and hits beyond --max-range) clear the cells along them up to
    /// --max-range; by default they are left out, as a "no return" says little about where.
    #[arg(long)]
    pub clear_no_return: bool,
    /// Which pose of a goalseek recording to map from: estimated or true.
    #[arg(long, default_value = "estimated", value_parser = ["estimated", "true"])]
    pub pose: String,
}

/// Runs `robot-app map`.
pub fn run(args: MapArgs) -> anyhow::Result<()> {
    super::check_map_options(args.resolution, args.max_range)?;
    let mut source =
        crate::record::open_log_topic(&args.log, args.sensor.as_deref(), args.topic.as_deref())?;
    let mut geometry = *source.geometry();
    if let Some(deg) = args.spread_deg {
        anyhow::ensure!(
            deg.is_finite() && deg > 0.0 && deg <= 360.0,
            "--spread-deg {deg}: must be above 0 and at most 360"
        );
        geometry = ScanGeometry::centred(
            geometry.ray_count,
            deg.to_radians(),
            geometry.min_range_m,
            geometry.max_range_m,
        )
        .with_context(|| format!("--spread-deg {deg}"))?;
    }
    let (scans, total) = source
        .posed_scans(args.pose == "true")
        .context("reading the log")?;
    crate::interrupt::check()?;
    if scans.is_empty() && args.pose == "true" {
        anyhow::bail!(
            "{}: none of its {total} scans has a true pose (only a recording of a simulated run has them; --pose estimated maps the recorded estimate)",
            args.log.display()
        );
    }
    if scans.is_empty() {
        anyhow::bail!(
            "{}: none of its {total} scans has a pose; 'robot-app map' needs a log with poses (e.g. a CARMEN corrected log)",
            args.log.display()
        );
    }
    let (grid, mut stats) = build_map(
        &geometry,
        &scans,
        args.resolution,
        args.max_range,
        args.clear_no_return,
    );
    stats.scans = total;
    // A map of part of the log is not written: a stop request ends here.
    crate::interrupt::check()?;
    anyhow::ensure!(
        grid.width() > 0,
        "{}: no hit lies within --max-range {} m: nothing to map",
        args.log.display(),
        args.max_range
    );
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    crate::outputs::write_grid(&args.out, &grid)?;
    let mut out = std::io::stdout().lock();
    writeln!(
        out,
        "{}: {} scans, {} mapped; grid {} x {} cells of {} m; {} of {} hit endpoints ({:.1} %) within one cell of an occupied cell; wrote map.pgm, map.yaml, map.png in {}",
        args.log.display(),
        stats.scans,
        stats.mapped,
        grid.width(),
        grid.height(),
        args.resolution,
        stats.near_occupied,
        stats.endpoints,
        100.0 * stats.endpoint_fit(),
        args.out.display()
    )?;
    if source.skipped() > 0 {
        tracing::warn!("{} malformed records skipped", source.skipped());
    }
    Ok(())
}
