//! The crate's error type.

/// What can be wrong with the navigator's parameters or inputs.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NavigatorError {
    /// A parameter is outside its valid range.
    #[error("{key} = {value} {requirement}")]
    InvalidParam {
        /// The parameter's key, `section.name` as in a configuration file.
        key: &'static str,
        /// Its value, as text.
        value: String,
        /// What it must satisfy.
        requirement: String,
    },
    /// A method name that is not a preset.
    #[error("unknown method '{0}' (expected paper or goalseek)")]
    UnknownMethod(String),
    /// The online SLAM's parameters were refused.
    #[error("online slam: {0}")]
    Slam(#[from] slam::SlamError),
    /// A start pose or goal that is not finite or lies beyond [`crate::MAX_COORD_M`].
    #[error("{what} ({value}) must be finite, with coordinates within +-1000 km")]
    NotFinite {
        /// What was given (start or goal).
        what: &'static str,
        /// Its value, as text.
        value: String,
    },
    /// [`crate::Navigator::retarget`] before the run to the last goal finished.
    #[error("a new target needs the run to the last one finished (it is {0:?})")]
    NotFinished(crate::Phase),
    /// [`crate::Navigator::retarget`] after a run that ended by a failure.
    #[error("a run that ended '{0}' cannot take a new target")]
    EndedBy(crate::Reason),
}
