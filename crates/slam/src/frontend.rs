//! The front end: each scan placed against a local submap of recent keyframes, by a narrow
//! then a wide correlative search around a constant-velocity prediction, refined by
//! point-to-line ICP.

use std::collections::{HashSet, VecDeque};
use std::hash::{BuildHasherDefault, Hasher};

use localiser::{MatchParams, MatchTarget, ScanMatch};
use nalgebra::{Matrix3, Vector3};
use scan_types::{Pose2, Scan, ScanGeometry, angle_diff_rad, floor_i64, normalize_angle_rad};
use serde::{Deserialize, Serialize};

use crate::correlative::{Window, search};
use crate::grid::ScoreGrid;
use crate::{SlamError, check};

/// Tuning of the [`FrontEnd`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct FrontEndParams {
    /// Cell size of the correlative search's likelihood field, metres.
    pub resolution_m: f64,
    /// Gaussian fall-off of the field around each submap point, metres.
    pub smoothing_m: f64,
    /// Half-width of the translation search around the prediction, metres.
    pub linear_window_m: f64,
    /// Half-width of the rotation search around the prediction, degrees.
    pub angular_window_deg: f64,
    /// Share of the last step's turn that the wide search's prediction repeats (subsampled
    /// logs turn in bursts: half the last turn is the safer centre for the window).
    pub rotation_prediction: f64,
    /// The pose ICP finds from the constant-velocity prediction is kept, without the wide
    /// search, when its field score reaches this (1, the default: never; the wide search
    /// places every scan) ...
    pub local_quality: f64,
    /// ... and it lies within this of the prediction, metres ...
    pub local_shift_m: f64,
    /// ... and turned at most this from it, degrees.
    pub local_turn_deg: f64,
    /// Half-width of a first, narrow correlative search around the prediction, metres (0:
    /// none): for the constant-velocity model when the last step moved at most half of it and
    /// turned at most half of `narrow_window_deg`, and for every [`FrontEnd::add_scan_near`]
    /// (never for [`FrontEnd::locate_near`], which searches its window alone); its pose is
    /// kept, without the wide search, unless it lies on the narrow window's edge ...
    pub narrow_window_m: f64,
    /// ... and the narrow search's half-width in rotation, degrees.
    pub narrow_window_deg: f64,
    /// Quality lost per square metre of the pose away from the prediction (keeps a corridor's
    /// scan where the motion puts it).
    pub translation_cost: f64,
    /// Quality lost per square radian away from the prediction.
    pub rotation_cost: f64,
    /// Max-pooled levels of the branch and bound (blocks of 2^depth cells at the top).
    pub depth: usize,
    /// A scan whose best pose scores below this (mean field value of its points, 0..1) is
    /// skipped.
    pub min_quality: f64,
    /// Fewest usable hits for a scan to be matched.
    pub min_points: usize,
    /// Hits nearer than this are not used, metres.
    pub min_range_m: f64,
    /// Hits farther than this are not used, metres.
    pub max_range_m: f64,
    /// Hits are thinned to one per cell of this size before the search, metres.
    pub voxel_m: f64,
    /// A placed scan becomes a keyframe of the submap when it is this far from the last one,
    /// metres ...
    pub keyframe_distance_m: f64,
    /// ... or turned this much from it, degrees.
    pub keyframe_angle_deg: f64,
    /// Keyframes in the submap.
    pub submap_keyframes: usize,
    /// Refine the correlative pose by point-to-line ICP against the submap's scans.
    pub refine: bool,
    /// A refinement that moves the correlative pose by more than this is refused, metres.
    pub max_refine_shift_m: f64,
    /// Neighbouring hits within this of each other lie on one surface for the refinement,
    /// metres.
    pub icp_surface_m: f64,
    /// ... or within this many ray spacings at their range (far hits of a wide scanner).
    pub icp_surface_spacings: f64,
    /// A hit's neighbours form a line for the refinement when their variance across it is at
    /// most this share of their variance along it (0..1; lower refuses the lines fitted
    /// around corners and round posts, and with them the short faces of door jambs).
    pub icp_line_scatter: f64,
    /// A refinement whose field score falls more than this below the correlative pose's is
    /// refused.
    pub max_refine_loss: f64,
    /// The refinement fits every this-many-th hit of the scan (1: all).
    pub icp_stride: usize,
    /// The refinement's submap keeps one point per square of this size and normal
    /// direction, the newest keyframe's (0: every point of every keyframe), metres.
    pub icp_target_voxel_m: f64,
    /// A motion prediction ([`FrontEnd::add_scan_near`]) and the refined pose are combined,
    /// each weighed by its information, so that the prediction holds the directions the scan
    /// leaves free (along a corridor); false keeps the laser's pose alone.
    pub fuse_prediction: bool,
    /// [`FrontEnd::locate_near`] also combines its answer with the prediction (under
    /// `fuse_prediction`); false answers the laser's pose alone.
    pub fuse_located: bool,
    /// The prediction's position standard deviation, metres ...
    pub prediction_sigma_m: f64,
    /// ... plus this share of the predicted step's length ...
    pub prediction_sigma_per_m: f64,
    /// ... and its heading standard deviation, degrees ...
    pub prediction_sigma_deg: f64,
    /// ... plus this share of the predicted step's turn.
    pub prediction_sigma_per_rad: f64,
}

impl Default for FrontEndParams {
    fn default() -> Self {
        Self {
            resolution_m: 0.1,
            smoothing_m: 0.2,
            linear_window_m: 1.6,
            angular_window_deg: 80.0,
            rotation_prediction: 0.5,
            local_quality: 1.0,
            local_shift_m: 0.1,
            local_turn_deg: 3.0,
            narrow_window_m: 0.3,
            narrow_window_deg: 10.0,
            translation_cost: 0.1,
            rotation_cost: 0.1,
            depth: 4,
            min_quality: 0.45,
            min_points: 20,
            min_range_m: 0.05,
            max_range_m: 49.9,
            voxel_m: 0.05,
            keyframe_distance_m: 0.3,
            keyframe_angle_deg: 10.0,
            submap_keyframes: 12,
            refine: true,
            max_refine_shift_m: 0.2,
            icp_surface_m: 0.3,
            icp_surface_spacings: 3.0,
            icp_line_scatter: 0.1,
            max_refine_loss: 0.05,
            icp_stride: 2,
            icp_target_voxel_m: 0.0,
            fuse_prediction: true,
            fuse_located: false,
            prediction_sigma_m: 0.002,
            prediction_sigma_per_m: 0.01,
            prediction_sigma_deg: 1.0,
            prediction_sigma_per_rad: 0.05,
        }
    }
}

impl FrontEndParams {
    /// Checks every value against its range; the error names the key.
    pub fn validate(&self) -> Result<(), SlamError> {
        let bad = check::invalid;
        check::each(
            &[
                ("resolution_m", self.resolution_m),
                ("smoothing_m", self.smoothing_m),
                ("max_range_m", self.max_range_m),
                ("voxel_m", self.voxel_m),
                ("max_refine_shift_m", self.max_refine_shift_m),
                ("prediction_sigma_m", self.prediction_sigma_m),
                ("prediction_sigma_deg", self.prediction_sigma_deg),
            ],
            check::positive,
            "must be a positive number",
        )?;
        check::each(
            &[
                ("linear_window_m", self.linear_window_m),
                ("angular_window_deg", self.angular_window_deg),
                ("min_range_m", self.min_range_m),
                ("keyframe_distance_m", self.keyframe_distance_m),
                ("keyframe_angle_deg", self.keyframe_angle_deg),
                ("translation_cost", self.translation_cost),
                ("rotation_cost", self.rotation_cost),
                ("icp_surface_spacings", self.icp_surface_spacings),
                ("local_shift_m", self.local_shift_m),
                ("local_turn_deg", self.local_turn_deg),
                ("narrow_window_m", self.narrow_window_m),
                ("narrow_window_deg", self.narrow_window_deg),
                ("icp_target_voxel_m", self.icp_target_voxel_m),
                ("prediction_sigma_per_m", self.prediction_sigma_per_m),
                ("prediction_sigma_per_rad", self.prediction_sigma_per_rad),
            ],
            |v| v.is_finite() && v >= 0.0,
            "must be a number >= 0",
        )?;
        check::each(
            &[
                ("min_quality", self.min_quality),
                ("local_quality", self.local_quality),
                ("rotation_prediction", self.rotation_prediction),
            ],
            |v| (0.0..=1.0).contains(&v),
            "must lie in 0..1",
        )?;
        if !(self.icp_line_scatter > 0.0 && self.icp_line_scatter <= 1.0) {
            return Err(bad(
                "icp_line_scatter",
                self.icp_line_scatter,
                "must lie in (0, 1]",
            ));
        }
        if self.resolution_m < 0.01 || self.linear_window_m / self.resolution_m > 1000.0 {
            return Err(bad(
                "resolution_m",
                self.resolution_m,
                "must be at least 0.01 and at least linear_window_m / 1000",
            ));
        }
        // The smoothing kernel spans 2.5 standard deviations a side, in cells.
        if self.smoothing_m > 20.0 * self.resolution_m {
            return Err(bad(
                "smoothing_m",
                self.smoothing_m,
                "must be at most 20 times resolution_m",
            ));
        }
        if self.min_range_m >= self.max_range_m {
            return Err(bad(
                "min_range_m",
                self.min_range_m,
                "must be below max_range_m",
            ));
        }
        if self.angular_window_deg > 180.0 {
            return Err(bad(
                "angular_window_deg",
                self.angular_window_deg,
                "must be at most 180",
            ));
        }
        if self.depth > 10 {
            return Err(bad("depth", self.depth as f64, "must be at most 10"));
        }
        if self.icp_target_voxel_m != 0.0 && self.icp_target_voxel_m < 0.001 {
            return Err(bad(
                "icp_target_voxel_m",
                self.icp_target_voxel_m,
                "must be 0 (off) or at least 0.001",
            ));
        }
        if self.icp_stride == 0 {
            return Err(bad("icp_stride", 0.0, "must be at least 1"));
        }
        if self.submap_keyframes == 0 {
            return Err(bad("submap_keyframes", 0.0, "must be at least 1"));
        }
        Ok(())
    }
}

/// The pose of least combined cost between a match at `pose` with the data's `information`
/// (x, y, heading) and a prediction of position and heading standard deviations `sigma_m` and
/// `sigma_rad`: the prediction holds what the data leave free. `pose` when no finite answer.
fn fuse(
    pose: Pose2,
    information: &[[f64; 3]; 3],
    predicted: Pose2,
    sigma_m: f64,
    sigma_rad: f64,
) -> Pose2 {
    let prior = Vector3::new(sigma_m.powi(-2), sigma_m.powi(-2), sigma_rad.powi(-2));
    let h = Matrix3::from_fn(|r, c| information[r][c]) + Matrix3::from_diagonal(&prior);
    let offset = Vector3::new(
        predicted.x_m - pose.x_m,
        predicted.y_m - pose.y_m,
        angle_diff_rad(predicted.theta_rad, pose.theta_rad),
    );
    // (H_data + H_prior) d = H_prior (prediction - pose).
    match h.lu().solve(&prior.component_mul(&offset)) {
        Some(d) if d.iter().all(|v| v.is_finite()) => Pose2::new(
            pose.x_m + d[0],
            pose.y_m + d[1],
            normalize_angle_rad(pose.theta_rad + d[2]),
        ),
        _ => pose,
    }
}

/// Where one scan was placed, or why it was not.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Placement {
    /// The scan's pose, in the frame of the first scan.
    Placed {
        /// The pose.
        pose: Pose2,
        /// The correlative score of the pose (mean field value of its points, 0..1).
        quality: f64,
        /// True when ICP refined the pose (false: the correlative pose, good to about a cell).
        refined: bool,
        /// How well the refinement's data alone pin the position in its worst direction
        /// (one standard deviation, metres; `None` when not refined): large along a lone
        /// wall or around a lone post, where the scan can slide.
        sigma_m: Option<f64>,
        /// True when the scan became a keyframe of the submap.
        keyframe: bool,
        /// True when the wide search placed it (false: the narrow search or ICP from the
        /// prediction).
        wide: bool,
    },
    /// The scan could not be placed and was left out.
    Skipped {
        /// Why.
        reason: SkipReason,
    },
}

/// Why a scan was not placed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SkipReason {
    /// Fewer usable hits than [`FrontEndParams::min_points`].
    TooFewHits {
        /// Usable hits.
        hits: usize,
    },
    /// No pose in the window scored [`FrontEndParams::min_quality`].
    NoMatch,
}

impl std::fmt::Display for SkipReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SkipReason::TooFewHits { hits } => write!(f, "only {hits} usable hits"),
            SkipReason::NoMatch => f.write_str("no pose in the window matched the submap"),
        }
    }
}

/// A scan kept in the submap.
#[derive(Debug, Clone)]
struct Keyframe {
    pose: Pose2,
    /// The refinement's reference points of the scan, in its own frame (fitted once).
    target: Option<MatchTarget>,
    /// Thinned hits, world frame.
    points: Vec<[f64; 2]>,
}

/// Laser-only pose tracking: feed scans in order, get their poses.
#[derive(Debug)]
pub struct FrontEnd {
    params: FrontEndParams,
    match_params: MatchParams,
    keyframes: VecDeque<Keyframe>,
    grid: Option<ScoreGrid>,
    target: MatchTarget,
    /// The last two placed poses (the older first).
    last: Option<Pose2>,
    before_last: Option<Pose2>,
}

impl FrontEnd {
    /// A front end whose first scan is placed at the origin.
    pub fn new(params: FrontEndParams) -> Result<Self, SlamError> {
        params.validate()?;
        let surface_m = params.icp_surface_m;
        let surface_spacings = params.icp_surface_spacings;
        let max_line_scatter = params.icp_line_scatter;
        let stride = params.icp_stride;
        Ok(Self {
            params,
            // Real scans with 1 deg rays: neighbouring hits of one wall lie far apart at range.
            match_params: MatchParams {
                max_rms_m: 0.05,
                surface_m,
                surface_spacings,
                normal_half_length_m: surface_m * 0.6,
                max_line_scatter,
                min_pairs: 30,
                stride,
                ..MatchParams::default()
            },
            keyframes: VecDeque::new(),
            grid: None,
            target: MatchTarget::new(),
            last: None,
            before_last: None,
        })
    }

    /// The parameters.
    pub fn params(&self) -> &FrontEndParams {
        &self.params
    }

    /// The refinement's ICP parameters.
    pub(crate) fn match_params(&self) -> &MatchParams {
        &self.match_params
    }

    /// Places the next scan (of `geometry`), predicted by the constant-velocity model.
    pub fn add_scan(&mut self, geometry: &ScanGeometry, scan: &Scan) -> Placement {
        self.add_scan_from(geometry, scan, None, true)
    }

    /// Places the next scan (of `geometry`) with the search centred on `prediction` (a pose
    /// from a motion model, e.g. the commands a robot gave since its last scan) instead of
    /// the constant-velocity model: the narrow window first, then the wide one; a refined pose
    /// is combined with the prediction ([`FrontEndParams::fuse_prediction`]). The first
    /// scan is placed at `prediction` itself, so that the poses are in the caller's frame.
    pub fn add_scan_near(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        prediction: Pose2,
    ) -> Placement {
        self.add_scan_from(geometry, scan, Some(prediction), true)
    }

    /// Where the scan would be placed with the search centred on `prediction` (combined with
    /// it only under [`FrontEndParams::fuse_located`]), without
    /// adding it: the caller decides the pose and adds the scan with [`FrontEnd::insert_at`]
    /// (an online user that refuses a placement keeps the submap in its own frame). Before
    /// the first insertion there is nothing to match: the answer is `prediction`, unrefined.
    pub fn locate_near(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        prediction: Pose2,
    ) -> Placement {
        self.add_scan_from(geometry, scan, Some(prediction), false)
    }

    /// Adds the scan at `pose` without matching it (a keyframe when it is the first, or far
    /// enough from the last keyframe); true when it became a keyframe.
    pub fn insert_at(&mut self, geometry: &ScanGeometry, scan: &Scan, pose: Pose2) -> bool {
        let points = thin_hits(geometry, scan, &self.params);
        if points.len() < self.params.min_points {
            return false;
        }
        let keyframe = self.grid.is_none() || self.is_keyframe(&pose);
        self.place(pose, geometry, scan, &points, keyframe);
        keyframe
    }

    fn add_scan_from(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        prediction: Option<Pose2>,
        commit: bool,
    ) -> Placement {
        let points = thin_hits(geometry, scan, &self.params);
        if points.len() < self.params.min_points {
            return Placement::Skipped {
                reason: SkipReason::TooFewHits { hits: points.len() },
            };
        }
        let (Some(last), true) = (self.last, self.grid.is_some()) else {
            let pose = prediction.unwrap_or_default();
            if commit {
                self.place(pose, geometry, scan, &points, true);
            }
            return Placement::Placed {
                pose,
                quality: 1.0,
                refined: false,
                sigma_m: None,
                keyframe: true,
                wide: false,
            };
        };
        // Constant velocity: the last step again.
        let step = self
            .before_last
            .map_or(Pose2::default(), |b| b.inverse().compose(&last));
        let guess = prediction.unwrap_or_else(|| last.compose(&step));
        // A placement that is kept is fused; `locate_near` answers the laser's pose unless
        // `fuse_located`.
        let fuse_with = prediction.filter(|_| commit || self.params.fuse_located);
        if let Some((m, quality)) = self.local(geometry, scan, &points, guess) {
            let pose = self.fused(&m, fuse_with);
            let keyframe = self.is_keyframe(&pose);
            if commit {
                self.place(pose, geometry, scan, &points, keyframe);
            }
            return Placement::Placed {
                pose,
                quality,
                refined: true,
                sigma_m: Some(m.data_worst_sigma_m),
                keyframe,
                wide: false,
            };
        }
        let p = &self.params;
        let grid = self
            .grid
            .as_ref()
            .expect("a submap exists once a scan is placed");
        let window = |linear_m: f64, angular_deg: f64| Window {
            linear_m,
            angular_rad: angular_deg.to_radians(),
            translation_cost: p.translation_cost,
            rotation_cost: p.rotation_cost,
        };
        // Fast scans: the best pose near the prediction, when it is not on the narrow
        // window's edge.
        let slow = step.x_m.hypot(step.y_m) <= 0.5 * p.narrow_window_m
            && step.theta_rad.abs() <= 0.5 * p.narrow_window_deg.to_radians();
        // For the constant-velocity model when the last step was slow, and for every motion
        // prediction of `add_scan_near`; `locate_near` keeps its caller's window alone.
        let narrow_first = if prediction.is_none() { slow } else { commit };
        let narrow = (narrow_first && p.narrow_window_m > 0.0 && p.narrow_window_deg > 0.0)
            .then(|| {
                let w = window(
                    p.narrow_window_m.min(p.linear_window_m),
                    p.narrow_window_deg.min(p.angular_window_deg),
                );
                search(grid, &points, &guess, &w, p.min_quality)
            })
            .flatten()
            .filter(|f| !f.on_edge);
        let wide = narrow.is_none();
        let found = match narrow {
            Some(f) => f,
            None => {
                let damped = Pose2::new(step.x_m, step.y_m, step.theta_rad * p.rotation_prediction);
                let centre = prediction.unwrap_or_else(|| last.compose(&damped));
                let w = window(p.linear_window_m, p.angular_window_deg);
                let Some(f) = search(grid, &points, &centre, &w, p.min_quality) else {
                    return Placement::Skipped {
                        reason: SkipReason::NoMatch,
                    };
                };
                f
            }
        };
        tracing::trace!(
            dx = found.pose.x_m - guess.x_m,
            dy = found.pose.y_m - guess.y_m,
            quality = found.quality,
            wide,
            "correlative placement"
        );
        let (pose, sigma_m) = match self.refine(geometry, scan, &points, found) {
            Some(m) => (self.fused(&m, fuse_with), Some(m.data_worst_sigma_m)),
            None => (found.pose, None),
        };
        let keyframe = self.is_keyframe(&pose);
        if commit {
            self.place(pose, geometry, scan, &points, keyframe);
        }
        Placement::Placed {
            pose,
            quality: found.quality,
            refined: sigma_m.is_some(),
            sigma_m,
            keyframe,
            wide,
        }
    }

    /// ICP from the prediction, and its field score, when that reaches `local_quality`.
    fn local(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        points: &[[f64; 2]],
        guess: Pose2,
    ) -> Option<(ScanMatch, f64)> {
        if !self.params.refine || self.params.local_quality >= 1.0 {
            return None;
        }
        let p = &self.params;
        // The prediction is close when scans come fast: a narrow first gate.
        let params = MatchParams {
            initial_gate_m: (2.0 * p.local_shift_m).max(self.match_params.final_gate_m),
            ..self.match_params
        };
        let m = self.target.align(geometry, scan, guess, &params)?;
        if m.pose.position().distance_m(&guess.position()) > p.local_shift_m
            || angle_diff_rad(m.pose.theta_rad, guess.theta_rad).abs()
                > p.local_turn_deg.to_radians()
        {
            return None;
        }
        let quality = crate::correlative::quality(self.grid.as_ref()?, points, &m.pose);
        tracing::trace!(quality, "local match");
        (quality >= self.params.local_quality).then_some((m, quality))
    }

    /// The correlative pose refined by ICP (`None`: no refinement, or one that moves too far
    /// or lowers the field score, is refused).
    fn refine(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        points: &[[f64; 2]],
        found: crate::correlative::Found,
    ) -> Option<ScanMatch> {
        let coarse = found.pose;
        if !self.params.refine {
            return None;
        }
        let shift = self.params.max_refine_shift_m;
        let m = self
            .target
            .align(geometry, scan, coarse, &self.match_params)
            .filter(|m| m.pose.position().distance_m(&coarse.position()) <= shift)?;
        let grid = self
            .grid
            .as_ref()
            .expect("a submap exists once a scan is placed");
        let refined_quality = crate::correlative::quality(grid, points, &m.pose);
        (refined_quality >= found.quality - self.params.max_refine_loss).then_some(m)
    }

    /// The refined pose combined with the motion `prediction`, each weighed by its information
    /// ([`FrontEndParams::fuse_prediction`]); the refined pose alone without a prediction.
    fn fused(&self, m: &ScanMatch, prediction: Option<Pose2>) -> Pose2 {
        let p = &self.params;
        let (Some(predicted), Some(last), true) = (prediction, self.last, p.fuse_prediction) else {
            return m.pose;
        };
        let step = last.inverse().compose(&predicted);
        let sigma_m = p.prediction_sigma_m + p.prediction_sigma_per_m * step.x_m.hypot(step.y_m);
        let sigma_rad =
            p.prediction_sigma_deg.to_radians() + p.prediction_sigma_per_rad * step.theta_rad.abs();
        fuse(m.pose, &m.data_information, predicted, sigma_m, sigma_rad)
    }

    fn is_keyframe(&self, pose: &Pose2) -> bool {
        self.keyframes.back().is_none_or(|k| {
            k.pose.position().distance_m(&pose.position()) >= self.params.keyframe_distance_m
                || angle_diff_rad(k.pose.theta_rad, pose.theta_rad).abs()
                    >= self.params.keyframe_angle_deg.to_radians()
        })
    }

    /// Records the placed pose; a keyframe enters the submap, which is then rebuilt.
    fn place(
        &mut self,
        pose: Pose2,
        geometry: &ScanGeometry,
        scan: &Scan,
        points: &[[f64; 2]],
        keyframe: bool,
    ) {
        self.before_last = self.last;
        self.last = Some(pose);
        if !keyframe {
            return;
        }
        let (s, c) = pose.theta_rad.sin_cos();
        let world = points
            .iter()
            .map(|p| {
                [
                    pose.x_m + c * p[0] - s * p[1],
                    pose.y_m + s * p[0] + c * p[1],
                ]
            })
            .collect();
        let target = self
            .params
            .refine
            .then(|| MatchTarget::from_scan(geometry, scan, &self.match_params));
        self.keyframes.push_back(Keyframe {
            pose,
            target,
            points: world,
        });
        while self.keyframes.len() > self.params.submap_keyframes {
            self.keyframes.pop_front();
        }
        let mut all = Vec::with_capacity(self.keyframes.iter().map(|k| k.points.len()).sum());
        for k in &self.keyframes {
            all.extend_from_slice(&k.points);
        }
        let p = &self.params;
        let window_cells = (p.linear_window_m / p.resolution_m).ceil() as usize + 1;
        self.grid = ScoreGrid::new(&all, p.resolution_m, p.smoothing_m, p.depth, window_cells);
        if p.refine {
            self.target = MatchTarget::new();
            self.target.reserve(
                self.keyframes
                    .iter()
                    .filter_map(|k| k.target.as_ref().map(MatchTarget::len))
                    .sum(),
            );
            for k in self.keyframes.iter().rev() {
                if let Some(t) = &k.target {
                    self.target.add_target(&k.pose, t);
                }
            }
            self.target.thin(p.icp_target_voxel_m);
        }
    }
}

/// The scan's hits within the range limits, robot frame, one per `voxel_m` cell (the first).
pub(crate) fn thin_hits(
    geometry: &ScanGeometry,
    scan: &Scan,
    params: &FrontEndParams,
) -> Vec<[f64; 2]> {
    let mut out: Vec<[f64; 2]> = Vec::new();
    let mut seen = HashSet::with_hasher(BuildHasherDefault::<VoxelHasher>::default());
    for (_, p) in scan.robot_hits(geometry) {
        let r = p.range_m();
        if !(r >= params.min_range_m && r <= params.max_range_m) {
            continue;
        }
        let key = (
            floor_i64(p.x_m() / params.voxel_m),
            floor_i64(p.y_m() / params.voxel_m),
        );
        if seen.insert(key) {
            out.push([p.x_m(), p.y_m()]);
        }
    }
    out
}

/// Hashes voxel keys (small integers, no adversary) by a multiply-rotate mix: cheaper than
/// the default SipHash.
#[derive(Default)]
struct VoxelHasher(u64);

impl Hasher for VoxelHasher {
    fn finish(&self) -> u64 {
        self.0
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(u64::from(b));
        }
    }

    fn write_u64(&mut self, v: u64) {
        self.0 = (self.0.rotate_left(29) ^ v).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    }

    fn write_i64(&mut self, v: i64) {
        self.write_u64(v as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_prediction_holds_the_direction_the_scan_leaves_free() {
        // A corridor along x: the data pin y and the heading (1e6 each), leave x free.
        let info = [[0.0, 0.0, 0.0], [0.0, 1e6, 0.0], [0.0, 0.0, 1e6]];
        let matched = Pose2::new(1.0, 0.0, 0.0);
        let predicted = Pose2::new(1.2, 0.05, 0.01);
        // Prior information 1 / 0.01^2 = 1e4 on each axis.
        let f = fuse(matched, &info, predicted, 0.01, 0.01);
        // x: no data, the prediction's 1.2; y and heading: 1e4 / (1e6 + 1e4) of the offset.
        assert!((f.x_m - 1.2).abs() < 1e-12, "{f:?}");
        assert!((f.y_m - 0.05 * 1e4 / 1.01e6).abs() < 1e-12, "{f:?}");
        assert!((f.theta_rad - 0.01 * 1e4 / 1.01e6).abs() < 1e-12, "{f:?}");
        // Coupled data: x and y tied (a wall along the diagonal pins x - y only).
        let diag = [[1e6, -1e6, 0.0], [-1e6, 1e6, 0.0], [0.0, 0.0, 1e6]];
        let f = fuse(
            Pose2::default(),
            &diag,
            Pose2::new(0.1, 0.1, 0.0),
            0.01,
            0.01,
        );
        // The offset (0.1, 0.1) lies along the free direction (1, 1): taken whole.
        assert!(
            (f.x_m - 0.1).abs() < 1e-9 && (f.y_m - 0.1).abs() < 1e-9,
            "{f:?}"
        );
        // A non-finite prediction leaves the match's pose.
        let f = fuse(matched, &info, Pose2::new(f64::NAN, 0.0, 0.0), 0.01, 0.01);
        assert_eq!(f, matched);
    }

    /// A 6 m x 4 m room with a box (every direction pinned), scans ray-cast at the truth: the
    /// second scan 0.05 m on, its prediction 0.02 m further along x. The refinement alone
    /// lands on the truth; fused, the pose moves toward the prediction by the prior's small
    /// share, strictly between the two; `locate_near` fuses only under `fuse_located`.
    #[test]
    fn add_scan_near_fuses_and_locate_near_only_when_asked() {
        use scan_types::testkit::{boxed, scan_at};
        let mut walls = boxed(-3.0, -2.0, 3.0, 2.0);
        walls.extend(boxed(1.0, 0.5, 1.6, 1.1));
        let g = ScanGeometry::centred(541, 270f64.to_radians(), 0.1, 20.0).unwrap();
        let first = scan_at(&g, &walls, 0.0, 0.0, 0.0);
        let second = scan_at(&g, &walls, 0.05, 0.0, 0.0);
        let predicted = Pose2::new(0.07, 0.0, 0.0);
        let place_with = |fuse_prediction: bool, fuse_located: bool, locate: bool| {
            let mut fe = FrontEnd::new(FrontEndParams {
                fuse_prediction,
                fuse_located,
                ..FrontEndParams::default()
            })
            .unwrap();
            fe.add_scan_near(&g, &first, Pose2::default());
            let placed = if locate {
                fe.locate_near(&g, &second, predicted)
            } else {
                fe.add_scan_near(&g, &second, predicted)
            };
            match placed {
                Placement::Placed {
                    pose,
                    refined: true,
                    ..
                } => pose,
                other => panic!("{other:?}"),
            }
        };
        let place =
            |fuse_prediction: bool, locate: bool| place_with(fuse_prediction, false, locate);
        let plain = place(false, false);
        assert!(
            (plain.x_m - 0.05).abs() < 0.005 && plain.y_m.abs() < 0.005,
            "{plain:?}"
        );
        // `locate_near` searches its window alone (no narrow search): fused or not, the same.
        let located = place(true, true);
        assert_eq!(located, place(false, true));
        assert!(
            located.position().distance_m(&plain.position()) < 0.001,
            "{located:?}"
        );
        let fused = place(true, false);
        assert!(
            fused.x_m > plain.x_m && fused.x_m < predicted.x_m,
            "{fused:?} {plain:?}"
        );
        // Under `fuse_located` the located pose moves toward the prediction as well.
        let located_fused = place_with(true, true, true);
        assert!(
            located_fused.x_m > located.x_m + 1e-4 && located_fused.x_m < predicted.x_m,
            "{located_fused:?} {located:?}"
        );
    }

    /// Round posts and square pillars, no noise, placed online as the navigator does: the
    /// search centred on the last estimate moved by the exact step, the answer combined with
    /// it, the scan inserted where the estimate puts it. Any drift of the estimate is the
    /// matcher's own. With the offline line criterion (0.1) lines fitted around the posts'
    /// arcs and the pillars' corners pull every placement ahead; with 0.03 they are refused.
    #[test]
    fn a_strict_line_criterion_stops_the_lean_along_the_motion() {
        use scan_types::testkit::{Seg, boxed, scan_at};
        let mut world: Vec<Seg> = Vec::new();
        for (cx, cy) in [(1.0, 1.5), (2.5, -1.2), (4.0, 1.8), (5.5, -1.5), (7.0, 1.3)] {
            // A post of radius 0.15 m as a 64-gon.
            let at = |k: usize| {
                let a = std::f64::consts::TAU * k as f64 / 64.0;
                (cx + 0.15 * a.cos(), cy + 0.15 * a.sin())
            };
            world.extend((0..64).map(|k| (at(k), at(k + 1))));
        }
        for (x, y) in [(1.8, -1.8), (4.7, 2.0), (7.8, -1.9)] {
            world.extend(boxed(x, y, x + 0.4, y + 0.3));
        }
        let g = ScanGeometry::paper();
        let step = 0.25;
        let drift = |icp_line_scatter: f64| {
            // The navigator's online settings (`[localiser] slam_*`).
            let mut fe = FrontEnd::new(FrontEndParams {
                icp_line_scatter,
                linear_window_m: 0.3,
                angular_window_deg: 8.0,
                resolution_m: 0.05,
                keyframe_distance_m: 0.5,
                submap_keyframes: 60,
                fuse_located: true,
                ..FrontEndParams::default()
            })
            .unwrap();
            let mut estimate = Pose2::default();
            for k in 0..40 {
                let scan = scan_at(&g, &world, step * k as f64, 0.0, 0.0);
                if k > 0 {
                    estimate = estimate.compose(&Pose2::new(step, 0.0, 0.0));
                    if let Placement::Placed {
                        pose,
                        refined: true,
                        ..
                    } = fe.locate_near(&g, &scan, estimate)
                    {
                        estimate = pose;
                    }
                }
                fe.insert_at(&g, &scan, estimate);
            }
            estimate.x_m - step * 39.0
        };
        let (strict, lenient) = (drift(0.03), drift(0.1));
        assert!(strict.abs() < 0.005, "0.03: {strict} m after 9.75 m");
        assert!(lenient > 0.02, "0.1: {lenient} m after 9.75 m");
    }

    #[test]
    fn out_of_range_values_are_refused_by_name() {
        let with = |voxel: f64| {
            FrontEndParams {
                icp_target_voxel_m: voxel,
                ..FrontEndParams::default()
            }
            .validate()
        };
        assert!(with(0.0).is_ok());
        assert!(with(0.02).is_ok());
        for bad in [-0.01, 1e-310, 0.0005, f64::NAN, f64::INFINITY] {
            let e = with(bad).expect_err("refused").to_string();
            assert!(e.contains("icp_target_voxel_m"), "{bad}: {e}");
        }
        // A smoothing of 100 m on 0.1 m cells would ask for a kernel of 5 000 x 5 000 cells
        // per scan; a hit window that is empty, for nothing.
        for (params, key) in [
            (
                FrontEndParams {
                    smoothing_m: 100.0,
                    ..FrontEndParams::default()
                },
                "smoothing_m",
            ),
            (
                FrontEndParams {
                    min_range_m: 60.0,
                    ..FrontEndParams::default()
                },
                "min_range_m",
            ),
        ] {
            let e = params.validate().expect_err("refused").to_string();
            assert!(e.contains(key), "{e}");
        }
        let stride = FrontEndParams {
            icp_stride: 0,
            ..FrontEndParams::default()
        };
        assert!(
            stride
                .validate()
                .unwrap_err()
                .to_string()
                .contains("icp_stride")
        );
        let sigmas = |v: [f64; 4]| {
            FrontEndParams {
                prediction_sigma_m: v[0],
                prediction_sigma_per_m: v[1],
                prediction_sigma_deg: v[2],
                prediction_sigma_per_rad: v[3],
                ..FrontEndParams::default()
            }
            .validate()
        };
        assert!(sigmas([0.002, 0.0, 1.0, 0.0]).is_ok());
        for bad in [0.0, -0.1, 1.5, f64::NAN] {
            let e = FrontEndParams {
                icp_line_scatter: bad,
                ..FrontEndParams::default()
            }
            .validate()
            .expect_err("refused")
            .to_string();
            assert!(e.contains("icp_line_scatter"), "{bad}: {e}");
        }
        for (v, key) in [
            ([0.0, 0.01, 1.0, 0.05], "prediction_sigma_m"),
            ([f64::NAN, 0.01, 1.0, 0.05], "prediction_sigma_m"),
            ([0.002, -0.1, 1.0, 0.05], "prediction_sigma_per_m"),
            ([0.002, f64::INFINITY, 1.0, 0.05], "prediction_sigma_per_m"),
            ([0.002, 0.01, 0.0, 0.05], "prediction_sigma_deg"),
            ([0.002, 0.01, 1.0, -1.0], "prediction_sigma_per_rad"),
        ] {
            let e = sigmas(v).expect_err("refused").to_string();
            assert!(e.contains(key), "{v:?}: {e}");
        }
    }
}
