//! End to end: the driver opens the emulator through a real pseudo-terminal, as it would open
//! `/dev/ttyACM0`, connects, reads VV/PP/II, synchronises clocks, streams and polls scans.

use std::time::Duration;

use scan_types::{LaserSource, RayStatus};
use urg_driver::{
    AcquisitionMode, Emulator, FixedSource, Model, Profile, Urg, UrgConfig, UrgError, serve_pty,
};

#[test]
fn driver_talks_to_the_emulator_over_a_pseudo_terminal() {
    let profile = Profile::of(Model::Urg04lx);
    let source = FixedSource::room(profile.params.geometry());
    let server = serve_pty(profile, source).expect("pseudo-terminal");
    assert!(server.path().starts_with("/dev/"), "{}", server.path());
    let config = UrgConfig {
        mode: AcquisitionMode::Streaming,
        time_sync_rounds: 5,
        ..UrgConfig::default()
    };
    let mut urg = Urg::open(server.path(), config).expect("connect over the pty");
    assert_eq!(urg.params().afrt, 384);
    let v = urg.version().unwrap();
    assert_eq!(v.product, "SOKUIKI Sensor URG-04LX");
    let st = urg.state().unwrap();
    assert_eq!(st.status, "Sensor works well.");
    // The host-time offset makes scan host times close to now.
    let a = urg.next_scan().unwrap();
    let b = urg.next_scan().unwrap();
    let now = urg_driver::host_now_s();
    assert!(
        (now - b.host_time_s).abs() < 1.0,
        "host time {} vs now {now}",
        b.host_time_s
    );
    assert_eq!(b.sensor_time_ms.unwrap() - a.sensor_time_ms.unwrap(), 100);
    assert_eq!(a.ranges_m[340], 3.0);
    assert_eq!(a.status[84], RayStatus::Error(7));
    urg.stop().unwrap();
    // Single scans on the same connection.
    let mut raw = urg_driver::RawScan::default();
    urg.laser_on().unwrap();
    let req = *urg.request();
    urg.get_scan(&req, &mut raw).unwrap();
    assert_eq!(raw.ranges_mm[340], 3000);

    // A stalled device gives a timeout, and the port is released for a second client.
    server.control().set_stalled(true);
    assert!(matches!(urg.version(), Err(UrgError::Timeout { .. })));
    server.control().set_stalled(false);
    drop(urg);
    let mut again = Urg::open(
        server.path(),
        UrgConfig {
            time_sync_rounds: 0,
            ..UrgConfig::default()
        },
    )
    .expect("reopen");
    assert_eq!(again.next_scan().unwrap().ranges_m[340], 3.0);
    server.stop();
    std::thread::sleep(Duration::from_millis(10));
}

#[test]
fn in_memory_and_pty_emulators_agree() {
    let mut mem = Urg::connect(Emulator::fixed(Model::Utm30lx), UrgConfig::default()).unwrap();
    let profile = Profile::of(Model::Utm30lx);
    let server = serve_pty(
        profile.clone(),
        FixedSource::room(profile.params.geometry()),
    )
    .unwrap();
    let mut pty = Urg::open(server.path(), UrgConfig::default()).unwrap();
    let a = mem.next_scan().unwrap();
    let b = pty.next_scan().unwrap();
    assert_eq!(a.status, b.status);
    assert_eq!(a.ranges_m.len(), 1081);
    for (x, y) in a.ranges_m.iter().zip(&b.ranges_m) {
        assert!(x == y || (x.is_nan() && y.is_nan()));
    }
}
