//! Atomic file writes: a temporary file in the same directory, then a rename.

use std::path::Path;

use crate::LocaliserError;

/// Writes `bytes` to `path` atomically ([`scan_types::write_atomic`]).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), LocaliserError> {
    scan_types::write_atomic(path, bytes).map_err(|source| LocaliserError::Io {
        path: path.to_path_buf(),
        source,
    })
}
