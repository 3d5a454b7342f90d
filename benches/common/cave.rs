//! The paper's world for benches: `../shared/worlds/stage/cave.png` at 10 m x 10 m with a
//! boundary wall (see its MANIFEST), ray cast by an exact traversal of the bitmap's cells.

#![allow(dead_code)]

use std::path::PathBuf;

use scan_types::{Scan, ScanGeometry};

/// cave.png as an occupancy bitmap, 0.02 m per pixel, centred on the origin.
pub struct Bitmap {
    width: usize,
    height: usize,
    dark: Vec<bool>,
    cell_m: f64,
}

impl Bitmap {
    pub fn load() -> Option<Bitmap> {
        let path = PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../shared/worlds/stage/cave.png"
        ));
        let img = image::open(&path).ok()?.to_luma8();
        let (w, h) = (img.width() as usize, img.height() as usize);
        let dark = img.pixels().map(|p| p.0[0] < 128).collect();
        Some(Bitmap {
            width: w,
            height: h,
            dark,
            cell_m: 10.0 / w as f64,
        })
    }

    /// Obstacle at cell (cx, cy) (cy = 0 at the bottom); outside the image is the boundary wall.
    pub fn occupied(&self, cx: i64, cy: i64) -> bool {
        if cx < 0 || cy < 0 || cx >= self.width as i64 || cy >= self.height as i64 {
            return true;
        }
        let row = self.height - 1 - cy as usize;
        self.dark[row * self.width + cx as usize]
    }

    /// Exact distance from (x, y) along `angle` to the first dark cell (grid traversal).
    pub fn raycast(&self, x: f64, y: f64, angle: f64, max_m: f64) -> Option<f64> {
        let half = self.width as f64 * self.cell_m / 2.0;
        let (gx, gy) = ((x + half) / self.cell_m, (y + half) / self.cell_m);
        let (dx, dy) = (angle.cos(), angle.sin());
        let (mut cx, mut cy) = (gx.floor() as i64, gy.floor() as i64);
        let step_x = if dx > 0.0 { 1 } else { -1 };
        let step_y = if dy > 0.0 { 1 } else { -1 };
        let next = |g: f64, c: i64, d: f64| {
            if d > 0.0 {
                (c as f64 + 1.0 - g) / d
            } else if d < 0.0 {
                (g - c as f64) / -d
            } else {
                f64::INFINITY
            }
        };
        let (mut tx, mut ty) = (next(gx, cx, dx), next(gy, cy, dy));
        let (ddx, ddy) = (1.0 / dx.abs(), 1.0 / dy.abs());
        let max_cells = max_m / self.cell_m;
        loop {
            let t = if tx < ty {
                cx += step_x;
                let t = tx;
                tx += ddx;
                t
            } else {
                cy += step_y;
                let t = ty;
                ty += ddy;
                t
            };
            if t > max_cells {
                return None;
            }
            if self.occupied(cx, cy) {
                return Some(t * self.cell_m);
            }
        }
    }

    pub fn scan(&self, g: &ScanGeometry, x: f64, y: f64, heading: f64) -> Scan {
        let ranges: Vec<f64> = (0..g.ray_count)
            .map(|i| {
                self.raycast(x, y, heading + g.bearing_rad(i), g.max_range_m)
                    .unwrap_or(g.max_range_m)
            })
            .collect();
        Scan::from_ranges(g, &ranges, 0.0)
    }
}
