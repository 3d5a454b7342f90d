//! Landmark statistics over the scans of a log: how many landmarks each scan holds, how many
//! are re-identified in the next scan, and how many are range-limit or dropout artefacts.
//!
//! Re-identification: a landmark of scan k is predicted in scan k+1 — moved by the relative
//! pose between the scans when the log has poses, left in place otherwise (the tracker's
//! prediction for no travel) — and counts as re-identified when scan k+1 has a feature of a
//! compatible side within the tracking gate of the prediction. A dropout is an edge whose
//! no-return gap is at most a given number of rays wide.

use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};

use crate::{
    DetectParams, Landmark, LandmarkKind, OpenSide, TrackParams, TrackUpdate, Tracker, detect,
};

/// Counts for one scan (or summed over a log).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LandmarkCounts {
    /// Scans counted.
    pub scans: usize,
    /// Landmarks found.
    pub found: usize,
    /// Found landmarks that have a next scan to be looked for in.
    pub followed: usize,
    /// Of those, re-identified in the next scan.
    pub reidentified: usize,
    /// Found landmarks that are max-range jumps (the paper's kind).
    pub max_range_jumps: usize,
    /// Found landmarks within the range-limit margin of the maximum range.
    pub range_limit: usize,
    /// Found edge landmarks whose no-return gap is a short dropout.
    pub dropout: usize,
    /// Of the dropout landmarks with a next scan, those re-identified in it.
    pub dropout_reidentified: usize,
    /// Dropout landmarks that have a next scan.
    pub dropout_followed: usize,
}

impl LandmarkCounts {
    /// Adds `o`'s counts to these.
    pub fn add(&mut self, o: &LandmarkCounts) {
        self.scans += o.scans;
        self.found += o.found;
        self.followed += o.followed;
        self.reidentified += o.reidentified;
        self.max_range_jumps += o.max_range_jumps;
        self.range_limit += o.range_limit;
        self.dropout += o.dropout;
        self.dropout_reidentified += o.dropout_reidentified;
        self.dropout_followed += o.dropout_followed;
    }

    /// Share of followed landmarks re-identified in the next scan.
    pub fn reid_rate(&self) -> f64 {
        self.reidentified as f64 / self.followed.max(1) as f64
    }
}

/// Width in rays of the no-return (max-range) run on the open side of an edge landmark.
fn gap_width(scan: &Scan, l: &Landmark) -> Option<usize> {
    let run = |step: isize| {
        let mut i = l.index as isize + step;
        let mut n = 0;
        while i >= 0 && (i as usize) < scan.len() && scan.status[i as usize] != RayStatus::Hit {
            if scan.status[i as usize] == RayStatus::MaxRange {
                n += 1;
            }
            i += step;
        }
        // A gap that runs off the end of the scan is not a dropout.
        (i >= 0 && (i as usize) < scan.len()).then_some(n)
    };
    match l.open_side? {
        OpenSide::Lower => run(-1),
        OpenSide::Higher => run(1),
        OpenSide::Both => run(-1).into_iter().chain(run(1)).min(),
    }
}

fn compatible(a: &Landmark, b: &Landmark) -> bool {
    match (a.open_side, b.open_side) {
        (Some(x), Some(y)) => x == y || x == OpenSide::Both || y == OpenSide::Both,
        _ => true,
    }
}

/// Counts the landmarks of `scan` and their re-identification in `next` (if any).
/// `poses` are the log's poses of the two scans, when it has them.
#[allow(clippy::too_many_arguments)]
pub fn count_scan(
    geometry: &ScanGeometry,
    scan: &Scan,
    next: Option<&Scan>,
    poses: Option<(Pose2, Pose2)>,
    detect_params: &DetectParams,
    track: &TrackParams,
    dropout_rays: usize,
) -> LandmarkCounts {
    let found = detect(geometry, scan, detect_params);
    let mut c = LandmarkCounts {
        scans: 1,
        found: found.len(),
        ..Default::default()
    };
    let is_dropout: Vec<bool> = found
        .iter()
        .map(|l| {
            l.kind == LandmarkKind::MaxRangeJump
                && gap_width(scan, l).is_some_and(|w| w <= dropout_rays)
        })
        .collect();
    for (l, &d) in found.iter().zip(&is_dropout) {
        c.max_range_jumps += usize::from(l.kind == LandmarkKind::MaxRangeJump);
        c.range_limit += usize::from(l.near_range_limit);
        c.dropout += usize::from(d);
    }
    let Some(next) = next else { return c };
    c.followed = found.len();
    c.dropout_followed = c.dropout;
    let candidates = detect(geometry, next, &track.detect.permissive());
    let rel = poses.map(|(a, b)| b.inverse().compose(&a));
    for (l, &d) in found.iter().zip(&is_dropout) {
        let ok = match rel {
            // The tracker itself, with no travel between the scans.
            None => matches!(
                Tracker::new(*l, *track).update(geometry, next, 0.0),
                TrackUpdate::Tracked(_)
            ),
            // The relative pose moves the prediction; then the tracker's gate and side rule.
            Some(rel) => {
                let q = rel.transform_point(l.robot_point());
                let q = scan_types::RobotPoint::new(q.x_m(), q.y_m());
                candidates
                    .iter()
                    .any(|m| compatible(l, m) && m.robot_point().distance_m(&q) <= track.gate_m)
            }
        };
        c.reidentified += usize::from(ok);
        c.dropout_reidentified += usize::from(ok && d);
    }
    c
}

/// Counts every scan of a log of `(scan, pose)` records against the next one; the poses (when
/// both scans of a pair have one) move the predictions.
pub fn count_log(
    geometry: &ScanGeometry,
    records: &[(Scan, Option<Pose2>)],
    detect_params: &DetectParams,
    track: &TrackParams,
    dropout_rays: usize,
) -> Vec<LandmarkCounts> {
    (0..records.len())
        .map(|k| {
            let (scan, pose) = &records[k];
            let next = records.get(k + 1);
            let poses = match (pose, next.and_then(|n| n.1)) {
                (Some(a), Some(b)) => Some((*a, b)),
                _ => None,
            };
            count_scan(
                geometry,
                scan,
                next.map(|n| &n.0),
                poses,
                detect_params,
                track,
                dropout_rays,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A wall 1 m ahead between -20 and +20 deg, nothing elsewhere: two max-range jumps.
    fn wall_scan(g: &ScanGeometry, shift_rays: isize) -> Scan {
        let r: Vec<f64> = (0..g.ray_count)
            .map(|i| {
                let b = g.bearing_rad(
                    (i as isize - shift_rays).clamp(0, g.ray_count as isize - 1) as usize
                );
                if b.abs() <= 20f64.to_radians() {
                    1.0 / b.cos()
                } else {
                    g.max_range_m
                }
            })
            .collect();
        Scan::from_ranges(g, &r, 0.0)
    }

    #[test]
    fn the_same_scan_reidentifies_every_landmark() {
        let g = ScanGeometry::paper();
        let s = wall_scan(&g, 0);
        let c = count_scan(
            &g,
            &s,
            Some(&s),
            None,
            &DetectParams::paper(),
            &TrackParams::paper(),
            3,
        );
        assert_eq!(c.found, 2);
        assert_eq!(c.max_range_jumps, 2);
        assert_eq!(
            (c.followed, c.reidentified, c.range_limit, c.dropout),
            (2, 2, 0, 0)
        );
    }

    #[test]
    fn an_occlusion_edge_is_not_counted_as_a_max_range_jump() {
        // A near wall at 1 m on the right half, a far one at 2 m on the left: every ray hits,
        // and the 1 m step between them is an occlusion edge, no max-range jump.
        let g = ScanGeometry::paper();
        let r: Vec<f64> = (0..g.ray_count)
            .map(|i| if i < g.ray_count / 2 { 1.0 } else { 2.0 })
            .collect();
        let s = Scan::from_ranges(&g, &r, 0.0);
        let c = count_scan(
            &g,
            &s,
            None,
            None,
            &DetectParams::default(),
            &TrackParams::default(),
            3,
        );
        assert!(c.found >= 1, "{c:?}");
        assert_eq!(c.max_range_jumps, 0, "{c:?}");
    }

    #[test]
    fn a_turn_known_from_poses_is_followed() {
        let g = ScanGeometry::paper();
        let s = wall_scan(&g, 0);
        // The robot turned by 30 rays: the wall appears shifted by -30 rays (to the right).
        let turn = 30.0 * g.increment_rad;
        let t = wall_scan(&g, -30);
        let p = TrackParams::default();
        let without = count_scan(&g, &s, Some(&t), None, &DetectParams::paper(), &p, 3);
        let with = count_scan(
            &g,
            &s,
            Some(&t),
            Some((Pose2::new(0.0, 0.0, 0.0), Pose2::new(0.0, 0.0, turn))),
            &DetectParams::paper(),
            &p,
            3,
        );
        assert_eq!(without.reidentified, 0);
        assert_eq!(with.reidentified, 2);
    }

    #[test]
    fn a_one_ray_hole_is_a_dropout() {
        let g = ScanGeometry::paper();
        let mut s = Scan::from_ranges(&g, &vec![1.0; g.ray_count], 0.0);
        s.ranges_m[300] = g.max_range_m;
        s.status[300] = RayStatus::MaxRange;
        let c = count_scan(
            &g,
            &s,
            None,
            None,
            &DetectParams::paper(),
            &TrackParams::paper(),
            3,
        );
        assert_eq!(c.found, 2);
        assert_eq!((c.dropout, c.followed), (2, 0));
    }
}
