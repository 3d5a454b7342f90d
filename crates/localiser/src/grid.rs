//! A log-odds occupancy grid that grows to fit, exported as a ROS map_server map and PNG.

use std::path::{Path, PathBuf};

use image::{ExtendedColorType, ImageEncoder};
use scan_types::{Pose2, RayStatus, RobotPoint, Scan, ScanGeometry, WorldPoint};

use crate::{LocaliserError, io::write_atomic};

/// What a cell is believed to hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CellState {
    /// Never observed, or evidence balanced.
    Unknown,
    /// Seen through.
    Free,
    /// Seen hit.
    Occupied,
}

/// Log-odds increments and thresholds of the grid.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GridParams {
    /// Cell side, metres.
    pub resolution_m: f64,
    /// Added to the cell a ray ends in with a hit (log-odds of p = 0.7).
    pub hit_log_odds: f32,
    /// Added to each cell a ray passes through (log-odds of p = 0.4, negative).
    pub free_log_odds: f32,
    /// Cells are clamped to +- this.
    pub clamp_log_odds: f32,
    /// A cell at or above this is occupied.
    pub occupied_log_odds: f32,
    /// A cell at or below this is free.
    pub free_threshold_log_odds: f32,
    /// The grid never grows wider or taller than this, metres: a scan that would need more
    /// (a wild pose or range) is skipped.
    pub max_extent_m: f64,
    /// The grid never holds more cells than this (memory: 4 bytes a cell): a scan that would
    /// need more is skipped.
    pub max_cells: usize,
}

impl GridParams {
    /// Defaults for a cell side of `resolution_m`.
    pub fn with_resolution(resolution_m: f64) -> Self {
        Self {
            resolution_m,
            hit_log_odds: 0.85,
            free_log_odds: -0.4,
            clamp_log_odds: 5.0,
            occupied_log_odds: 0.4,
            free_threshold_log_odds: -0.4,
            max_extent_m: 2000.0,
            max_cells: 1 << 25,
        }
    }
}

/// Pixel values of the map_server export (Nav2 trinary convention).
pub mod pixel {
    /// An occupied cell (dark).
    pub const OCCUPIED: u8 = 0;
    /// A free cell (light).
    pub const FREE: u8 = 254;
    /// An unknown cell.
    pub const UNKNOWN: u8 = 205;
}

/// The two files of a map_server map.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct MapServerFiles {
    /// The P5 PGM image.
    pub pgm: PathBuf,
    /// The YAML description.
    pub yaml: PathBuf,
}

/// A log-odds occupancy grid in the world frame that grows to fit what it integrates.
///
/// ```
/// use localiser::OccupancyGrid;
/// use scan_types::{Pose2, Scan, ScanGeometry, WorldPoint};
/// // One ray straight ahead hitting at 1 m.
/// let g = ScanGeometry::new(0.0, 0.01, 1, 0.0, 4.0).unwrap();
/// let mut grid = OccupancyGrid::new(0.1);
/// grid.integrate(&Pose2::new(0.0, 0.0, 0.0), &g, &Scan::from_ranges(&g, &[1.0], 0.0));
/// assert!(grid.is_occupied(WorldPoint::new(1.0, 0.02)));
/// assert!(grid.is_free(WorldPoint::new(0.5, 0.02)));
/// assert!(!grid.is_occupied(WorldPoint::new(2.0, 0.02)));
/// ```
#[derive(Debug, Clone, PartialEq)]
pub struct OccupancyGrid {
    params: GridParams,
    /// Global cell index (floor(x / res)) of column 0.
    col0: i64,
    /// Global cell index (floor(y / res)) of row 0 (the bottom row).
    row0: i64,
    width: usize,
    height: usize,
    cells: Vec<f32>,
}

impl OccupancyGrid {
    /// An empty grid with cells of `resolution_m` (non-finite or non-positive: 0.05 m).
    pub fn new(resolution_m: f64) -> Self {
        let r = if resolution_m.is_finite() && resolution_m > 0.0 {
            resolution_m
        } else {
            0.05
        };
        Self::with_params(GridParams::with_resolution(r))
    }

    /// An empty grid with explicit parameters.
    pub fn with_params(params: GridParams) -> Self {
        Self {
            params,
            col0: 0,
            row0: 0,
            width: 0,
            height: 0,
            cells: Vec::new(),
        }
    }

    /// The parameters.
    pub fn params(&self) -> &GridParams {
        &self.params
    }

    /// Cell side, metres.
    pub fn resolution_m(&self) -> f64 {
        self.params.resolution_m
    }

    /// Columns (x).
    pub fn width(&self) -> usize {
        self.width
    }

    /// Rows (y).
    pub fn height(&self) -> usize {
        self.height
    }

    /// World position of the lower-left corner of cell (0, 0).
    pub fn origin(&self) -> WorldPoint {
        let r = self.params.resolution_m;
        WorldPoint::new(self.col0 as f64 * r, self.row0 as f64 * r)
    }

    /// World centre of cell (`col`, `row`), row 0 at the bottom.
    pub fn cell_centre(&self, col: usize, row: usize) -> WorldPoint {
        let r = self.params.resolution_m;
        WorldPoint::new(
            (self.col0 + col as i64) as f64 * r + 0.5 * r,
            (self.row0 + row as i64) as f64 * r + 0.5 * r,
        )
    }

    /// Global cell index of a world point.
    fn global(&self, p: WorldPoint) -> (i64, i64) {
        let r = self.params.resolution_m;
        (floor_i64(p.x_m() / r), floor_i64(p.y_m() / r))
    }

    /// (col, row) of the cell holding `p`, if inside the grid.
    pub fn cell_of(&self, p: WorldPoint) -> Option<(usize, usize)> {
        if !(p.x_m().is_finite() && p.y_m().is_finite()) {
            return None;
        }
        let (gx, gy) = self.global(p);
        let (c, r) = (gx - self.col0, gy - self.row0);
        (c >= 0 && r >= 0 && (c as usize) < self.width && (r as usize) < self.height)
            .then_some((c as usize, r as usize))
    }

    /// Log-odds of cell (`col`, `row`); 0 outside.
    pub fn log_odds(&self, col: usize, row: usize) -> f32 {
        if col < self.width && row < self.height {
            self.cells[row * self.width + col]
        } else {
            0.0
        }
    }

    /// Occupancy probability at `p` (0.5 where unknown or outside).
    pub fn probability(&self, p: WorldPoint) -> f64 {
        let l = self.cell_of(p).map_or(0.0, |(c, r)| self.log_odds(c, r)) as f64;
        1.0 - 1.0 / (1.0 + l.exp())
    }

    /// State of cell (`col`, `row`).
    pub fn cell_state(&self, col: usize, row: usize) -> CellState {
        let l = self.log_odds(col, row);
        if l >= self.params.occupied_log_odds {
            CellState::Occupied
        } else if l <= self.params.free_threshold_log_odds {
            CellState::Free
        } else {
            CellState::Unknown
        }
    }

    /// State of the cell holding `p` (unknown outside the grid).
    pub fn state(&self, p: WorldPoint) -> CellState {
        self.cell_of(p)
            .map_or(CellState::Unknown, |(c, r)| self.cell_state(c, r))
    }

    /// True when the cell holding `p` is occupied.
    pub fn is_occupied(&self, p: WorldPoint) -> bool {
        self.state(p) == CellState::Occupied
    }

    /// True when the cell holding `p` is free.
    pub fn is_free(&self, p: WorldPoint) -> bool {
        self.state(p) == CellState::Free
    }

    /// Grows the grid (with some padding) so that global cells `lo..=hi` fit.
    fn ensure(&mut self, lo: (i64, i64), hi: (i64, i64)) {
        const PAD: i64 = 16;
        let (c1, r1) = (
            self.col0 + self.width as i64 - 1,
            self.row0 + self.height as i64 - 1,
        );
        let empty = self.width == 0;
        if !empty && lo.0 >= self.col0 && lo.1 >= self.row0 && hi.0 <= c1 && hi.1 <= r1 {
            return;
        }
        let (nc0, nr0, nc1, nr1) = if empty {
            (lo.0 - PAD, lo.1 - PAD, hi.0 + PAD, hi.1 + PAD)
        } else {
            (
                if lo.0 < self.col0 {
                    lo.0 - PAD
                } else {
                    self.col0
                },
                if lo.1 < self.row0 {
                    lo.1 - PAD
                } else {
                    self.row0
                },
                if hi.0 > c1 { hi.0 + PAD } else { c1 },
                if hi.1 > r1 { hi.1 + PAD } else { r1 },
            )
        };
        let (nw, nh) = ((nc1 - nc0 + 1) as usize, (nr1 - nr0 + 1) as usize);
        let mut cells = vec![0f32; nw * nh];
        for row in 0..self.height {
            let nrow = (self.row0 + row as i64 - nr0) as usize;
            let ncol = (self.col0 - nc0) as usize;
            let src = &self.cells[row * self.width..(row + 1) * self.width];
            cells[nrow * nw + ncol..nrow * nw + ncol + self.width].copy_from_slice(src);
        }
        self.col0 = nc0;
        self.row0 = nr0;
        self.width = nw;
        self.height = nh;
        self.cells = cells;
    }

    fn add(&mut self, g: (i64, i64), delta: f32) {
        let (c, r) = ((g.0 - self.col0) as usize, (g.1 - self.row0) as usize);
        if c < self.width && r < self.height {
            let v = &mut self.cells[r * self.width + c];
            let m = self.params.clamp_log_odds;
            *v = (*v + delta).clamp(-m, m);
        }
    }

    /// Integrates `scan` taken at `pose`: cells along each ray up to its end become more
    /// free, the cell of a hit more occupied; max-range rays only free; error rays nothing.
    ///
    /// Returns false (and changes nothing) for a non-finite pose, a scan without usable rays,
    /// or one that would grow the grid beyond `max_extent_m` or `max_cells`.
    pub fn integrate(&mut self, pose: &Pose2, geometry: &ScanGeometry, scan: &Scan) -> bool {
        if !(pose.x_m.is_finite() && pose.y_m.is_finite() && pose.theta_rad.is_finite()) {
            tracing::warn!(?pose, "occupancy grid: non-finite pose, scan skipped");
            return false;
        }
        let n = geometry
            .ray_count
            .min(scan.ranges_m.len())
            .min(scan.status.len());
        let start = pose.position();
        let mut ends: Vec<(WorldPoint, bool)> = Vec::with_capacity(n);
        let dirs = geometry.directions();
        for i in 0..n {
            let r = scan.ranges_m[i];
            let hit = match scan.status[i] {
                RayStatus::Hit if r.is_finite() && r >= 0.0 => true,
                RayStatus::MaxRange => false,
                _ => continue,
            };
            let range = if hit { r } else { geometry.max_range_m };
            let d = dirs[i];
            let p = RobotPoint::new(range * d[0], range * d[1]);
            ends.push((pose.transform_point(p), hit));
        }
        if ends.is_empty() {
            return false;
        }
        let mut lo = self.global(start);
        let mut hi = lo;
        for (p, _) in &ends {
            let g = self.global(*p);
            lo = (lo.0.min(g.0), lo.1.min(g.1));
            hi = (hi.0.max(g.0), hi.1.max(g.1));
        }
        if self.width > 0 {
            lo = (lo.0.min(self.col0), lo.1.min(self.row0));
            hi = (
                hi.0.max(self.col0 + self.width as i64 - 1),
                hi.1.max(self.row0 + self.height as i64 - 1),
            );
        }
        let max_cells = (self.params.max_extent_m / self.params.resolution_m).ceil();
        let span = (hi.0.saturating_sub(lo.0)).max(hi.1.saturating_sub(lo.1)) as f64;
        let area =
            (hi.0.saturating_sub(lo.0) as f64 + 33.0) * (hi.1.saturating_sub(lo.1) as f64 + 33.0);
        if span + 1.0 > max_cells || area > self.params.max_cells as f64 {
            tracing::warn!(
                ?pose,
                max_extent_m = self.params.max_extent_m,
                max_cells = self.params.max_cells,
                "occupancy grid: scan would grow the map too far, skipped"
            );
            return false;
        }
        self.ensure(lo, hi);
        let free = self.params.free_log_odds;
        let res = self.params.resolution_m;
        let m = self.params.clamp_log_odds;
        let (col0, row0, width, height) = (self.col0, self.row0, self.width, self.height);
        let cells = &mut self.cells;
        for (end, _) in &ends {
            // Every cell but the last is seen through.
            traverse_before_end(res, start, *end, |g| {
                let (c, r) = ((g.0 - col0) as usize, (g.1 - row0) as usize);
                if c < width && r < height {
                    let v = &mut cells[r * width + c];
                    *v = (*v + free).clamp(-m, m);
                }
            });
        }
        // Hits after frees, so a grazing neighbour ray does not erase a wall cell.
        let hit = self.params.hit_log_odds;
        for (end, is_hit) in &ends {
            if *is_hit {
                let g = self.global(*end);
                self.add(g, hit);
            }
        }
        true
    }

    /// The grid as a greyscale image, row 0 at the top (highest y): occupied 0, free 254,
    /// unknown 205.
    pub fn to_pixels(&self) -> Vec<u8> {
        let mut out = Vec::with_capacity(self.width * self.height);
        for row in (0..self.height).rev() {
            for col in 0..self.width {
                out.push(match self.cell_state(col, row) {
                    CellState::Occupied => pixel::OCCUPIED,
                    CellState::Free => pixel::FREE,
                    CellState::Unknown => pixel::UNKNOWN,
                });
            }
        }
        out
    }

    /// Writes `<dir>/<stem>.pgm` (P5) and `<dir>/<stem>.yaml` for ROS map_server / Nav2's
    /// map loader (`mode: trinary`, origin = the lower-left pixel), each atomically.
    pub fn write_map_server(
        &self,
        dir: &Path,
        stem: &str,
    ) -> Result<MapServerFiles, LocaliserError> {
        if self.width == 0 {
            return Err(LocaliserError::EmptyMap);
        }
        let pgm = dir.join(format!("{stem}.pgm"));
        let yaml = dir.join(format!("{stem}.yaml"));
        let mut bytes = Vec::new();
        image::codecs::pnm::PnmEncoder::new(&mut bytes)
            .with_subtype(image::codecs::pnm::PnmSubtype::Graymap(
                image::codecs::pnm::SampleEncoding::Binary,
            ))
            .write_image(
                &self.to_pixels(),
                self.width as u32,
                self.height as u32,
                ExtendedColorType::L8,
            )
            .map_err(|e| LocaliserError::Image {
                path: pgm.clone(),
                message: e.to_string(),
            })?;
        write_atomic(&pgm, &bytes)?;
        let o = self.origin();
        let text = format!(
            "image: {stem}.pgm\nmode: trinary\nresolution: {}\norigin: [{}, {}, 0.0]\nnegate: 0\noccupied_thresh: {}\nfree_thresh: {}\n",
            scan_types::format_decimal(self.params.resolution_m),
            scan_types::format_decimal(o.x_m()),
            scan_types::format_decimal(o.y_m()),
            scan_types::MAP_OCCUPIED_THRESH,
            scan_types::MAP_FREE_THRESH,
        );
        write_atomic(&yaml, text.as_bytes())?;
        Ok(MapServerFiles { pgm, yaml })
    }

    /// Writes the grid as a greyscale PNG (same pixels as the PGM), atomically.
    pub fn to_png(&self, path: &Path) -> Result<(), LocaliserError> {
        if self.width == 0 {
            return Err(LocaliserError::EmptyMap);
        }
        let mut bytes = Vec::new();
        image::codecs::png::PngEncoder::new(&mut bytes)
            .write_image(
                &self.to_pixels(),
                self.width as u32,
                self.height as u32,
                ExtendedColorType::L8,
            )
            .map_err(|e| LocaliserError::Image {
                path: path.to_path_buf(),
                message: e.to_string(),
            })?;
        write_atomic(path, &bytes)
    }
}

/// `x.floor() as i64` without a libm call (the baseline x86-64 target has no rounding
/// instruction); equal for every input, NaN and infinities included.
fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if t as f64 > x { t.saturating_sub(1) } else { t }
}

/// Calls `visit` on the global cells crossed by the segment `a -> b` in order
/// (Amanatides-Woo), up to but excluding `b`'s cell.
fn traverse_before_end(res: f64, a: WorldPoint, b: WorldPoint, mut visit: impl FnMut((i64, i64))) {
    let (sx, sy, ex, ey) = (a.x_m(), a.y_m(), b.x_m(), b.y_m());
    let (mut cx, mut cy) = (floor_i64(sx / res), floor_i64(sy / res));
    let (tx, ty) = (floor_i64(ex / res), floor_i64(ey / res));
    let (dx, dy) = (ex - sx, ey - sy);
    let step_x = if dx > 0.0 { 1 } else { -1 };
    let step_y = if dy > 0.0 { 1 } else { -1 };
    let t_delta_x = if dx != 0.0 {
        res / dx.abs()
    } else {
        f64::INFINITY
    };
    let t_delta_y = if dy != 0.0 {
        res / dy.abs()
    } else {
        f64::INFINITY
    };
    let mut t_max_x = if dx > 0.0 {
        ((cx + 1) as f64 * res - sx) / dx
    } else if dx < 0.0 {
        (cx as f64 * res - sx) / dx
    } else {
        f64::INFINITY
    };
    let mut t_max_y = if dy > 0.0 {
        ((cy + 1) as f64 * res - sy) / dy
    } else if dy < 0.0 {
        (cy as f64 * res - sy) / dy
    } else {
        f64::INFINITY
    };
    let max_steps = (tx - cx).unsigned_abs() + (ty - cy).unsigned_abs() + 2;
    for _ in 0..max_steps {
        if cx == tx && cy == ty {
            return;
        }
        visit((cx, cy));
        if t_max_x < t_max_y {
            cx += step_x;
            t_max_x += t_delta_x;
        } else {
            cy += step_y;
            t_max_y += t_delta_y;
        }
    }
}

/// Global cells crossed by the segment `a -> b` in order (Amanatides-Woo), `b`'s cell last:
/// the collecting walk `traverse_before_end` replaced, kept as its reference.
#[cfg(test)]
fn traverse(res: f64, a: WorldPoint, b: WorldPoint, out: &mut Vec<(i64, i64)>) {
    let (sx, sy, ex, ey) = (a.x_m(), a.y_m(), b.x_m(), b.y_m());
    let (mut cx, mut cy) = ((sx / res).floor() as i64, (sy / res).floor() as i64);
    let (tx, ty) = ((ex / res).floor() as i64, (ey / res).floor() as i64);
    let (dx, dy) = (ex - sx, ey - sy);
    let step_x = if dx > 0.0 { 1 } else { -1 };
    let step_y = if dy > 0.0 { 1 } else { -1 };
    let t_delta_x = if dx != 0.0 {
        res / dx.abs()
    } else {
        f64::INFINITY
    };
    let t_delta_y = if dy != 0.0 {
        res / dy.abs()
    } else {
        f64::INFINITY
    };
    let mut t_max_x = if dx > 0.0 {
        ((cx + 1) as f64 * res - sx) / dx
    } else if dx < 0.0 {
        (cx as f64 * res - sx) / dx
    } else {
        f64::INFINITY
    };
    let mut t_max_y = if dy > 0.0 {
        ((cy + 1) as f64 * res - sy) / dy
    } else if dy < 0.0 {
        (cy as f64 * res - sy) / dy
    } else {
        f64::INFINITY
    };
    let max_steps = (tx - cx).unsigned_abs() + (ty - cy).unsigned_abs() + 2;
    for _ in 0..max_steps {
        out.push((cx, cy));
        if cx == tx && cy == ty {
            return;
        }
        if t_max_x < t_max_y {
            cx += step_x;
            t_max_x += t_delta_x;
        } else {
            cy += step_y;
            t_max_y += t_delta_y;
        }
    }
    // Rounding stopped short: make sure the end cell comes last.
    if out.last() != Some(&(tx, ty)) {
        out.push((tx, ty));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn floor_i64_matches_std() {
        let xs = [
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            -1e300,
            1e300,
            -2.5,
            -2.0,
            -1e-300,
            -0.0,
            0.0,
            0.5,
            1.0,
            4.999_999_999_999_999,
            (1u64 << 53) as f64 + 2.0,
        ];
        for x in xs {
            assert_eq!(floor_i64(x), x.floor() as i64, "{x}");
        }
    }

    #[test]
    fn walk_equals_the_collected_path_but_its_end() {
        let mut noise = scan_types::testkit::Noise::new(7);
        let mut uniform = || noise.uniform();
        let mut cases: Vec<(WorldPoint, WorldPoint)> = (0..3000)
            .map(|_| {
                let a = WorldPoint::new(uniform() * 8.0 - 4.0, uniform() * 8.0 - 4.0);
                let b = WorldPoint::new(uniform() * 8.0 - 4.0, uniform() * 8.0 - 4.0);
                (a, b)
            })
            .collect();
        // Axis-aligned, on cell borders, and zero length.
        cases.push((WorldPoint::new(0.0, 0.0), WorldPoint::new(1.0, 0.0)));
        cases.push((WorldPoint::new(0.05, 0.1), WorldPoint::new(0.05, -1.0)));
        cases.push((WorldPoint::new(0.3, 0.3), WorldPoint::new(0.3, 0.3)));
        cases.push((WorldPoint::new(-0.1, -0.1), WorldPoint::new(0.2, 0.2)));
        for (a, b) in cases {
            let mut want = Vec::new();
            traverse(0.05, a, b, &mut want);
            want.pop();
            let mut got = Vec::new();
            traverse_before_end(0.05, a, b, |g| got.push(g));
            assert_eq!(got, want, "{a:?} -> {b:?}");
        }
    }
}
