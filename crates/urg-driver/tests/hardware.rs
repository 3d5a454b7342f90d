//! Tests against a real Hokuyo, skipped unless the `hardware-tests` feature is on:
//! `URG_PORT=/dev/hokuyo cargo test -p urg-driver --features hardware-tests -- --test-threads 1`.
#![cfg(feature = "hardware-tests")]

use scan_types::{LaserSource, RayStatus};
use urg_driver::{AcquisitionMode, Urg, UrgConfig};

fn port() -> String {
    std::env::var("URG_PORT").unwrap_or_else(|_| "/dev/hokuyo".into())
}

#[test]
fn real_sensor_connects_and_scans_in_both_modes() {
    for mode in [AcquisitionMode::Polled, AcquisitionMode::Streaming] {
        let mut urg = Urg::open(
            &port(),
            UrgConfig {
                mode,
                ..UrgConfig::default()
            },
        )
        .unwrap();
        let g = *urg.geometry();
        assert_eq!(g.ray_count, urg.request().value_count());
        let v = urg.version().unwrap();
        assert!(v.protocol.contains("SCIP 2"), "{v:?}");
        let mut last = None;
        for _ in 0..5 {
            let s = urg.next_scan().unwrap();
            s.validate(&g).unwrap();
            assert!(s.status.contains(&RayStatus::Hit));
            let t = s.sensor_time_ms.unwrap();
            if let Some(l) = last {
                assert!(t > l, "time stamps increase");
            }
            last = Some(t);
        }
        urg.stop().unwrap();
        assert_eq!(urg.stats().checksum_errors, 0);
    }
}
