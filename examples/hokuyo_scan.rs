//! Opens a Hokuyo (URG-04LX, UTM-30LX, ...) on a serial port and prints one scan as
//! `bearing_deg,range_m,status`.
//!
//! Run: `cargo run --example hokuyo_scan -- /dev/ttyACM0` (or any SCIP 2.0 device, such as
//! the pseudo-terminal `robot-app emulate` prints).
#![allow(clippy::print_stdout)] // an example program prints its result

use scan_types::LaserSource;
use urg_driver::{Urg, UrgConfig};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let port = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "/dev/ttyACM0".into());
    let mut urg = Urg::open(&port, UrgConfig::default())?;
    let geometry = *urg.geometry();
    let scan = urg.next_scan()?;
    println!("bearing_deg,range_m,status");
    for i in 0..scan.len() {
        let bearing = geometry.bearing_rad(i).to_degrees();
        println!("{bearing:.3},{:.3},{:?}", scan.ranges_m[i], scan.status[i]);
    }
    urg.stop()?;
    Ok(())
}
