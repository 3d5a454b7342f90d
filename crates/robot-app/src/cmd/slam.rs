//! `robot-app slam`: a trajectory and a map from the laser alone, for any log goalseek reads.
//! The poses and odometry a log may carry are never given to the estimator unless
//! `--motion-prior` asks for them; they are used, when present, to evaluate it. The run and its report are [`slam::LogRun`]'s; this
//! command reads the log, shows progress and writes the outputs.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use anyhow::Context;
use clap::Args;
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use scan_log::{LogOptions, LogSource};
use scan_types::{LaserSource, Pose2, ScanGeometry, WorldPoint};

use slam::{FrontEndParams, LogRun, LoopParams, SlamRun};

use crate::outputs::write_atomic;
use scan_log::tum;

/// Cell side of the map `slam` writes by default, metres.
pub const MAP_RESOLUTION_M: f64 = 0.05;

/// Range up to which rays enter that map by default, metres.
pub const MAP_MAX_RANGE_M: f64 = 20.0;

/// Arguments of `robot-app slam`.
#[derive(Debug, Args)]
pub struct SlamArgs {
    /// The log: CARMEN (.log, .log.gz), BreezySLAM .dat, an MCAP file (goalseek, ROS 2,
    /// Foxglove) or a rosbag2 bag (.db3 file or bag folder).
    #[arg(long)]
    pub log: PathBuf,
    /// The laser topic to read when a bag or MCAP file holds several (e.g. /scan).
    #[arg(long, value_name = "NAME")]
    pub topic: Option<String>,
    /// Output folder (created if missing).
    #[arg(long, default_value = "goalseek-slam")]
    pub out: PathBuf,
    /// TOML file overriding front-end parameters, and loop-closure ones in a
    /// `[loop_closure]` table (see docs/slam.md).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// The front end alone: no loop closure, no pose graph (for comparison).
    #[arg(long)]
    pub no_loop_closure: bool,
    /// Centre each scan's search on the log's own pose change since the last placed scan
    /// (its odometry, else its pose: a goalseek recording's estimate): the trajectory is then
    /// no longer the laser's alone, and an evaluation against those poses is not independent.
    #[arg(long)]
    pub motion_prior: bool,
    /// Map cell side, metres.
    #[arg(long, default_value_t = MAP_RESOLUTION_M)]
    pub resolution: f64,
    /// Rays enter the map up to this range, metres: farther hits and no-return rays are left
    /// out (the estimate uses every hit within the front end's `max_range_m`).
    #[arg(long, default_value_t = MAP_MAX_RANGE_M)]
    pub max_range: f64,
    /// Live view (the front end's poses as scans are placed; the final map at the end).
    #[command(flatten)]
    pub live: crate::live::LiveOptions,
}

/// Front-end and loop-closure parameters: the defaults overridden by a TOML file (front-end
/// keys at the top level, loop-closure keys in a `[loop_closure]` table).
pub fn load_params(path: Option<&Path>) -> anyhow::Result<(FrontEndParams, LoopParams)> {
    let Some(p) = path else {
        return Ok((FrontEndParams::default(), LoopParams::default()));
    };
    let text = std::fs::read_to_string(p)
        .with_context(|| format!("cannot read config {}", p.display()))?;
    let mut table: toml::Table =
        toml::from_str(&text).with_context(|| format!("config {}", p.display()))?;
    let loops: LoopParams = match table.remove("loop_closure") {
        Some(v) => v
            .try_into()
            .with_context(|| format!("config {}: [loop_closure]", p.display()))?,
        None => LoopParams::default(),
    };
    let front: FrontEndParams = table.try_into().with_context(|| {
        format!(
            "config {} (front-end keys at the top level, loop-closure keys in a [loop_closure] table)",
            p.display()
        )
    })?;
    front
        .validate()
        .with_context(|| format!("config {}", p.display()))?;
    loops
        .validate()
        .with_context(|| format!("config {}: [loop_closure]", p.display()))?;
    Ok((front, loops))
}

/// A progress bar on stderr that shows itself once the run has taken a second.
struct Progress {
    bar: ProgressBar,
    start: Instant,
    shown: bool,
}

impl Progress {
    fn new() -> Self {
        let bar = ProgressBar::with_draw_target(None, ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{spinner} {pos} scans, {elapsed}")
                .unwrap_or_else(|_| ProgressStyle::default_spinner()),
        );
        Self {
            bar,
            start: Instant::now(),
            shown: false,
        }
    }

    fn tick(&mut self) {
        if !self.shown && self.start.elapsed() > Duration::from_secs(1) {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.shown = true;
        }
        self.bar.inc(1);
    }
}

/// Runs the front end over every scan of `path` ([`slam::LogRun`]), then loop closure unless
/// `loops` is `None`.
pub fn run_log(
    path: &Path,
    params: &FrontEndParams,
    loops: Option<&LoopParams>,
) -> anyhow::Result<SlamRun> {
    run_log_topic(path, None, params, loops)
}

/// [`run_log`] over the laser topic `topic` of `path` (`None`: the log's only one).
pub fn run_log_topic(
    path: &Path,
    topic: Option<&str>,
    params: &FrontEndParams,
    loops: Option<&LoopParams>,
) -> anyhow::Result<SlamRun> {
    Ok(run_log_live(path, topic, params, loops, None, false, false)?.0)
}

/// [`run_log`] with the search centred on the log's own pose change (`--motion-prior`).
pub fn run_log_with_motion(
    path: &Path,
    params: &FrontEndParams,
    loops: Option<&LoopParams>,
) -> anyhow::Result<SlamRun> {
    Ok(run_log_live(path, None, params, loops, None, true, false)?.0)
}

/// [`run_log_topic`] showing every scan on `live`, with the front end's pose of it when the
/// scan was placed; with `motion_prior`, each search is centred on the log's own pose change.
/// With `interruptible`, a stop request (Ctrl-C) ends the reading and skips loop closure: the
/// run holds the front end's poses of the scans read, and the flag returned is true.
fn run_log_live(
    path: &Path,
    topic: Option<&str>,
    params: &FrontEndParams,
    loops: Option<&LoopParams>,
    mut live: Option<&mut crate::live::LiveView>,
    motion_prior: bool,
    interruptible: bool,
) -> anyhow::Result<(SlamRun, bool)> {
    let options = LogOptions {
        topic: topic.map(str::to_string),
        ..LogOptions::default()
    };
    let mut source = LogSource::open(path, &options)
        .with_context(|| format!("opening the log {}", path.display()))?;
    let name = path.display().to_string();
    let mut progress = Progress::new();
    let mut run = LogRun::new(&name, *source.geometry(), params)?;
    // The motion source is chosen once, on the first record with a pose: odometry when the
    // log has it, else its pose; a record without that one centres nothing.
    let mut odometry: Option<bool> = None;
    let mut interrupted = false;
    loop {
        if interruptible && crate::interrupt::requested() {
            interrupted = true;
            break;
        }
        let rec = match source.next_record() {
            Ok(r) => r,
            Err(e) if e.is_end_of_log() => break,
            Err(e) => return Err(e).context("reading the log"),
        };
        progress.tick();
        let placed = run.placed().len();
        if motion_prior && odometry.is_none() && (rec.odom_pose.or(rec.pose)).is_some() {
            odometry = Some(rec.odom_pose.is_some());
        }
        let motion = match odometry {
            Some(true) => rec.odom_pose,
            Some(false) => rec.pose,
            None => None,
        };
        // The simulator's truth, where the log has it, is the better reference.
        run.add_with_motion(
            rec.line,
            &rec.geometry,
            &rec.scan,
            rec.true_pose.or(rec.pose),
            motion,
        );
        if let Some(v) = live.as_deref_mut() {
            let estimate = run.placed().get(placed).map(|p| p.pose);
            v.scan(&rec.geometry, &rec.scan, estimate, None);
        }
    }
    if motion_prior && odometry.is_none() {
        tracing::warn!(
            "{name}: --motion-prior: the log holds no poses; the constant-velocity model centres every search"
        );
    }
    let run = match loops.filter(|_| !interrupted) {
        Some(l) => run
            .finish_with_loops(source.skipped(), l)
            .context("loop closure")?,
        None => run.finish(source.skipped()),
    };
    progress.bar.finish_and_clear();
    if interrupted {
        tracing::warn!(
            "{name}: interrupted after {} scans; the outputs hold the front end's poses of \
             those, without loop closure",
            run.report.scans
        );
    }
    Ok((run, interrupted))
}

/// Writes `trajectory.tum`, `reference.tum` (when the log has poses), the maps and
/// `slam.json` into `dir`; fills in the map consistency.
pub fn write_outputs(
    dir: &Path,
    run: &mut SlamRun,
    resolution_m: f64,
    max_range_m: f64,
) -> anyhow::Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    write_atomic(
        &dir.join("trajectory.tum"),
        tum(run.placed.iter().map(|p| (p.time_s, p.pose))).as_bytes(),
    )?;
    if run.report.evaluation.is_some() {
        let rows = run
            .placed
            .iter()
            .filter_map(|p| p.reference.map(|r| (p.time_s, r)));
        write_atomic(&dir.join("reference.tum"), tum(rows).as_bytes())?;
    }
    let grid = run.map(resolution_m, max_range_m);
    if grid.width() > 0 {
        write_maps(dir, run, &grid)?;
    } else {
        tracing::warn!(
            "the map holds no hit (no scan placed, or none within {max_range_m} m): map.pgm, map.yaml and map.png are not written"
        );
        crate::outputs::remove_maps(dir)?;
    }
    let mut text = serde_json::to_string_pretty(&run.report)?;
    text.push('\n');
    write_atomic(&dir.join("slam.json"), text.as_bytes())
}

/// `map.pgm`, `map.yaml` and `map.png` (with the trajectory and the closures) of `grid`.
fn write_maps(dir: &Path, run: &SlamRun, grid: &localiser::OccupancyGrid) -> anyhow::Result<()> {
    grid.write_map_server(dir, "map")?;
    let closures = run
        .report
        .loop_closure
        .as_ref()
        .map_or(&[][..], |l| &l.closures[..]);
    let poses: Vec<Pose2> = run.placed.iter().map(|p| p.pose).collect();
    let png = map_png(
        &Raster {
            pixels: grid.to_pixels(),
            width: grid.width(),
            height: grid.height(),
            origin: grid.origin(),
            resolution_m: grid.resolution_m(),
        },
        &poses,
        closures,
    )?;
    write_atomic(&dir.join("map.png"), &png)
}

/// A greyscale map image (row 0 at the top) and where it lies.
struct Raster {
    pixels: Vec<u8>,
    width: usize,
    height: usize,
    /// World position of the lower-left corner of the bottom-left pixel.
    origin: WorldPoint,
    resolution_m: f64,
}

/// Trajectory colour on `map.png`.
const TRAJECTORY_RGB: [u8; 3] = [0, 90, 255];
/// Accepted loop closures on `map.png`.
const ACCEPTED_RGB: [u8; 3] = [0, 170, 0];
/// Rejected loop closures on `map.png`.
const REJECTED_RGB: [u8; 3] = [220, 0, 0];

/// `map.png`: the map with the trajectory through `poses` (blue) and each loop closure as a
/// line between its two scans (green accepted, red rejected), in exact colours.
fn map_png(map: &Raster, poses: &[Pose2], closures: &[slam::Closure]) -> anyhow::Result<Vec<u8>> {
    let (w, h) = (map.width, map.height);
    anyhow::ensure!(
        map.pixels.len() == w * h && w > 0 && h > 0,
        "map.png: an empty map or one of the wrong size"
    );
    let rgb: Vec<u8> = map.pixels.iter().flat_map(|&v| [v, v, v]).collect();
    let mut img =
        image::RgbImage::from_raw(w as u32, h as u32, rgb).context("map.png: wrong buffer size")?;
    // A pose in cells from the lower-left corner (the grid's own cell of a point is the
    // floor of these).
    let r = map.resolution_m;
    let (col0, row0) = (
        (map.origin.x_m() / r).round(),
        (map.origin.y_m() / r).round(),
    );
    let cells = |p: &Pose2| (p.x_m / r - col0, p.y_m / r - row0);
    for pair in poses.windows(2) {
        segment(&mut img, cells(&pair[0]), cells(&pair[1]), TRAJECTORY_RGB);
    }
    for c in closures {
        let (Some(a), Some(b)) = (poses.get(c.from), poses.get(c.to)) else {
            continue;
        };
        let colour = if c.accepted {
            ACCEPTED_RGB
        } else {
            REJECTED_RGB
        };
        segment(&mut img, cells(a), cells(b), colour);
    }
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .context("encoding map.png")?;
    Ok(png)
}

/// Paints the cells the segment `a -> b` (in cells from the image's lower-left corner)
/// crosses inside the image; a segment with a non-finite end is left out.
fn segment(img: &mut image::RgbImage, a: (f64, f64), b: (f64, f64), colour: [u8; 3]) {
    let (w, h) = (f64::from(img.width()), f64::from(img.height()));
    if ![a.0, a.1, b.0, b.1].iter().all(|v| v.is_finite()) {
        return;
    }
    // Clipped to the image (Liang-Barsky), so that the walk below stays within it.
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let edge = 1e-9;
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0),
        (dx, w - edge - a.0),
        (-dy, a.1),
        (dy, h - edge - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return;
            }
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    if t0 > t1 {
        return;
    }
    let cell = |t: f64| {
        let (x, y) = (a.0 + t * dx, a.1 + t * dy);
        (
            x.floor().clamp(0.0, w - 1.0) as i64,
            y.floor().clamp(0.0, h - 1.0) as i64,
        )
    };
    let ((mut x, mut y), (x1, y1)) = (cell(t0), cell(t1));
    // Bresenham between the two cells.
    let (sx, sy) = ((x1 - x).signum(), (y1 - y).signum());
    let (ax, ay) = ((x1 - x).abs(), -(y1 - y).abs());
    let mut err = ax + ay;
    let top = img.height() as i64 - 1;
    loop {
        img.put_pixel(x as u32, (top - y) as u32, image::Rgb(colour));
        if x == x1 && y == y1 {
            break;
        }
        let e2 = 2 * err;
        if e2 >= ay {
            err += ay;
            x += sx;
        }
        if e2 <= ax {
            err += ax;
            y += sy;
        }
    }
}

/// The map of `placed` scans in the frame of their reference poses, placed by the first
/// scan's reference pose alone (no fit to the rest); `None` when that scan has none.
pub fn map_at_reference_start(
    geometry: &ScanGeometry,
    placed: &[slam::Placed],
    resolution_m: f64,
    max_range_m: f64,
) -> Option<localiser::OccupancyGrid> {
    let first = placed.first()?;
    let to_reference = first.reference?.compose(&first.pose.inverse());
    let scans: Vec<_> = placed
        .iter()
        .map(|p| (to_reference.compose(&p.pose), p.scan.clone()))
        .collect();
    let (grid, _) = localiser::build_map(geometry, &scans, resolution_m, max_range_m, false);
    Some(grid)
}

/// Runs `robot-app slam`.
pub fn run(args: SlamArgs) -> anyhow::Result<()> {
    super::check_map_options(args.resolution, args.max_range)?;
    let (params, loops) = load_params(args.config.as_deref())?;
    let loops = (!args.no_loop_closure).then_some(&loops);
    let mut live = args.live.start(args.resolution)?;
    let (mut run, interrupted) = run_log_live(
        &args.log,
        args.topic.as_deref(),
        &params,
        loops,
        live.as_mut(),
        args.motion_prior,
        true,
    )?;
    write_outputs(&args.out, &mut run, args.resolution, args.max_range)?;
    if let Some(v) = live {
        v.finish(Some(&run.map(args.resolution, args.max_range)));
    }
    let r = &run.report;
    let closures = r.loop_closure.as_ref().map_or(String::new(), |l| {
        format!(
            "; loop closures {} accepted, {} rejected",
            l.accepted, l.rejected
        )
    });
    let eval = r.evaluation.as_ref().map_or(String::new(), |e| {
        format!(
            "; against the log's reference poses: k->k+1 {:.3} m {:.2} deg, ATE {:.3} m, final error {:.3} m",
            e.relative_1.translation_m.mean,
            e.relative_1.rotation_deg.mean,
            e.absolute_m.rmse,
            e.final_position_error_m
        ) + &e.closures.map_or(String::new(), |c| {
            format!(
                ", {} of {} accepted closures more than {} m or {} deg off",
                c.outside, c.accepted, c.bound_m, c.bound_deg
            )
        })
    });
    let malformed = match r.malformed_records {
        0 => String::new(),
        n => format!(", {n} malformed records left out"),
    };
    let consistency = r
        .map_consistency_share
        .map_or("no map (no hit in map range)".to_string(), |c| {
            format!("map consistency {:.1} %", 100.0 * c)
        });
    crate::say!(
        "{}: {} of {} scans placed, {} skipped{malformed}; {:.2} ms per scan (median), {consistency}, start to end {:.2} m{closures}{eval}; outputs in {}",
        args.log.display(),
        r.placed,
        r.scans,
        r.skipped.len(),
        r.time_per_scan_ms[0],
        r.start_to_end_m,
        args.out.display()
    );
    if interrupted {
        return Err(crate::interrupt::Interrupted.into());
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use localiser::{CellState, pixel};
    use scan_types::Scan;

    #[test]
    fn map_png_draws_the_trajectory_and_the_closures_where_they_are() {
        // A 40 x 20 pixel map of 0.05 m cells from (-1, -0.5): world (x, y) lies in cell
        // column floor(x / 0.05) + 20 and row floor(y / 0.05) + 10 from the bottom, which is
        // pixel row 19 minus that from the top.
        let map = Raster {
            pixels: vec![pixel::FREE; 40 * 20],
            width: 40,
            height: 20,
            origin: WorldPoint::new(-1.0, -0.5),
            resolution_m: 0.05,
        };
        let at = |x: f64, y: f64| Pose2::new(x, y, 0.0);
        let gap = at(f64::NAN, 0.0);
        let poses = [
            at(-0.875, -0.375), // 0: cell (2, 2), pixel row 17
            at(0.875, -0.375),  // 1: cell (37, 2)
            gap,                // 2
            at(0.0, 0.0),       // 3: on a cell's corner: cell (20, 10), pixel row 9
            at(1e12, 1e12),     // 4: far beyond the image, up and to the right
            gap,                // 5
            at(-0.775, 0.425),  // 6: cell (4, 18)
            gap,                // 7
            at(-0.275, -0.075), // 8: cell (14, 8)
            gap,                // 9
            at(-0.775, -0.275), // 10: cell (4, 4), pixel row 15
            gap,                // 11
            at(0.475, -0.275),  // 12: cell (29, 4)
        ];
        let closure = |from, to, accepted| slam::Closure {
            from,
            to,
            quality: 1.0,
            measured: [0.0; 3],
            accepted,
            heading_sigma_deg: 1.0,
            data_heading_sigma_deg: None,
            data_worst_sigma_m: None,
            residual_sigmas: [0.0; 3],
            weight: 1.0,
        };
        let closures = [
            closure(6, 8, true),
            closure(10, 12, false),
            closure(0, 99, true),
            closure(2, 3, true),
        ];
        let png = map_png(&map, &poses, &closures).unwrap();
        let img = image::load_from_memory(&png).unwrap().to_rgb8();
        assert_eq!(img.dimensions(), (40, 20));
        let px = |col, row| img.get_pixel(col, row).0;
        let (blue, green, red) = ([0, 90, 255], [0, 170, 0], [220, 0, 0]);
        // The leg 0 -> 1 along pixel row 17, columns 2 to 37, and nothing beyond.
        assert_eq!(px(2, 17), blue);
        assert_eq!(px(20, 17), blue);
        assert_eq!(px(37, 17), blue);
        assert_eq!(px(38, 17), [pixel::FREE; 3]);
        // From the corner pose, toward the far one: the diagonal (20 + k, 10 + k) from the
        // bottom, cut at the image's edge.
        assert_eq!(px(20, 9), blue);
        assert_eq!(px(25, 4), blue);
        assert_eq!(px(29, 0), blue);
        // The accepted closure: the diagonal from cell (4, 18) to (14, 8), in exact colour.
        assert_eq!(px(4, 1), green);
        assert_eq!(px(9, 6), green);
        assert_eq!(px(14, 11), green);
        // The rejected one along pixel row 15, columns 4 to 29.
        assert_eq!(px(15, 15), red);
        assert_eq!(px(30, 15), [pixel::FREE; 3]);
        // Away from every line the map is as it was; only the four lines were drawn.
        assert_eq!(px(35, 9), [pixel::FREE; 3]);
        let drawn = img.pixels().filter(|p| p.0 != [pixel::FREE; 3]).count();
        assert_eq!(drawn, 36 + 10 + 11 + 26);
        // An empty map, or one of the wrong size, is an error, not a panic.
        let empty = Raster {
            pixels: Vec::new(),
            width: 0,
            height: 0,
            ..map
        };
        assert!(map_png(&empty, &poses, &closures).is_err());
        let short = Raster {
            pixels: vec![pixel::FREE; 10],
            width: 40,
            height: 20,
            ..empty
        };
        assert!(map_png(&short, &poses, &closures).is_err());
    }

    #[test]
    fn the_map_is_placed_by_the_first_scans_reference_pose() {
        // 21 rays over +-10 deg, each hitting a wall square to the robot 1.02 m ahead.
        let geometry =
            ScanGeometry::new(-10f64.to_radians(), 1f64.to_radians(), 21, 0.02, 4.0).unwrap();
        let ranges: Vec<f64> = (0..21)
            .map(|i| 1.02 / geometry.bearing_rad(i).cos())
            .collect();
        let scan = Scan::from_ranges(&geometry, &ranges, 0.0);
        let placed = |pose: Pose2, reference: Option<Pose2>| slam::Placed {
            time_s: 0.0,
            pose,
            reference,
            scan: scan.clone(),
        };
        let half_pi = std::f64::consts::FRAC_PI_2;
        // The estimate starts at (0.5, 0) facing +x, where the truth is (2, 3) facing +y; three
        // scans there, then three turned about by the estimate, placed by that alone (their
        // own references, far off, are not used).
        let here = Pose2::new(0.5, 0.0, 0.0);
        let on = Pose2::new(0.5, 0.0, std::f64::consts::PI);
        let far = Some(Pose2::new(9.0, 9.0, 0.0));
        let scans = [
            placed(here, Some(Pose2::new(2.0, 3.0, half_pi))),
            placed(here, far),
            placed(here, far),
            placed(on, far),
            placed(on, far),
            placed(on, far),
        ];
        let grid = map_at_reference_start(&geometry, &scans, 0.05, 4.0).unwrap();
        // The walls: 1.02 m from (2, 3) along +y, and along -y.
        for y in [4.02, 1.98] {
            assert_eq!(
                grid.state(WorldPoint::new(2.0, y)),
                CellState::Occupied,
                "y {y}"
            );
        }
        assert_eq!(grid.state(WorldPoint::new(2.0, 3.5)), CellState::Free);
        // Not where the estimate's own frame would put them.
        assert_ne!(grid.state(WorldPoint::new(1.52, 0.0)), CellState::Occupied);
        // No reference: no map.
        let unreferenced = [placed(here, None)];
        assert!(map_at_reference_start(&geometry, &unreferenced, 0.05, 4.0).is_none());
    }
}
