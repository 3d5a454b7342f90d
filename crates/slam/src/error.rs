//! The crate's error type.

/// What can be wrong with the front end's parameters or the trajectories given to evaluation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SlamError {
    /// A parameter is outside its valid range.
    #[error("{key} = {value} {requirement}")]
    InvalidParam {
        /// The parameter's name.
        key: &'static str,
        /// Its value, as text.
        value: String,
        /// What it must satisfy.
        requirement: &'static str,
    },
    /// Two trajectories to compare differ in length.
    #[error("the estimate has {estimate} poses, the reference {reference}")]
    LengthMismatch {
        /// Poses of the estimate.
        estimate: usize,
        /// Poses of the reference.
        reference: usize,
    },
    /// Too few poses for the measure asked for.
    #[error("{what} needs at least {needed} poses, {got} given")]
    TooFewPoses {
        /// The measure.
        what: &'static str,
        /// Poses it needs.
        needed: usize,
        /// Poses given.
        got: usize,
    },
}
