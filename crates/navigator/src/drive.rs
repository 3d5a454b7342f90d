//! One leg driven in steps: the landmark tracked, the travel measured on it and refined by
//! scan matching against keyframes.

use landmarks::{Circle, Landmark, RoundParams, TrackUpdate, Tracker, round_centre, round_object};
use localiser::{MatchParams, MatchTarget};
use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

use crate::{Navigator, TravelRule};

/// Bearing of the side rays.
const SIDE_RAD: f64 = std::f64::consts::FRAC_PI_2;
/// Shares of the commanded travel tried as well when matching, so that a base that stalls or
/// slips is seen by the laser rather than assumed to have done what it was told.
const PARTIAL_SHARES: [f64; 4] = [0.0, 0.25, 0.5, 0.75];
/// Partial shares are tried from this much commanded travel on, metres.
const PARTIAL_MIN_M: f64 = 0.1;
/// The laser disagrees with the commands when the match lands this many prior sigmas off.
const DISAGREE_SIGMAS: f64 = 3.0;
/// A partial-travel match with nothing to compare with must pair this share of the hits.
const ALONE_SHARE: f64 = 0.5;
/// A match leaves the travel to the laser when its worst direction is known this well, metres.
const CONSTRAINED_SIGMA_M: f64 = 0.05;
/// A landmark's travel strays from the commands by more than this, metres ...
const STRAY_M: f64 = 0.2;
/// ... or this share of the commanded travel.
const STRAY_SHARE: f64 = 0.3;

/// What a leg is for.
#[derive(Debug, Clone, Copy)]
pub(crate) enum LegKind {
    /// Straight to the target.
    Final,
    /// To point B of a landmark (world frame by the estimate at the leg's start).
    ToB {
        landmark: WorldPoint,
        point_b: WorldPoint,
    },
    /// A short leg without a landmark in front.
    Short,
}

/// A drive under way.
pub(crate) struct Drive {
    pub(crate) kind: LegKind,
    /// The estimate at the start of the leg.
    pub(crate) origin: Pose2,
    /// The most the leg drives, metres.
    pub(crate) limit_m: f64,
    step_m: f64,
    stop_at_side: bool,
    tracker: Option<Tracker>,
    /// The landmark's distance ahead at the start (OB).
    ob0: Option<f64>,
    /// `[tracking] round_centre`: the landmark's object, followed by its centre once it
    /// proves round.
    round: Option<RoundTrack>,
    match_params: MatchParams,
    /// The reference scan for matching: its pose relative to the start of the drive, the
    /// measured travel there, and the scan.
    key: Option<(Pose2, f64, MatchTarget)>,
    /// Forward motion commanded and done so far, metres.
    pub(crate) commanded_m: f64,
    /// Measured travel at the last fix and the commanded travel at that fix.
    fix: Option<(f64, f64)>,
    /// The landmark edge's travel at the last tracked scan and the commanded travel then:
    /// what the drive aims by, since it stops when the edge is abreast.
    edge_fix: Option<(f64, f64)>,
    /// True when the last travel estimate came from a well-constrained scan match (the
    /// laser), not from the commands or a landmark fix alone.
    pub(crate) laser_measured: bool,
    pub(crate) last_scan: Scan,
    /// `[planner] replan_step_m`: the rest of the leg judged on the planner's map while
    /// driving (`None`: not watched).
    pub(crate) watch: Option<Watch>,
}

/// What a watched leg is judged against.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Watch {
    /// Progress toward the target per metre of the leg when it was planned: the path length
    /// from its start less that from its end, over its length.
    pub(crate) rate: f64,
    /// Commanded travel at the last check, metres.
    pub(crate) checked_m: f64,
}

impl Drive {
    /// A drive of at most `limit_m` from `origin`, tracking `landmark` (seen in `scan`, taken
    /// at `origin`); a leg to B stops when the side ray sees the landmark.
    pub(crate) fn new(
        nav: &Navigator,
        kind: LegKind,
        origin: Pose2,
        limit_m: f64,
        landmark: Option<Landmark>,
        scan: Scan,
    ) -> Self {
        let matching = nav.params.localiser.travel_rule == TravelRule::ScanMatched;
        let match_params = MatchParams::default();
        let key = matching.then(|| {
            (
                Pose2::default(),
                0.0f64,
                MatchTarget::from_scan(&nav.geometry, &scan, &match_params),
            )
        });
        Self {
            kind,
            origin,
            limit_m,
            step_m: nav.params.tracking.step_m,
            stop_at_side: matches!(kind, LegKind::ToB { .. }),
            tracker: landmark.map(|l| Tracker::new(l, nav.track_params)),
            ob0: landmark.map(|l| l.range_m * l.bearing_rad.cos()),
            round: landmark
                .filter(|_| nav.params.tracking.round_centre)
                .map(|l| RoundTrack::new(&nav.geometry, l, &scan)),
            match_params,
            key,
            commanded_m: 0.0,
            fix: None,
            edge_fix: None,
            laser_measured: false,
            last_scan: scan,
            watch: None,
        }
    }

    /// The travel measured so far: the last landmark fix plus the commands since.
    pub(crate) fn measured_m(&self) -> f64 {
        self.fix
            .map_or(self.commanded_m, |(m, c)| m + self.commanded_m - c)
    }

    /// How far the landmark's edge is still ahead on a leg to B, metres.
    fn to_b_m(&self) -> Option<f64> {
        let ob = self.ob0.filter(|_| self.stop_at_side)?;
        let travel = self
            .edge_fix
            .map_or(self.commanded_m, |(m, c)| m + self.commanded_m - c);
        Some(ob - travel)
    }

    /// What is left of the leg as planned: to B when the landmark gives its distance (the
    /// drive stops there), else to the limit, metres.
    pub(crate) fn remaining_m(&self) -> f64 {
        let to_limit = self.limit_m - self.commanded_m;
        self.to_b_m().map_or(to_limit, |b| b.min(to_limit))
    }

    /// The next step to command, or `None` when the drive is over.
    pub(crate) fn next_step_m(&self) -> Option<f64> {
        let (limit, commanded) = (self.limit_m, self.commanded_m);
        // Written so that a NaN limit also ends the drive.
        if commanded.partial_cmp(&(limit - 1e-6)) != Some(std::cmp::Ordering::Less) {
            return None;
        }
        // Aim the last step at B itself when the landmark gives its distance.
        let to_go = self.to_b_m().map_or(limit - commanded, |b| b.max(0.01));
        let step = self.step_m.min(to_go).min(limit - commanded);
        (step > 1e-6).then_some(step)
    }

    /// Takes the scan after a step; false when the drive stops here (B reached, or the
    /// landmark of a leg to B lost).
    pub(crate) fn scanned(&mut self, nav: &Navigator, scan: &Scan) -> bool {
        self.last_scan = scan.clone();
        let update = self
            .tracker
            .as_mut()
            .map(|t| t.update(&nav.geometry, scan, self.commanded_m));
        match update {
            Some(TrackUpdate::Tracked(l)) => {
                let edge = self.ob0.unwrap_or(0.0) - l.range_m * l.bearing_rad.cos();
                self.edge_fix = Some((edge, self.commanded_m));
                let centre = self
                    .round
                    .as_mut()
                    .map_or(Centre::Unknown, |r| r.travel(&nav.geometry, scan, &l));
                let measured = match centre {
                    Centre::Unknown => Some(edge),
                    Centre::Missed => None,
                    Centre::Travel(m) => Some(m),
                };
                if let Some(m) = measured {
                    self.fix = Some((m, self.commanded_m));
                }
                let side = SIDE_RAD - 0.5 * nav.geometry.increment_rad.abs();
                if self.stop_at_side && l.bearing_rad.abs() >= side {
                    return false;
                }
            }
            Some(TrackUpdate::Lost) => {
                tracing::debug!(commanded = self.commanded_m, "landmark lost while driving");
                if self.stop_at_side {
                    return false;
                }
                self.tracker = None;
            }
            Some(TrackUpdate::Predicted(_)) | None => {}
        }
        // A new reference scan every `keyframe_m` while scan matching.
        let measured = self.measured_m();
        if let Some((pose, at, target)) = self.key.as_mut()
            && measured - *at >= nav.params.localiser.keyframe_m
        {
            (*pose, _) = matched(nav, target, pose, measured - *at, scan, &self.match_params);
            *at = measured;
            *target = MatchTarget::from_scan(&nav.geometry, scan, &self.match_params);
        }
        true
    }

    /// The pose reached relative to the start of the drive: the travel measured from the
    /// landmark (the commands when nothing was tracked), refined by scan matching under
    /// [`TravelRule::ScanMatched`].
    pub(crate) fn travelled(&mut self, nav: &Navigator) -> Pose2 {
        let measured = self.measured_m();
        match self.key.as_mut() {
            Some((pose, at, target)) => {
                let scan = &self.last_scan;
                let (mut rel, mut sigma) =
                    matched(nav, target, pose, measured - *at, scan, &self.match_params);
                // A landmark whose travel strays far from the commands may be a feature that
                // moves with the robot (where a wall leaves the range or the view): it stands
                // only when the scans pin that travel down; else the commands seed the match.
                let gap = self.commanded_m - measured;
                let confirm = nav.params.localiser.stray_landmark_max_sigma_m;
                if confirm > 0.0
                    && gap.abs() > STRAY_M.max(STRAY_SHARE * self.commanded_m)
                    && sigma.is_none_or(|s| s > confirm)
                {
                    let (r, s) = matched(
                        nav,
                        target,
                        pose,
                        measured - *at + gap,
                        scan,
                        &self.match_params,
                    );
                    tracing::debug!(
                        landmark_m = measured,
                        commanded_m = self.commanded_m,
                        "the landmark's travel strays from the commands and the scans do not confirm it"
                    );
                    (rel, sigma) = (r, s);
                }
                self.laser_measured = sigma.is_some_and(|s| s <= CONSTRAINED_SIGMA_M);
                rel
            }
            None => {
                self.laser_measured = false;
                Pose2::new(measured, 0.0, 0.0)
            }
        }
    }
}

/// A round landmark's object: the start's landmark and scan, and once a scan shows the object
/// round, its radius and the centre's distance ahead at the start.
struct RoundTrack {
    start: Landmark,
    start_scan: Scan,
    radius_m: Option<f64>,
    ob_m: Option<f64>,
    /// The start scan's hits do not fit the circle: the edge it is, for this leg.
    failed: bool,
    params: RoundParams,
}

/// What one scan says of the travel on a round landmark's centre.
enum Centre {
    /// Not known round: measure on the edge.
    Unknown,
    /// Known round, but this scan's hits do not fit it: no fix from this scan.
    Missed,
    /// The travel measured on the centre, metres.
    Travel(f64),
}

impl RoundTrack {
    fn new(geometry: &ScanGeometry, start: Landmark, scan: &Scan) -> Self {
        let params = RoundParams::default();
        let circle = round_object(geometry, scan, &start, &params);
        circle.iter().for_each(log_round);
        Self {
            start,
            start_scan: scan.clone(),
            radius_m: circle.map(|c| c.radius_m),
            ob_m: circle.map(|c| c.centre.x_m()),
            failed: false,
            params,
        }
    }

    /// The travel measured on the centre of the object seen as `l` in `scan`.
    fn travel(&mut self, geometry: &ScanGeometry, scan: &Scan, l: &Landmark) -> Centre {
        if self.failed {
            return Centre::Unknown;
        }
        let radius = match self.radius_m {
            Some(r) => r,
            None => match round_object(geometry, scan, l, &self.params) {
                Some(c) => {
                    log_round(&c);
                    *self.radius_m.insert(c.radius_m)
                }
                None => return Centre::Unknown,
            },
        };
        let ob = match self.ob_m {
            Some(ob) => ob,
            None => {
                match round_centre(
                    geometry,
                    &self.start_scan,
                    &self.start,
                    radius,
                    &self.params,
                ) {
                    Some(c) => *self.ob_m.insert(c.centre.x_m()),
                    None => {
                        self.failed = true;
                        return Centre::Unknown;
                    }
                }
            }
        };
        match round_centre(geometry, scan, l, radius, &self.params) {
            Some(c) => {
                let edge = self.start.range_m * self.start.bearing_rad.cos()
                    - l.range_m * l.bearing_rad.cos();
                tracing::trace!(
                    centre_m = ob - c.centre.x_m(),
                    edge_m = edge,
                    "travel on a round object's centre"
                );
                Centre::Travel(ob - c.centre.x_m())
            }
            None => Centre::Missed,
        }
    }
}

fn log_round(c: &Circle) {
    tracing::debug!(
        radius_m = c.radius_m,
        rms_m = c.rms_m,
        points = c.points,
        "landmark on a round object"
    );
}

/// The pose of `scan` relative to the start of the drive: matched against `target` (the
/// reference scan taken at `key`), starting from `key` advanced by `ahead_m` and from shares
/// of it (the base may have stalled or slipped); the guess itself when no match succeeds.
/// With it, how well the match's data pin the position in the worst direction (one standard
/// deviation, metres; `None` without a match).
fn matched(
    nav: &Navigator,
    target: &mut MatchTarget,
    key: &Pose2,
    ahead_m: f64,
    scan: &Scan,
    params: &MatchParams,
) -> (Pose2, Option<f64>) {
    let guess = Pose2::new(ahead_m, 0.0, 0.0);
    // The guess is as good as the drive: its error grows with the distance.
    let l = &nav.params.localiser;
    let prior = MatchParams {
        prior_sigma_m: l.match_prior_m + l.match_prior_per_m * ahead_m.abs(),
        prior_sigma_rad: l.drive_turn_sigma_deg.to_radians(),
        ..*params
    };
    let mut best = target.align(&nav.geometry, scan, guess, &prior);
    // The laser does not confirm the commands when the match, pulled toward them by the
    // prior, still lands several prior sigmas away, fails, or leaves the travel to the prior
    // (a base that did not move sees its front wall a leg away from where the command puts it:
    // only the side walls pair).
    let disagrees = best.as_ref().is_none_or(|m| {
        (m.pose.x_m - ahead_m).abs() > DISAGREE_SIGMAS * prior.prior_sigma_m
            || m.data_worst_sigma_m > CONSTRAINED_SIGMA_M
    });
    if ahead_m.abs() >= PARTIAL_MIN_M && disagrees {
        let hits = scan.robot_hits(&nav.geometry).count();
        // The commands do not explain the scan: try partial travel, a hypothesis of the
        // laser's, without pull toward the commanded distance (the heading keeps its prior:
        // the base drives straight however far it got).
        let loose = MatchParams {
            prior_sigma_m: ahead_m.abs(),
            ..prior
        };
        for share in PARTIAL_SHARES {
            let seed = Pose2::new(share * ahead_m, 0.0, 0.0);
            if let Some(m) = target.align(&nav.geometry, scan, seed, &loose)
                && (best.is_some() || m.pairs as f64 >= ALONE_SHARE * hits as f64)
                && fits_better(&m, best.as_ref(), l.partial_travel_max_sigma_m)
            {
                best = Some(m);
            }
        }
    }
    // The base drives straight: a match that turned the robot more than the base can while
    // driving paired the wrong points (a lone post or a short wall seen from a new angle).
    let max_turn = l.drive_max_turn_deg.to_radians();
    if let Some(m) = best.as_ref()
        && m.pose.theta_rad.abs() > max_turn
    {
        tracing::debug!(
            ahead_m,
            dth_deg = m.pose.theta_rad.to_degrees(),
            "scan match turned the robot on a straight drive; refused"
        );
        best = None;
    }
    match best {
        Some(m) => {
            tracing::debug!(
                ahead_m,
                dx = m.pose.x_m - ahead_m,
                dy = m.pose.y_m,
                dth_deg = m.pose.theta_rad.to_degrees(),
                sig = m.worst_sigma_m,
                data_sig = m.data_worst_sigma_m,
                rms = m.rms_m,
                pairs = m.pairs,
                "scan match"
            );
            (key.compose(&m.pose), Some(m.data_worst_sigma_m))
        }
        None => {
            tracing::debug!(ahead_m, "scan match failed; keeping the landmark's travel");
            (key.compose(&guess), None)
        }
    }
}

/// True when match `m` explains the scan clearly better than `current`: more points paired
/// and no worse a fit, along a direction the data pin down to `max_sigma_m` (in a featureless
/// corridor every travel fits alike, and among a few posts another travel may fit by chance:
/// the commands stand).
fn fits_better(
    m: &localiser::ScanMatch,
    current: Option<&localiser::ScanMatch>,
    max_sigma_m: f64,
) -> bool {
    if m.data_worst_sigma_m > max_sigma_m {
        return false;
    }
    match current {
        None => true,
        Some(c) => {
            let moved = (m.pose.x_m - c.pose.x_m).hypot(m.pose.y_m - c.pose.y_m);
            moved > 0.02 && m.pairs as f64 >= 1.15 * c.pairs as f64 && m.rms_m <= 1.2 * c.rms_m
        }
    }
}
