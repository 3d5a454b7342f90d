//! The crate's error type.

/// What can be wrong with scan-types values built from outside data.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ScanTypesError {
    /// A scan geometry field is out of its domain.
    #[error("invalid scan geometry: {field} = {value} ({why})")]
    InvalidGeometry {
        /// The field that is wrong.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What the field must satisfy.
        why: &'static str,
    },
    /// A scan's per-ray arrays do not match its geometry.
    #[error("scan has {got} {what}, its geometry says {expected} rays")]
    LengthMismatch {
        /// Which array.
        what: &'static str,
        /// Its length.
        got: usize,
        /// The geometry's ray count.
        expected: usize,
    },
    /// A comma-separated value has a part that is not a finite number.
    #[error("{what} {text:?}: {token:?} is not a finite number")]
    NotANumber {
        /// What the text should describe (`pose`, `point`, `size`).
        what: &'static str,
        /// The whole text.
        text: String,
        /// The part that is not a number.
        token: String,
    },
    /// A comma-separated value has the wrong number of parts.
    #[error("{what} {text:?}: expected {expected} comma-separated numbers, found {found}")]
    WrongCount {
        /// What the text should describe.
        what: &'static str,
        /// The whole text.
        text: String,
        /// Numbers expected.
        expected: usize,
        /// Numbers found.
        found: usize,
    },
    /// A value that must be positive is not.
    #[error("{what} {text:?}: every number must be > 0")]
    NotPositive {
        /// What the text should describe.
        what: &'static str,
        /// The whole text.
        text: String,
    },
}
