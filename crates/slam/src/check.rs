//! Range checks of parameters, shared by the front end's and loop closure's `validate`.

use crate::SlamError;

/// The error for parameter `key` of `value` that breaks `requirement`.
pub(crate) fn invalid(key: &'static str, value: f64, requirement: &'static str) -> SlamError {
    SlamError::InvalidParam {
        key,
        value: value.to_string(),
        requirement,
    }
}

/// The first of `pairs` (key, value) whose value fails `ok`, as an error saying `requirement`.
pub(crate) fn each(
    pairs: &[(&'static str, f64)],
    ok: impl Fn(f64) -> bool,
    requirement: &'static str,
) -> Result<(), SlamError> {
    match pairs.iter().find(|(_, v)| !ok(*v)) {
        Some(&(key, v)) => Err(invalid(key, v, requirement)),
        None => Ok(()),
    }
}

/// A finite number above 0.
pub(crate) fn positive(v: f64) -> bool {
    v.is_finite() && v > 0.0
}
