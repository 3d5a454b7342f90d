//! The front end over every scan of a log, and the run's report: placed and skipped scans, time
//! per scan, path figures, map consistency and, when the log has reference poses (never shown
//! to the front end), the errors against them.

use std::time::Instant;

use scan_types::{Pose2, Scan, ScanGeometry};
use serde::Serialize;

use crate::eval::{
    ClosureCheck, RelativeError, Stats, absolute_errors, closure_check, relative_error,
};
use crate::{FrontEnd, FrontEndParams, LoopParams, LoopReport, Placement, SlamError, close_loops};

/// One placed scan.
#[derive(Debug, Clone)]
pub struct Placed {
    /// Its time stamp, seconds (the log's, or the scan index).
    pub time_s: f64,
    /// The estimate.
    pub pose: Pose2,
    /// The log's reference pose, if it has one (never seen by the estimator).
    pub reference: Option<Pose2>,
    /// The scan.
    pub scan: Scan,
}

/// A scan that was not placed.
#[derive(Debug, Clone, Serialize)]
pub struct Skip {
    /// Its line (text logs) or sequence number (MCAP).
    pub line: usize,
    /// Why.
    pub reason: String,
}

/// `slam.json`.
#[derive(Debug, Clone, Serialize)]
pub struct SlamReport {
    /// The log.
    pub log: String,
    /// Scans read.
    pub scans: usize,
    /// Scans placed.
    pub placed: usize,
    /// Scans that could not be placed.
    pub skipped: Vec<Skip>,
    /// Malformed records of the log that were skipped while reading.
    pub malformed_records: usize,
    /// Where the time stamps come from: `log` or `scan_index`.
    pub timestamps: String,
    /// Front-end time per scan, milliseconds: median and 99th percentile.
    pub time_per_scan_ms: [f64; 2],
    /// Wall-clock time of the estimate (reading, front end, loop closure when run), seconds.
    pub total_time_s: f64,
    /// Straight-line distance between the first and the last placed pose, metres.
    pub start_to_end_m: f64,
    /// Length of the estimated path, metres.
    pub estimated_path_length_m: f64,
    /// Share of the map's hit endpoints within one cell of an occupied cell (`None`: no hit
    /// in map range, no map).
    pub map_consistency_share: Option<f64>,
    /// True when some scan's search was centred on a motion source's pose change
    /// ([`LogRun::add_with_motion`]): the trajectory is then not the laser's alone.
    pub motion_prior: bool,
    /// Against the log's reference poses, when every placed scan has one.
    pub evaluation: Option<Evaluation>,
    /// Loop closure, when it ran (`None`: the front end alone).
    pub loop_closure: Option<LoopReport>,
    /// Loop closure's parameters, when it ran.
    pub loop_params: Option<LoopParams>,
    /// The front end's parameters.
    pub params: FrontEndParams,
}

/// Errors against the reference poses.
#[derive(Debug, Clone, Serialize)]
pub struct Evaluation {
    /// Relations k to k+1.
    pub relative_1: RelativeError,
    /// Relations k to k+10.
    pub relative_10: Option<RelativeError>,
    /// Position error after an SE(2) alignment, metres.
    pub absolute_m: Stats,
    /// The last placed scan's position error after that alignment, metres.
    pub final_position_error_m: f64,
    /// Accepted loop closures against the reference relative poses (0.2 m, 2 deg), when loop
    /// closure ran.
    pub closures: Option<ClosureCheck>,
}

/// A finished run.
pub struct SlamRun {
    /// The log's geometry.
    pub geometry: ScanGeometry,
    /// Placed scans, in order.
    pub placed: Vec<Placed>,
    /// What `slam.json` holds.
    pub report: SlamReport,
}

/// The front end fed one log's scans in order, collecting what [`SlamRun`] reports.
pub struct LogRun {
    fe: FrontEnd,
    name: String,
    geometry: ScanGeometry,
    placed: Vec<Placed>,
    skipped: Vec<Skip>,
    times_ms: Vec<f64>,
    scans: usize,
    started: Instant,
    /// The motion source's pose of the last placed scan ([`LogRun::add_with_motion`]).
    last_motion: Option<Pose2>,
    /// Whether a motion source centred a search.
    used_motion: bool,
}

impl LogRun {
    /// A run over the log `name` (for messages and the report) of `geometry`, with `params`.
    pub fn new(
        name: &str,
        geometry: ScanGeometry,
        params: &FrontEndParams,
    ) -> Result<Self, SlamError> {
        Ok(Self {
            fe: FrontEnd::new(params.clone())?,
            name: name.to_string(),
            geometry,
            placed: Vec::new(),
            skipped: Vec::new(),
            times_ms: Vec::new(),
            scans: 0,
            started: Instant::now(),
            last_motion: None,
            used_motion: false,
        })
    }

    /// Places the next scan of the log (its `line`, or sequence number); `reference` is the
    /// log's pose of it, kept for evaluation only.
    pub fn add(
        &mut self,
        line: usize,
        geometry: &ScanGeometry,
        scan: &Scan,
        reference: Option<Pose2>,
    ) {
        self.add_with_motion(line, geometry, scan, reference, None);
    }

    /// [`LogRun::add`] with the search centred on the last placed pose moved as `motion` (a
    /// pose of the scan from another source: odometry, a robot's own estimate) moved since
    /// the last placed scan; without `motion`, or before one, the constant-velocity model.
    pub fn add_with_motion(
        &mut self,
        line: usize,
        geometry: &ScanGeometry,
        scan: &Scan,
        reference: Option<Pose2>,
        motion: Option<Pose2>,
    ) {
        self.scans += 1;
        let t = Instant::now();
        let prediction = match (motion, self.last_motion, self.placed.last()) {
            (Some(now), Some(then), Some(last)) => {
                Some(last.pose.compose(&then.inverse().compose(&now)))
            }
            _ => None,
        };
        let placement = match prediction {
            Some(p) => {
                self.used_motion = true;
                self.fe.add_scan_near(geometry, scan, p)
            }
            None => self.fe.add_scan(geometry, scan),
        };
        self.times_ms.push(t.elapsed().as_secs_f64() * 1e3);
        match placement {
            Placement::Placed { pose, .. } => {
                self.last_motion = motion;
                self.placed.push(Placed {
                    time_s: scan.host_time_s,
                    pose,
                    reference,
                    scan: scan.clone(),
                })
            }
            Placement::Skipped { reason } => {
                tracing::warn!("{} line {line}: scan not placed: {reason}", self.name);
                self.skipped.push(Skip {
                    line,
                    reason: reason.to_string(),
                });
            }
        }
    }

    /// The scans placed so far, in order (the front end's poses).
    pub fn placed(&self) -> &[Placed] {
        &self.placed
    }

    /// Ends the run; `malformed_records` is the count of records the reader skipped.
    pub fn finish(self, malformed_records: usize) -> SlamRun {
        let total_time_s = self.started.elapsed().as_secs_f64();
        self.report(malformed_records, total_time_s, None)
    }

    /// Ends the run with loop closure over the front end's trajectory ([`close_loops`]):
    /// the placed poses become the optimised ones.
    pub fn finish_with_loops(
        mut self,
        malformed_records: usize,
        params: &LoopParams,
    ) -> Result<SlamRun, SlamError> {
        let scans: Vec<&Scan> = self.placed.iter().map(|p| &p.scan).collect();
        let poses: Vec<Pose2> = self.placed.iter().map(|p| p.pose).collect();
        let (poses, loops) = close_loops(&self.geometry, &scans, &poses, self.fe.params(), params)?;
        for (p, pose) in self.placed.iter_mut().zip(poses) {
            p.pose = pose;
        }
        let total_time_s = self.started.elapsed().as_secs_f64();
        let mut run = self.report(malformed_records, total_time_s, Some(loops));
        run.report.loop_params = Some(params.clone());
        Ok(run)
    }

    fn report(
        self,
        malformed_records: usize,
        total_time_s: f64,
        loop_closure: Option<LoopReport>,
    ) -> SlamRun {
        let Self {
            fe,
            name,
            geometry,
            mut placed,
            skipped,
            mut times_ms,
            scans,
            used_motion,
            ..
        } = self;
        let timestamps = fix_timestamps(&name, &mut placed);
        let report = SlamReport {
            log: name,
            scans,
            placed: placed.len(),
            skipped,
            malformed_records,
            timestamps,
            time_per_scan_ms: [
                percentile(&mut times_ms, 0.5),
                percentile(&mut times_ms, 0.99),
            ],
            total_time_s,
            start_to_end_m: match (placed.first(), placed.last()) {
                (Some(a), Some(b)) => a.pose.position().distance_m(&b.pose.position()),
                _ => 0.0,
            },
            estimated_path_length_m: placed
                .windows(2)
                .map(|w| w[0].pose.position().distance_m(&w[1].pose.position()))
                .sum(),
            map_consistency_share: None,
            motion_prior: used_motion,
            evaluation: evaluate(&placed, loop_closure.as_ref()),
            loop_closure,
            loop_params: None,
            params: fe.params().clone(),
        };
        SlamRun {
            geometry,
            placed,
            report,
        }
    }
}

impl SlamRun {
    /// The map of the placed scans at their estimates (rays up to `max_range_m`, no-return rays
    /// left out); fills in the report's map consistency.
    pub fn map(&mut self, resolution_m: f64, max_range_m: f64) -> localiser::OccupancyGrid {
        let scans: Vec<(Pose2, Scan)> = self
            .placed
            .iter()
            .map(|p| (p.pose, p.scan.clone()))
            .collect();
        let (grid, stats) =
            localiser::build_map(&self.geometry, &scans, resolution_m, max_range_m, false);
        self.report.map_consistency_share = (stats.endpoints > 0).then(|| stats.endpoint_fit());
        grid
    }
}

/// Keeps the log's time stamps when they are finite and increase; else the scan index.
fn fix_timestamps(name: &str, placed: &mut [Placed]) -> String {
    let increasing = placed.iter().all(|p| p.time_s.is_finite())
        && placed.windows(2).all(|w| w[1].time_s > w[0].time_s);
    if increasing {
        return "log".into();
    }
    tracing::warn!(
        "{name}: the time stamps are missing or do not increase; trajectory.tum uses the scan index"
    );
    for (i, p) in placed.iter_mut().enumerate() {
        p.time_s = i as f64;
    }
    "scan_index".into()
}

fn percentile(v: &mut [f64], q: f64) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[((v.len() - 1) as f64 * q).round() as usize]
}

fn evaluate(placed: &[Placed], loops: Option<&LoopReport>) -> Option<Evaluation> {
    let reference: Vec<Pose2> = placed.iter().map(|p| p.reference).collect::<Option<_>>()?;
    let est: Vec<Pose2> = placed.iter().map(|p| p.pose).collect();
    let absolute = absolute_errors(&est, &reference).ok()?;
    Some(Evaluation {
        relative_1: relative_error(&est, &reference, 1).ok()?,
        relative_10: relative_error(&est, &reference, 10).ok(),
        absolute_m: Stats::of(&absolute),
        final_position_error_m: *absolute.last()?,
        closures: loops.and_then(|l| {
            let accepted: Vec<(usize, usize, Pose2)> = l
                .closures
                .iter()
                .filter(|c| c.accepted)
                .map(|c| {
                    (
                        c.from,
                        c.to,
                        Pose2::new(c.measured[0], c.measured[1], c.measured[2]),
                    )
                })
                .collect();
            closure_check(&accepted, &reference, 0.2, 2.0)
        }),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use scan_types::testkit::{boxed, scan_at};
    use std::f64::consts::FRAC_PI_2;

    /// Scans in a 4 m square room from the true `poses`, with `motion` poses for them; the
    /// placed poses.
    fn placed_in_a_square_room(poses: &[Pose2], motion: &[Option<Pose2>]) -> Vec<Pose2> {
        let g = ScanGeometry::new(-120f64.to_radians(), 1f64.to_radians(), 241, 0.02, 5.6).unwrap();
        let room = boxed(-2.0, -2.0, 2.0, 2.0);
        let mut run = LogRun::new("room", g, &FrontEndParams::default()).unwrap();
        for (k, (p, m)) in poses.iter().zip(motion).enumerate() {
            let scan = scan_at(&g, &room, p.x_m, p.y_m, p.theta_rad);
            run.add_with_motion(k + 1, &g, &scan, None, *m);
        }
        assert_eq!(run.placed().len(), poses.len());
        run.placed().iter().map(|p| p.pose).collect()
    }

    #[test]
    fn a_motion_source_resolves_a_turn_the_laser_cannot_see() {
        // A quarter turn in the middle of the room, then 1 m ahead (+y).
        let truth = [
            Pose2::new(0.0, 0.0, 0.0),
            Pose2::new(0.0, 0.0, FRAC_PI_2),
            Pose2::new(0.0, 1.0, FRAC_PI_2),
        ];
        // The room looks the same after the turn: from the laser alone (constant velocity:
        // no turn) the second scan stays at 0 deg.
        let alone = placed_in_a_square_room(&truth[..2], &[None, None]);
        assert!(alone[1].theta_rad.to_degrees().abs() < 1.0, "{alone:?}");
        // A motion source that turned and drove the same, in a frame of its own.
        let a = Pose2::new(10.0, 5.0, 0.5);
        let b = a.compose(&Pose2::new(0.0, 0.0, FRAC_PI_2));
        let c = b.compose(&Pose2::new(1.0, 0.0, 0.0));
        let placed = placed_in_a_square_room(&truth, &[Some(a), Some(b), Some(c)]);
        for (p, t) in placed.iter().zip(&truth) {
            assert!(p.position().distance_m(&t.position()) < 0.05, "{placed:?}");
            let turn = (p.theta_rad - t.theta_rad).to_degrees();
            assert!(turn.abs() < 1.0, "{placed:?}");
        }
    }
}
