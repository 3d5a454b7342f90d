//! The run-output log formats: the leg ends of a run ([`RunLog`], [`LegRecord`]) as
//! `trajectory.csv` and TUM trajectories (`estimate.tum`, `truth.tum`), each written atomically
//! (temp file + rename), and the errors against truth they hold.

use std::fmt::Write as _;
use std::path::Path;

use scan_types::{Pose2, WorldPoint, angle_diff_rad};

use crate::{LegSummary, LogError};

/// One row of `trajectory.csv`: the pose at the end of a leg (row 0 is the start).
#[derive(Debug, Clone, PartialEq)]
pub struct LegRecord {
    /// Leg number (0 = start).
    pub leg: usize,
    /// Time of the scan that ended the leg, seconds (the TUM files' time stamps).
    pub time_s: f64,
    /// The robot's estimate.
    pub estimate: Pose2,
    /// The true pose (simulator only).
    pub truth: Option<Pose2>,
    /// The landmark the leg localised on, world frame by the estimate.
    pub landmark: Option<WorldPoint>,
    /// Point B of the leg (where the side ray should see the landmark).
    pub point_b: Option<WorldPoint>,
    /// The hits of the scan taken at the end of the leg, world frame by the estimate.
    pub scan_points: Vec<WorldPoint>,
}

/// Everything a run records for its outputs and its plot.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunLog {
    /// Target.
    pub goal: Option<WorldPoint>,
    /// Leg ends, starting with the start pose.
    pub legs: Vec<LegRecord>,
}

impl RunLog {
    /// Position errors (estimate against truth) of every row that has a truth.
    pub fn position_errors_m(&self) -> Vec<f64> {
        self.legs
            .iter()
            .filter_map(|r| {
                r.truth
                    .map(|t| r.estimate.position().distance_m(&t.position()))
            })
            .collect()
    }

    /// Root mean square of [`RunLog::position_errors_m`], or `None` without truth.
    pub fn ate_rmse_m(&self) -> Option<f64> {
        let e = self.position_errors_m();
        if e.is_empty() {
            return None;
        }
        Some((e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt())
    }

    /// Final position and heading error (metres, degrees) of the last row with a truth.
    pub fn final_errors(&self) -> Option<(f64, f64)> {
        let last = self.legs.last()?;
        let t = last.truth?;
        Some((
            last.estimate.position().distance_m(&t.position()),
            angle_diff_rad(last.estimate.theta_rad, t.theta_rad)
                .abs()
                .to_degrees(),
        ))
    }

    /// The legs as the metadata of a recording ([`LegSummary`]).
    pub fn leg_summaries(&self) -> Vec<LegSummary> {
        let xy = |p: WorldPoint| [p.x_m(), p.y_m()];
        self.legs
            .iter()
            .map(|l| LegSummary {
                leg: l.leg,
                estimate: [l.estimate.x_m, l.estimate.y_m, l.estimate.theta_rad],
                landmark: l.landmark.map(xy),
                point_b: l.point_b.map(xy),
            })
            .collect()
    }
}

fn opt(v: Option<f64>) -> String {
    v.map_or_else(String::new, |x| format!("{x:.6}"))
}

/// `trajectory.csv` text: one row per leg end.
pub fn trajectory_csv(log: &RunLog) -> String {
    let mut s = String::from(
        "leg,est_x_m,est_y_m,est_heading_rad,true_x_m,true_y_m,true_heading_rad,landmark_x_m,landmark_y_m,b_x_m,b_y_m\n",
    );
    for r in &log.legs {
        let _ = writeln!(
            s,
            "{},{:.6},{:.6},{:.6},{},{},{},{},{},{},{}",
            r.leg,
            r.estimate.x_m,
            r.estimate.y_m,
            r.estimate.theta_rad,
            opt(r.truth.map(|t| t.x_m)),
            opt(r.truth.map(|t| t.y_m)),
            opt(r.truth.map(|t| t.theta_rad)),
            opt(r.landmark.map(|p| p.x_m())),
            opt(r.landmark.map(|p| p.y_m())),
            opt(r.point_b.map(|p| p.x_m())),
            opt(r.point_b.map(|p| p.y_m())),
        );
    }
    s
}

/// A TUM trajectory (`timestamp tx ty tz qx qy qz qw`) of `(time stamp, pose)` rows.
pub fn tum(poses: impl IntoIterator<Item = (f64, Pose2)>) -> String {
    let mut s = String::new();
    for (t, p) in poses {
        let half = p.theta_rad / 2.0;
        let _ = writeln!(
            s,
            "{:.6} {:.6} {:.6} 0.000000 0.000000 0.000000 {:.9} {:.9}",
            t,
            p.x_m,
            p.y_m,
            half.sin(),
            half.cos()
        );
    }
    s
}

/// Writes `trajectory.csv`, `estimate.tum` and (with truth) `truth.tum` in `dir`.
pub fn write_trajectory(dir: &Path, log: &RunLog) -> Result<(), LogError> {
    write_atomic(&dir.join("trajectory.csv"), trajectory_csv(log).as_bytes())?;
    write_atomic(
        &dir.join("estimate.tum"),
        tum(log.legs.iter().map(|r| (r.time_s, r.estimate))).as_bytes(),
    )?;
    if log.legs.iter().any(|r| r.truth.is_some()) {
        write_atomic(
            &dir.join("truth.tum"),
            tum(log
                .legs
                .iter()
                .filter_map(|r| r.truth.map(|t| (r.time_s, t))))
            .as_bytes(),
        )?;
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically ([`scan_types::write_atomic`]).
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), LogError> {
    scan_types::write_atomic(path, bytes).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })
}
