//! The point map: hit points of the scans taken at localised poses, in the world frame.

use std::fmt::Write as _;
use std::path::Path;

use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};

use crate::{LocaliserError, io::write_atomic};

/// The hit points of one localised scan.
#[derive(Debug, Clone, PartialEq)]
pub struct MapScan {
    /// The pose the scan was taken at.
    pub pose: Pose2,
    /// Its hit points in the world frame.
    pub points: Vec<WorldPoint>,
}

/// World hit points, one group per localised scan (one per leg).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointMap {
    scans: Vec<MapScan>,
}

impl PointMap {
    /// An empty map.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the hits of `scan` seen from `pose` (max-range and error rays add nothing).
    pub fn add_scan(&mut self, pose: &Pose2, geometry: &ScanGeometry, scan: &Scan) {
        let points = scan.world_hits(geometry, pose).map(|(_, p)| p).collect();
        self.scans.push(MapScan {
            pose: *pose,
            points,
        });
    }

    /// The scans in the order they were added.
    pub fn scans(&self) -> &[MapScan] {
        &self.scans
    }

    /// Every point of every scan.
    pub fn points(&self) -> impl Iterator<Item = WorldPoint> + '_ {
        self.scans.iter().flat_map(|s| s.points.iter().copied())
    }

    /// Number of scans.
    pub fn len(&self) -> usize {
        self.scans.len()
    }

    /// True when no scan was added.
    pub fn is_empty(&self) -> bool {
        self.scans.is_empty()
    }

    /// Writes `scan,x_m,y_m` CSV (one line per point, with a header), atomically.
    pub fn write_csv(&self, path: &Path) -> Result<(), LocaliserError> {
        let mut s = String::from("scan,x_m,y_m\n");
        for (k, scan) in self.scans.iter().enumerate() {
            for p in &scan.points {
                let _ = writeln!(s, "{k},{:.4},{:.4}", p.x_m(), p.y_m());
            }
        }
        write_atomic(path, s.as_bytes())
    }
}
