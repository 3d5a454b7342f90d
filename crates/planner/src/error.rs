//! The crate's error type.

/// What can be wrong with planner parameters (see [`crate::PlannerParams::validate`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlannerError {
    /// A parameter is out of its domain.
    #[error("invalid planner parameter {field} = {value} ({why})")]
    InvalidParam {
        /// The parameter.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy.
        why: &'static str,
    },
}
