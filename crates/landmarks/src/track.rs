//! Tracking one landmark while the robot drives straight.

use scan_types::{RobotPoint, Scan, ScanGeometry};

use crate::{DetectParams, Landmark, OpenSide, detect_near};

/// How a [`Tracker`] re-identifies its landmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrackParams {
    /// Largest distance between the predicted and the re-identified landmark, metres.
    pub gate_m: f64,
    /// The gate grows by this much per metre driven since the last fix (drive scale error).
    pub gate_growth_per_m: f64,
    /// The gate also grows by this many ray spacings at the landmark's range (an edge's hit
    /// jumps by up to one spacing along its face from scan to scan).
    pub gate_ray_spacings: f64,
    /// Scans in a row without a match before the landmark counts as lost; meanwhile the
    /// tracker reports the prediction.
    pub max_missed_scans: usize,
    /// When no feature lies in the gate, accept the nearest plain hit point within half the
    /// gate (an edge turning into a corner as the robot passes it).
    pub point_fallback: bool,
    /// Re-identify nothing within `detect.range_limit_margin_m` of the maximum range: there
    /// the last hit of a surface running out of range moves with the robot.
    pub reject_near_range_limit: bool,
    /// Detection rules for re-identification (their `permissive()` form is used).
    pub detect: DetectParams,
}

impl Default for TrackParams {
    /// goalseek: 6 cm gate growing 3 cm per metre driven and by two ray spacings at the
    /// landmark's range, three missed scans tolerated, no point fallback (it slides along
    /// flat faces), nothing re-identified at the range limit.
    fn default() -> Self {
        Self {
            gate_m: 0.06,
            gate_growth_per_m: 0.03,
            gate_ray_spacings: 2.0,
            max_missed_scans: 3,
            point_fallback: false,
            reject_near_range_limit: true,
            detect: DetectParams::default(),
        }
    }
}

impl TrackParams {
    /// Close to the paper (which gives no gate): features only, 0.2 m gate, no misses allowed.
    pub fn paper() -> Self {
        Self {
            gate_m: 0.2,
            gate_growth_per_m: 0.0,
            gate_ray_spacings: 0.0,
            max_missed_scans: 0,
            point_fallback: false,
            reject_near_range_limit: false,
            detect: DetectParams::paper(),
        }
    }
}

/// What one scan said about the tracked landmark.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TrackUpdate {
    /// Re-identified in this scan, in this scan's robot frame.
    Tracked(Landmark),
    /// Not found in this scan but not yet lost: the predicted landmark.
    Predicted(Landmark),
    /// Not found for more than `max_missed_scans` scans in a row.
    Lost,
}

/// Follows one landmark from scan to scan while the robot drives straight along its heading.
///
/// The prediction starts from the last fix: the landmark's robot-frame point moves back by
/// the distance driven since then (`x - (travelled - travelled_at_fix)`, `y` unchanged).
#[derive(Debug, Clone)]
pub struct Tracker {
    params: TrackParams,
    last: Landmark,
    last_point: RobotPoint,
    last_travelled_m: f64,
    misses: usize,
    lost: bool,
}

impl Tracker {
    /// Starts tracking `landmark`, seen at travelled distance 0.
    pub fn new(landmark: Landmark, params: TrackParams) -> Self {
        Self {
            params,
            last: landmark,
            last_point: landmark.robot_point(),
            last_travelled_m: 0.0,
            misses: 0,
            lost: false,
        }
    }

    /// The last re-identified landmark (or the first one).
    pub fn last(&self) -> &Landmark {
        &self.last
    }

    /// Distance driven at the last fix, metres.
    pub fn last_travelled_m(&self) -> f64 {
        self.last_travelled_m
    }

    /// Scans in a row without a match.
    pub fn misses(&self) -> usize {
        self.misses
    }

    /// True once the landmark has been reported lost.
    pub fn is_lost(&self) -> bool {
        self.lost
    }

    /// Where the landmark should be in the robot frame after driving `travelled_m` in total.
    pub fn predict(&self, travelled_m: f64) -> RobotPoint {
        RobotPoint::new(
            self.last_point.x_m() - (travelled_m - self.last_travelled_m),
            self.last_point.y_m(),
        )
    }

    /// Re-identifies the landmark in `scan`, taken after driving `travelled_m` in total from
    /// where the landmark was first seen.
    pub fn update(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        travelled_m: f64,
    ) -> TrackUpdate {
        if self.lost {
            return TrackUpdate::Lost;
        }
        let pred = self.predict(travelled_m);
        let gate = self.params.gate_m
            + self.params.gate_growth_per_m * (travelled_m - self.last_travelled_m).abs()
            + self.params.gate_ray_spacings * pred.range_m() * geometry.increment_rad.abs();
        // Only landmarks within the gate can match: corners are sought near the prediction.
        let found = detect_near(geometry, scan, &self.params.detect.permissive(), pred, gate);
        let compatible = |l: &Landmark| match (self.last.open_side, l.open_side) {
            (Some(a), Some(b)) => a == b || a == OpenSide::Both || b == OpenSide::Both,
            _ => true,
        };
        let clear = |range_m: f64| {
            !self.params.reject_near_range_limit
                || range_m
                    < geometry.max_range_m - self.params.detect.range_limit_margin_for(geometry)
        };
        let best = found
            .iter()
            .filter(|l| compatible(l) && clear(l.range_m))
            .map(|l| (l.robot_point().distance_m(&pred), l))
            .filter(|(d, _)| *d <= gate)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, l)| *l);
        let best = best.or_else(|| {
            if !self.params.point_fallback {
                return None;
            }
            scan.robot_hits(geometry)
                .filter(|(_, p)| clear(p.range_m()))
                .map(|(i, p)| (p.distance_m(&pred), i, p))
                .filter(|(d, _, _)| *d <= 0.5 * gate)
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, i, p)| Landmark {
                    index: i,
                    range_m: p.range_m(),
                    bearing_rad: p.bearing_rad(),
                    kind: self.last.kind,
                    open_side: self.last.open_side,
                    score: self.last.score * 0.5,
                    ..self.last
                })
        });
        match best {
            Some(l) => {
                self.last = l;
                self.last_point = l.robot_point();
                self.last_travelled_m = travelled_m;
                self.misses = 0;
                TrackUpdate::Tracked(l)
            }
            None => {
                self.misses += 1;
                if self.misses > self.params.max_missed_scans {
                    self.lost = true;
                    tracing::debug!(travelled_m, "landmark lost");
                    return TrackUpdate::Lost;
                }
                let index = geometry
                    .nearest_index(pred.bearing_rad())
                    .unwrap_or(self.last.index);
                TrackUpdate::Predicted(Landmark {
                    index,
                    range_m: pred.range_m(),
                    bearing_rad: pred.bearing_rad(),
                    ..self.last
                })
            }
        }
    }
}
