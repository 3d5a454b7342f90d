//! Reading back the TUM trajectories robot-app writes.

use std::path::Path;

/// The position (x, y) of the last line of the TUM file at `path`.
pub fn last_xy(path: &Path) -> [f64; 2] {
    let text = std::fs::read_to_string(path).unwrap();
    let f: Vec<f64> = text
        .lines()
        .last()
        .unwrap_or_else(|| panic!("{} is empty", path.display()))
        .split_whitespace()
        .map(|v| v.parse().unwrap())
        .collect();
    [f[1], f[2]]
}
