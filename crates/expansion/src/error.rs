//! The crate's error type.

/// What can be wrong with the inputs of an expansion (see [`crate::check_inputs`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ExpansionError {
    /// The robot radius is negative, NaN or infinite.
    #[error("robot radius {radius_m} m is not a finite number >= 0")]
    InvalidRadius {
        /// The radius given.
        radius_m: f64,
    },
    /// A per-ray array does not have one entry per ray of the geometry.
    #[error("{what} has {got} entries, the scan geometry has {expected} rays")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The geometry's ray count.
        expected: usize,
    },
}
