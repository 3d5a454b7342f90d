//! The `LaserSource` trait: anything that produces scans.

use crate::{Scan, ScanGeometry};

/// A source of laser scans: the real Hokuyo, the simulator, or a recorded log.
///
/// ```
/// use scan_types::{LaserSource, Scan, ScanGeometry};
/// use std::convert::Infallible;
///
/// /// A source that always returns the same scan.
/// struct Fixed(ScanGeometry, Scan);
/// impl LaserSource for Fixed {
///     type Error = Infallible;
///     fn geometry(&self) -> &ScanGeometry { &self.0 }
///     fn next_scan(&mut self) -> Result<Scan, Infallible> { Ok(self.1.clone()) }
/// }
///
/// let g = ScanGeometry::centred(2, 1.0, 0.0, 4.0).unwrap();
/// let mut src = Fixed(g, Scan::from_ranges(&g, &[1.0, 4.0], 0.0));
/// assert_eq!(src.next_scan().unwrap().ranges_m, vec![1.0, 4.0]);
/// ```
pub trait LaserSource {
    /// What can go wrong while reading a scan (`Infallible` for the simulator).
    type Error: std::error::Error + Send + Sync + 'static;

    /// The geometry every scan of this source has.
    fn geometry(&self) -> &ScanGeometry;

    /// The next scan; blocks until one is available.
    fn next_scan(&mut self) -> Result<Scan, Self::Error>;
}

impl<S: LaserSource + ?Sized> LaserSource for Box<S> {
    type Error = S::Error;
    fn geometry(&self) -> &ScanGeometry {
        (**self).geometry()
    }
    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        (**self).next_scan()
    }
}

impl<S: LaserSource + ?Sized> LaserSource for &mut S {
    type Error = S::Error;
    fn geometry(&self) -> &ScanGeometry {
        (**self).geometry()
    }
    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        (**self).next_scan()
    }
}
