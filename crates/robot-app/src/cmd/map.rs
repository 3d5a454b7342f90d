//! `robot-app map`: an occupancy grid from a log that carries poses (e.g. the CARMEN
//! corrected logs), written as `map.pgm` + `map.yaml` (map_server) and `map.png`.

use std::io::Write;
use std::path::PathBuf;

use anyhow::Context;
use clap::Args;
use localiser::{CellState, OccupancyGrid};
use scan_types::{LaserSource, Pose2, RayStatus, Scan, ScanGeometry};

/// Arguments of `robot-app map`.
#[derive(Debug, Args)]
pub struct MapArgs {
    /// The log (with poses): CARMEN .log/.log.gz or a goalseek .mcap recording.
    #[arg(long)]
    pub log: PathBuf,
    /// Cell side, metres.
    #[arg(long, default_value_t = 0.05)]
    pub resolution: f64,
    /// Output directory (created if missing).
    #[arg(long, default_value = ".")]
    pub out: PathBuf,
    /// Rays are used up to this range: farther hits and no-return rays only clear cells up
    /// to it, metres.
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

/// What `robot-app map` measured.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapStats {
    /// Scans in the log.
    pub scans: usize,
    /// Scans integrated (those with a pose).
    pub mapped: usize,
    /// Hit endpoints checked.
    pub endpoints: usize,
    /// Endpoints within one cell (8-neighbourhood) of an occupied cell of the final map.
    pub near_occupied: usize,
}

impl MapStats {
    /// Share of endpoints within one cell of an occupied cell.
    pub fn endpoint_fit(&self) -> f64 {
        self.near_occupied as f64 / self.endpoints.max(1) as f64
    }
}

/// The scan limited to `max_range_m` (farther hits become max-range misses) and its
/// geometry; without `clear_no_return`, max-range misses are left out (marked invalid).
fn clip(
    geometry: &ScanGeometry,
    scan: &Scan,
    max_range_m: f64,
    clear_no_return: bool,
) -> (ScanGeometry, Scan) {
    let mut g = *geometry;
    g.max_range_m = max_range_m.min(g.max_range_m);
    let mut s = scan.clone();
    for (r, st) in s.ranges_m.iter_mut().zip(s.status.iter_mut()) {
        if *st == RayStatus::Hit && *r >= g.max_range_m {
            *st = RayStatus::MaxRange;
        }
        if *st == RayStatus::MaxRange {
            if clear_no_return {
                *r = g.max_range_m;
            } else {
                *r = f64::NAN;
                *st = RayStatus::Error(0);
            }
        }
    }
    (g, s)
}

/// Builds the grid from `(pose, scan)` pairs and measures how well the endpoints fit it.
pub fn build_map(
    geometry: &ScanGeometry,
    scans: &[(Pose2, Scan)],
    resolution_m: f64,
    max_range_m: f64,
    clear_no_return: bool,
) -> (OccupancyGrid, MapStats) {
    let mut grid = OccupancyGrid::new(resolution_m);
    let clipped: Vec<(ScanGeometry, Scan)> = scans
        .iter()
        .map(|(_, s)| clip(geometry, s, max_range_m, clear_no_return))
        .collect();
    for ((pose, _), (g, s)) in scans.iter().zip(&clipped) {
        grid.integrate(pose, g, s);
    }
    let (mut endpoints, mut near) = (0usize, 0usize);
    for ((pose, _), (g, s)) in scans.iter().zip(&clipped) {
        for (_, p) in s.world_hits(g, pose) {
            endpoints += 1;
            if let Some((c, r)) = grid.cell_of(p) {
                let hit = (-1i64..=1).any(|dr| {
                    (-1i64..=1).any(|dc| {
                        let (cc, rr) = (c as i64 + dc, r as i64 + dr);
                        cc >= 0
                            && rr >= 0
                            && (cc as usize) < grid.width()
                            && (rr as usize) < grid.height()
                            && grid.cell_state(cc as usize, rr as usize) == CellState::Occupied
                    })
                });
                near += usize::from(hit);
            }
        }
    }
    let stats = MapStats {
        scans: scans.len(),
        mapped: scans.len(),
        endpoints,
        near_occupied: near,
    };
    (grid, stats)
}

/// Runs `robot-app map`.
pub fn run(args: MapArgs) -> anyhow::Result<()> {
    if !(args.resolution.is_finite() && args.resolution > 0.0) {
        anyhow::bail!(
            "--resolution {}: must be a positive number of metres",
            args.resolution
        );
    }
    if !(args.max_range.is_finite() && args.max_range > 0.0) {
        anyhow::bail!(
            "--max-range {}: must be a positive number of metres",
            args.max_range
        );
    }
    let mut source = crate::record::open_log(&args.log, None)?;
    let mut geometry = *source.geometry();
    if let Some(deg) = args.spread_deg {
        geometry = ScanGeometry::centred(
            geometry.ray_count,
            deg.to_radians(),
            geometry.min_range_m,
            geometry.max_range_m,
        )
        .with_context(|| format!("--spread-deg {deg}"))?;
    }
    let use_true = args.pose == "true";
    let mut scans = Vec::new();
    let mut total = 0usize;
    loop {
        let rec = match source.next_record() {
            Ok(r) => r,
            Err(e) if e.is_end_of_log() => break,
            Err(e) => return Err(e).context("reading the log"),
        };
        total += 1;
        let pose = if use_true {
            rec.true_pose
        } else {
            rec.pose.or(rec.true_pose)
        };
        if let Some(p) = pose {
            scans.push((p, rec.scan.clone()));
        }
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
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    grid.write_map_server(&args.out, "map")?;
    grid.to_png(&args.out.join("map.png"))?;
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// A robot in a 4 m x 4 m square room, seen from a few poses with exact ranges: every
    /// endpoint lies on a wall, so every one is within a cell of an occupied cell.
    #[test]
    fn exact_scans_of_a_room_fit_their_map() {
        let g = ScanGeometry::centred(360, 2.0 * PI * 359.0 / 360.0, 0.0, 10.0).unwrap();
        let range = |x: f64, y: f64, a: f64| {
            // Distance from (x, y) along a to the walls x = +-2, y = +-2.
            let (c, s) = (a.cos(), a.sin());
            let tx = if c > 0.0 {
                (2.0 - x) / c
            } else if c < 0.0 {
                (-2.0 - x) / c
            } else {
                f64::INFINITY
            };
            let ty = if s > 0.0 {
                (2.0 - y) / s
            } else if s < 0.0 {
                (-2.0 - y) / s
            } else {
                f64::INFINITY
            };
            tx.min(ty)
        };
        let poses = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.5, -0.3, 1.0),
            Pose2::new(-1.0, 1.0, -2.0),
        ];
        let scans: Vec<(Pose2, Scan)> = poses
            .iter()
            .map(|p| {
                let r: Vec<f64> = (0..g.ray_count)
                    .map(|i| range(p.x_m, p.y_m, p.theta_rad + g.bearing_rad(i)))
                    .collect();
                (*p, Scan::from_ranges(&g, &r, 0.0))
            })
            .collect();
        let (grid, stats) = build_map(&g, &scans, 0.05, 20.0, false);
        assert_eq!(stats.endpoints, 3 * 360);
        assert_eq!(stats.near_occupied, stats.endpoints);
        // The wall is occupied, the middle of the room free.
        // (Endpoints on x = 2 land on either side of the cell border at 2.0.)
        let w = |x| grid.is_occupied(scan_types::WorldPoint::new(x, 0.3));
        assert!(w(1.99) || w(2.01));
        assert!(grid.is_free(scan_types::WorldPoint::new(0.2, 0.2)));
        // Clipping at 1 m: no hit is closer than 1 m here, so none is checked.
        let (_, clipped) = build_map(&g, &scans[..1], 0.05, 1.0, true);
        assert_eq!(clipped.endpoints, 0);
    }
}
