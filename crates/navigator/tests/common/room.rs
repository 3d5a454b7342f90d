//! The hand-built room the localisation tests drive in.

use scan_types::testkit::{Seg, boxed};

/// A closed 8 m x 5 m room with three boxes in it.
pub fn room() -> Vec<Seg> {
    let mut segs = boxed(0.0, 0.0, 8.0, 5.0);
    segs.extend(boxed(3.0, 1.4, 3.6, 2.0));
    segs.extend(boxed(5.0, 3.2, 5.5, 3.7));
    segs.extend(boxed(1.8, 3.5, 2.2, 3.9));
    segs
}
