//! Scan matching: the pose of a scan relative to reference scans, by point-to-line ICP with a
//! prior that holds the directions the geometry does not constrain (a corridor's length) at
//! the initial guess.

mod align;
#[cfg(test)]
mod fixtures;
mod params;
mod surface;
mod target;

pub use params::{MatchParams, ScanMatch};
pub use target::MatchTarget;
