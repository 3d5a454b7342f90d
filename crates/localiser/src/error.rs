//! The crate's error type.

use std::path::PathBuf;

/// What can go wrong in localisation and mapping.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LocaliserError {
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        source: std::io::Error,
    },
    /// Encoding an image failed.
    #[error("{path}: cannot encode image: {message}")]
    Image {
        /// The file being written.
        path: PathBuf,
        /// What the encoder said.
        message: String,
    },
    /// The map has no cells yet (no scan integrated).
    #[error("the map is empty: integrate a scan first")]
    EmptyMap,
    /// A parameter is out of its domain.
    #[error("invalid parameter: {field} = {value} ({why})")]
    InvalidParam {
        /// The parameter.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What it must satisfy.
        why: &'static str,
    },
}
