//! The sensor side of SCIP 2.0: an emulated URG-04LX or UTM-30LX that takes its ranges from
//! any `LaserSource`, usable in memory as a driver transport or on a pseudo-terminal.
//!
//! ```
//! use urg_driver::{Emulator, Model, Urg, UrgConfig};
//! use scan_types::LaserSource;
//! let mut urg = Urg::connect(Emulator::fixed(Model::Urg04lx), UrgConfig::default()).unwrap();
//! let scan = urg.next_scan().unwrap();
//! // The default fixed scan: the wall ahead is 3 m away.
//! assert_eq!(scan.ranges_m[340], 3.0);
//! ```

mod commands;
mod control;
mod machine;
mod profile;
mod pty;
mod scans;
mod source;
mod tcp;
mod transport;

pub use control::{EmulatorControl, Fault};
pub use machine::SensorCore;
pub use profile::{Model, Profile, step_bearing_rad};
pub use pty::{PtyServer, sensor, serve_pty, serve_pty_with};
pub use source::FixedSource;
pub use tcp::{TcpServer, serve_tcp, serve_tcp_with};
pub use transport::Emulator;
