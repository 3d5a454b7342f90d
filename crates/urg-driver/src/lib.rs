//! Hokuyo SCIP 2.0 driver: a pure codec ([`codec`]), a command port generic over its
//! transport ([`ScipPort`]), a connected sensor that implements `LaserSource` ([`Urg`],
//! [`ReconnectingUrg`]) and, behind a cargo feature, an emulator of the sensor side
//! (`Emulator`, `serve_pty`).
//!
//! # Features
//!
//! - `emulator` (off by default): the `emulator` module, an emulated URG-04LX or UTM-30LX
//!   usable in memory as a transport or served on a pseudo-terminal, with its items
//!   re-exported at the crate root. A robot build of the driver leaves it out; simulator
//!   runs, tests and tools turn it on (`urg-driver = { ..., features = ["emulator"] }`).
//! - `hardware-tests`: runs `tests/hardware.rs` against a real sensor.
//!
//! The driver owns its transport (`T: Read + Write`, given back by `into_inner`); opening a
//! real port goes through [`Urg::open`] (the `serialport` crate). Ranges come out in metres:
//! values below the sensor's DMIN are error codes, kept as `RayStatus::Error(code)`, except
//! code 0 ("no return"), which is `RayStatus::MaxRange`.
//!
//! ```
//! # #[cfg(feature = "emulator")]
//! # fn main() {
//! use scan_types::{LaserSource, RayStatus};
//! use urg_driver::{AcquisitionMode, Emulator, Model, Urg, UrgConfig};
//!
//! let config = UrgConfig { mode: AcquisitionMode::Streaming, ..UrgConfig::default() };
//! let mut urg = Urg::connect(Emulator::fixed(Model::Urg04lx), config).unwrap();
//! assert_eq!(urg.params().model, "URG-04LX(Hokuyo Automatic Co.,Ltd.)");
//! assert_eq!(urg.geometry().ray_count, 682);
//! let a = urg.next_scan().unwrap();
//! let b = urg.next_scan().unwrap();
//! // One sensor period (100 ms) between streamed scans.
//! assert_eq!(b.sensor_time_ms.unwrap() - a.sensor_time_ms.unwrap(), 100);
//! assert_eq!(a.status[84], RayStatus::Error(7));
//! # }
//! # #[cfg(not(feature = "emulator"))]
//! # fn main() {}
//! ```

pub mod codec;
mod driver;
#[cfg(feature = "emulator")]
pub mod emulator;
mod error;
mod info;
pub mod port;
pub mod time;

pub use codec::{Command, DataKind, RawScan, ScanRequest, Status, StreamRequest, TimeCode};
pub use driver::{
    AcquisitionMode, Backoff, PortOpener, PortSpec, PortTransport, PortUrg, ReconnectingUrg,
    SCIP_TCP_PORT, SerialOpener, SerialTransport, SerialUrg, TCP_PREFIX, Urg, UrgConfig,
    connect_with_backoff, host_now_s, open_port, open_serial, open_tcp,
};
#[cfg(feature = "emulator")]
pub use emulator::{
    Emulator, EmulatorControl, Fault, FixedSource, Model, Profile, PtyServer, SensorCore,
    TcpServer, serve_pty, serve_pty_with, serve_tcp, serve_tcp_with,
};
pub use error::UrgError;
pub use info::{SensorParams, StateInfo, VersionInfo};
pub use port::{PortConfig, PortStats, ScipPort};
