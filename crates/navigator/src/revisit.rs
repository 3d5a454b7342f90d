//! Revisits: a leg's end scan matched against the leg-end scans of earlier legs taken nearby,
//! so that a place seen again pulls the estimate back to where it was mapped.

use localiser::{MatchParams, MatchTarget, OccupancyGrid};
use scan_types::{Pose2, Scan, ScanGeometry};

use crate::params::LocaliserParams;

/// Least share of the scan's hits that must pair with the earlier scans.
const MIN_PAIRED_SHARE: f64 = 0.5;
/// A correction is taken only within this many standard deviations of the estimate.
const MAX_SIGMAS: f64 = 3.0;
/// Floors of the estimate's uncertainty in those gates: metres and degrees.
const MIN_GATE_M: f64 = 0.03;
const MIN_GATE_DEG: f64 = 0.5;

/// One leg's end: its scan, the estimate there and that estimate's uncertainty.
struct Keyframe {
    leg: usize,
    pose: Pose2,
    scan: Scan,
    sigma_m: f64,
    sigma_heading_rad: f64,
}

/// A revisit correction: the new estimate and its uncertainty.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Correction {
    /// The leg whose end the scan was matched in the frame of (the nearest earlier leg end).
    pub anchor_leg: usize,
    /// The estimate after the correction.
    pub pose: Pose2,
    /// Its position uncertainty, metres (one standard deviation).
    pub sigma_m: f64,
    /// Its heading uncertainty, radians.
    pub sigma_heading_rad: f64,
}

/// The leg ends seen so far.
#[derive(Default)]
pub(crate) struct Revisits {
    keyframes: Vec<Keyframe>,
}

impl Revisits {
    /// Keeps leg `leg`'s end scan, taken at `pose` with the given uncertainty.
    pub fn add(&mut self, leg: usize, pose: Pose2, scan: &Scan, sigma: (f64, f64)) {
        self.keyframes.push(Keyframe {
            leg,
            pose,
            scan: scan.clone(),
            sigma_m: sigma.0,
            sigma_heading_rad: sigma.1,
        });
    }

    /// Spreads a correction of the estimate at leg `leg`'s end (from `before` to `after`) over
    /// the leg ends kept since leg `from`, in proportion to their leg number: the drift grew
    /// leg by leg, so the older leg ends move less.
    pub fn distribute(&mut self, from: usize, leg: usize, before: Pose2, after: Pose2) {
        if leg <= from {
            return;
        }
        let dx = after.x_m - before.x_m;
        let dy = after.y_m - before.y_m;
        let dth = scan_types::normalize_angle_rad(after.theta_rad - before.theta_rad);
        for k in self
            .keyframes
            .iter_mut()
            .filter(|k| k.leg > from && k.leg < leg)
        {
            let w = (k.leg - from) as f64 / (leg - from) as f64;
            k.pose = Pose2::new(
                k.pose.x_m + w * dx,
                k.pose.y_m + w * dy,
                scan_types::normalize_angle_rad(k.pose.theta_rad + w * dth),
            );
        }
    }

    /// The occupancy grid of every leg end kept, at its (corrected) pose.
    pub fn grid(&self, resolution_m: f64, geometry: &ScanGeometry) -> OccupancyGrid {
        let mut grid = OccupancyGrid::new(resolution_m);
        for k in &self.keyframes {
            grid.integrate(&k.pose, geometry, &k.scan);
        }
        grid
    }

    /// Matches `scan`, taken at leg `leg`'s end near `estimate` (uncertainty `sigma`: metres,
    /// radians), against the nearest earlier leg ends old enough; the correction when the
    /// match is good, pins the pose and lies within the uncertainty.
    pub fn correct(
        &self,
        params: &LocaliserParams,
        geometry: &ScanGeometry,
        leg: usize,
        scan: &Scan,
        estimate: Pose2,
        sigma: (f64, f64),
    ) -> Option<Correction> {
        let here = estimate.position();
        let newest = leg.checked_sub(params.revisit_min_age_legs)?;
        let mut near: Vec<(f64, &Keyframe)> = self
            .keyframes
            .iter()
            .filter(|k| k.leg <= newest)
            .map(|k| (k.pose.position().distance_m(&here), k))
            .filter(|(d, _)| *d <= params.revisit_radius_m)
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        near.truncate(params.revisit_keyframes);
        let anchor_leg = near.first()?.1.leg;
        let base = near.first()?.1.pose;
        let to_base = base.inverse();
        let defaults = MatchParams::default();
        let mut target = MatchTarget::new();
        for (_, k) in &near {
            target.add_scan(&to_base.compose(&k.pose), geometry, &k.scan, &defaults);
        }
        let guess = to_base.compose(&estimate);
        let hits = scan.robot_hits(geometry).count();
        // First near the estimate, as if it had not drifted; only when that does not fit,
        // as far as its uncertainty allows. A place that repeats (a row of posts) then
        // cannot pull an estimate that already fits one copy of it onto the next.
        let near_gate = (MIN_GATE_M, MIN_GATE_DEG.to_radians());
        let wide_gate = (
            sigma.0.max(MIN_GATE_M),
            sigma.1.max(MIN_GATE_DEG.to_radians()),
        );
        let (pose, m) = [near_gate, wide_gate]
            .into_iter()
            .find_map(|(gate_m, gate_rad)| {
                let match_params = MatchParams {
                    prior_sigma_m: gate_m,
                    prior_sigma_rad: gate_rad,
                    ..defaults
                };
                let m = target.align(geometry, scan, guess, &match_params)?;
                let pose = base.compose(&m.pose);
                let shift = pose.position().distance_m(&here);
                let turn =
                    scan_types::normalize_angle_rad(pose.theta_rad - estimate.theta_rad).abs();
                let taken = m.data_worst_sigma_m <= params.revisit_max_sigma_m
                    && m.pairs as f64 >= MIN_PAIRED_SHARE * hits as f64
                    && shift <= MAX_SIGMAS * gate_m
                    && turn <= MAX_SIGMAS * gate_rad;
                tracing::debug!(
                    leg,
                    keyframes = near.len(),
                    gate_m,
                    shift,
                    turn_deg = turn.to_degrees(),
                    data_sig = m.data_worst_sigma_m,
                    pairs = m.pairs,
                    hits,
                    taken,
                    "revisit match"
                );
                taken.then_some((pose, m))
            })?;
        // As certain as the earlier leg ends, plus the match's own uncertainty.
        let (kf_m, kf_rad) = near
            .iter()
            .fold((f64::INFINITY, f64::INFINITY), |acc, (_, k)| {
                (acc.0.min(k.sigma_m), acc.1.min(k.sigma_heading_rad))
            });
        Some(Correction {
            anchor_leg,
            pose,
            sigma_m: kf_m.hypot(m.worst_sigma_m).min(sigma.0),
            sigma_heading_rad: kf_rad.min(sigma.1),
        })
    }
}
