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
}
