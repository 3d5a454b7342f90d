//! The shared real data beside the repository (`../shared/data/`), for tests that read it.

use std::path::PathBuf;

/// `../shared/data/REL`, or `None` (with a note) when `../shared` is absent.
#[allow(clippy::print_stdout)] // the note says why the test did nothing
pub fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/")).join(rel);
    if p.exists() {
        Some(p)
    } else {
        println!("skipping: {} not found (../shared is absent)", p.display());
        None
    }
}
