//! The crate's error type.

/// What can be wrong with landmark parameters.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LandmarksError {
    /// A parameter is out of its domain.
    #[error("invalid landmark parameter: {field} = {value} ({why})")]
    InvalidParam {
        /// The parameter that is wrong.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy.
        why: &'static str,
    },
}
