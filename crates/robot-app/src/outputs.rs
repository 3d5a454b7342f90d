//! The run's `summary.json`, written atomically (temp file + rename); the trajectory files
//! beside it are [`scan_log::write_trajectory`]'s.

use std::path::Path;

use anyhow::Context;
use serde::{Deserialize, Serialize};

pub use navigator::Reason;

/// `summary.json`: the outcome of one run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// True when the run ended at the target (in the simulator: the true position within the
    /// success radius and no collision; on a real robot: the estimate within tolerance).
    pub reached: bool,
    /// Why the run ended.
    pub reason: Reason,
    /// Legs driven (one landmark fix or final approach each).
    pub legs: usize,
    /// Scans taken.
    pub scans: usize,
    /// Collisions recorded by the simulator (0 on a real robot).
    pub collisions: usize,
    /// Distance commanded, metres: the sum of the forward moves the navigator sent (not what
    /// the robot drove; see `true_path_length_m`).
    pub commanded_path_length_m: f64,
    /// Distance the robot truly drove, metres (simulator only): the `p` of SPL.
    pub true_path_length_m: Option<f64>,
    /// Shortest collision-free path from start to target for the robot's disc in the true
    /// world, metres (simulator only; `null` when none was found): the `l` of SPL.
    pub geodesic_m: Option<f64>,
    /// Success weighted by path length of this run, [`spl`] (simulator only; `null` without
    /// a geodesic).
    pub spl: Option<f64>,
    /// Distance between the final estimate and the true position, metres (simulator only).
    pub final_position_error_m: Option<f64>,
    /// Final heading error, degrees (simulator only).
    pub final_heading_error_deg: Option<f64>,
    /// RMS of the position error at every leg end, metres (simulator only).
    pub ate_rmse_m: Option<f64>,
    /// True distance to the target at the end, metres (simulator only).
    pub goal_distance_m: Option<f64>,
    /// CPU time of the run, seconds (the loop's own thread).
    pub cpu_time_s: f64,
    /// Method preset used.
    pub method: String,
    /// Noise seed (simulator).
    pub seed: Option<u64>,
    /// Start pose.
    pub start: PoseOut,
    /// Target.
    pub goal: PointOut,
    /// Final estimated pose.
    pub final_estimate: PoseOut,
    /// Final true pose (simulator only).
    pub final_truth: Option<PoseOut>,
    /// A one-line note on how the run ended (the error, for a failure).
    pub note: String,
    /// The narrow passages the run drove through (graded clearance), in leg order.
    #[serde(default)]
    pub narrow_passages: Vec<NarrowPassage>,
    /// The navigator's position uncertainty at the end of every leg (leg 0 = the start),
    /// metres: its own error model, no truth needed.
    pub position_sigma_m: Vec<f64>,
    /// The navigator's heading uncertainty at the end of every leg, degrees.
    pub heading_sigma_deg: Vec<f64>,
}

/// A pose in a JSON report: metres and degrees.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseOut {
    /// X, metres.
    pub x_m: f64,
    /// Y, metres.
    pub y_m: f64,
    /// Heading, degrees.
    pub heading_deg: f64,
}

impl PoseOut {
    /// The report form of `p`.
    pub fn of(p: &scan_types::Pose2) -> Self {
        Self {
            x_m: p.x_m,
            y_m: p.y_m,
            heading_deg: p.theta_rad.to_degrees(),
        }
    }
}

/// A point in a JSON report, metres.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PointOut {
    /// X, metres.
    pub x_m: f64,
    /// Y, metres.
    pub y_m: f64,
}

impl PointOut {
    /// The report form of `p`.
    pub fn of(p: scan_types::WorldPoint) -> Self {
        Self {
            x_m: p.x_m(),
            y_m: p.y_m(),
        }
    }
}

/// A passage narrower than the full margin allows, taken on one leg.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct NarrowPassage {
    /// The leg's number (1 = the first leg driven).
    pub leg: usize,
    /// Where the robot's centre passes closest to an obstacle (estimate's frame).
    pub at: PointOut,
    /// Distance from there to the nearest hit of the planning scan, metres.
    pub clearance_m: f64,
    /// The passage's width across the leg, metres.
    pub width_m: f64,
}

/// The `summary.json` records of an outcome's narrow passages.
pub fn narrow_passages(outcome: &navigator::Outcome) -> Vec<NarrowPassage> {
    outcome
        .narrow_passages
        .iter()
        .map(|n| NarrowPassage {
            leg: n.leg,
            at: PointOut::of(n.at),
            clearance_m: n.clearance_m,
            width_m: n.width_m,
        })
        .collect()
}

/// The navigator's position and heading uncertainty at each leg end of `outcome`.
pub fn leg_sigmas(outcome: &navigator::Outcome) -> (Vec<f64>, Vec<f64>) {
    outcome
        .legs
        .iter()
        .map(|l| (l.position_sigma_m, l.heading_sigma_deg))
        .unzip()
}

/// One run's term of Success weighted by Path Length (Anderson et al. 2018):
/// `S * l / max(p, l)` for success `S`, shortest path `l` and path driven `p`; 1 for a success
/// with no positive `l`.
pub fn spl(reached: bool, geodesic_m: f64, path_m: f64) -> f64 {
    if !reached {
        return 0.0;
    }
    if geodesic_m.is_nan() || geodesic_m <= 0.0 {
        return 1.0;
    }
    // `f64::max` ignores a NaN `path_m`.
    geodesic_m / path_m.max(geodesic_m)
}

/// Set once standard output carries a base's commands (`--base stdio`).
static STDOUT_IS_BASE: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Sends result lines to standard error from now on: standard output carries nothing but a
/// base's commands.
pub fn stdout_is_base() {
    STDOUT_IS_BASE.store(true, std::sync::atomic::Ordering::SeqCst);
}

/// Prints a result line on stdout (stderr once [`stdout_is_base`]). A reader that has gone
/// away (`robot-app ... | head`) is no error: the work goes on and its files are written.
pub fn say(text: std::fmt::Arguments) {
    use std::io::Write;
    let written = if STDOUT_IS_BASE.load(std::sync::atomic::Ordering::SeqCst) {
        std::io::stderr().lock().write_fmt(text)
    } else {
        std::io::stdout().lock().write_fmt(text)
    };
    if let Err(e) = written
        && e.kind() != std::io::ErrorKind::BrokenPipe
    {
        tracing::error!("cannot write a result line: {e}");
    }
}

/// `println!` through [`say`].
#[macro_export]
macro_rules! say {
    ($($arg:tt)*) => {
        $crate::outputs::say(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes `bytes` to `path` atomically ([`scan_types::write_atomic`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> anyhow::Result<()> {
    scan_types::write_atomic(path, bytes)
        .with_context(|| format!("cannot write {}", path.display()))
}

/// Writes `map.pgm`, `map.yaml` and `map.png` of `grid` in `dir`; a grid that holds no scan
/// (a run stopped before its first) writes none and says so.
pub fn write_grid(dir: &Path, grid: &localiser::OccupancyGrid) -> anyhow::Result<()> {
    if grid.width() == 0 {
        tracing::warn!("no scan was mapped: map.pgm, map.yaml and map.png are not written");
        return remove_maps(dir);
    }
    grid.write_map_server(dir, "map")
        .with_context(|| format!("writing map.pgm/map.yaml in {}", dir.display()))?;
    grid.to_png(&dir.join("map.png"))
        .with_context(|| format!("writing map.png in {}", dir.display()))
}

/// Removes an earlier run's `map.pgm`, `map.yaml` and `map.png` from `dir`, so that none lies
/// beside outputs it does not belong to.
pub fn remove_maps(dir: &Path) -> anyhow::Result<()> {
    for name in ["map.pgm", "map.yaml", "map.png"] {
        let path = dir.join(name);
        match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                return Err(e).with_context(|| format!("cannot remove {}", path.display()));
            }
            _ => {}
        }
    }
    Ok(())
}

/// Writes `summary.json` in `dir`.
pub fn write_summary(dir: &Path, summary: &Summary) -> anyhow::Result<()> {
    let mut text = serde_json::to_string_pretty(summary)?;
    text.push('\n');
    write_atomic(&dir.join("summary.json"), text.as_bytes())
}
