//! Unplugging a sensor on a pseudo-terminal: the terminal closes as a USB device does, the
//! reconnecting driver waits, reopens the same (stable) path when the sensor is back, checks
//! it is the same sensor, and resumes.

use std::time::{Duration, Instant};

use scan_types::LaserSource;
use urg_driver::{
    Backoff, FixedSource, Model, Profile, ReconnectingUrg, Urg, UrgConfig, UrgError, open_serial,
    serve_pty, serve_pty_with,
};

fn backoff() -> Backoff {
    Backoff {
        initial: Duration::from_millis(50),
        max: Duration::from_millis(400),
        factor: 2.0,
        max_attempts: Some(40),
        cancel: None,
    }
}

fn config() -> UrgConfig {
    UrgConfig {
        time_sync_rounds: 2,
        ..UrgConfig::default()
    }
}

#[test]
fn unplug_for_two_seconds_then_replug_resumes_the_scans() {
    let p = Profile::of(Model::Urg04lx);
    let server = serve_pty(p.clone(), FixedSource::room(p.params.geometry())).unwrap();
    let path = server.path().to_string();
    let open_path = path.clone();
    let mut laser =
        ReconnectingUrg::new(move || open_serial(&open_path), config(), backoff()).unwrap();
    let first = laser.next_scan().unwrap();
    // Wall x = 3 m straight ahead (index 340 = step 384 = AFRT).
    assert_eq!(first.ranges_m[340], 3.0);

    server.control().unplug();
    let unplugged_at = Instant::now();
    let gone = (0..200).any(|_| {
        std::thread::sleep(Duration::from_millis(5));
        !std::path::Path::new(&path).exists()
    });
    assert!(gone, "the device link disappears while unplugged");
    let ctl = server.control().clone();
    let replug = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_secs(2));
        ctl.plug();
    });
    let scan = laser.next_scan().unwrap();
    replug.join().unwrap();
    assert!(unplugged_at.elapsed() >= Duration::from_secs(2));
    assert_eq!(scan.ranges_m[340], 3.0);
    assert_eq!(laser.reconnects(), 1);
    laser.next_scan().unwrap();
}

#[test]
fn a_bare_driver_reports_the_unplug_as_a_disconnect() {
    let p = Profile::of(Model::Urg04lx);
    let server = serve_pty(p.clone(), FixedSource::room(p.params.geometry())).unwrap();
    let mut urg = Urg::open(server.path(), config()).unwrap();
    urg.next_scan().unwrap();
    server.control().unplug();
    // The emulator's thread closes the terminal a moment later (its link goes with it).
    let gone = (0..200).any(|_| {
        std::thread::sleep(Duration::from_millis(5));
        !std::path::Path::new(server.path()).exists()
    });
    assert!(gone);
    let e = urg.next_scan().unwrap_err();
    assert!(matches!(e, UrgError::Disconnected(_)), "{e}");
}

#[test]
fn a_different_sensor_behind_the_same_path_is_refused() {
    let p = Profile::of(Model::Urg04lx);
    let first = serve_pty(p.clone(), FixedSource::room(p.params.geometry())).unwrap();
    // The second sensor is the same model with another serial number.
    let mut other = p.clone();
    for (k, v) in &mut other.version {
        if k == "SERI" {
            *v = "H0000001".into();
        }
    }
    let second = serve_pty_with(urg_driver::SensorCore::new(
        other,
        FixedSource::room(p.params.geometry()),
        urg_driver::EmulatorControl::default(),
    ))
    .unwrap();
    let paths = [first.path().to_string(), second.path().to_string()];
    let opened = std::sync::Arc::new(std::sync::atomic::AtomicUsize::new(0));
    let o2 = opened.clone();
    let mut laser = ReconnectingUrg::new(
        move || {
            let k = o2.fetch_add(1, std::sync::atomic::Ordering::SeqCst).min(1);
            open_serial(&paths[k])
        },
        config(),
        backoff(),
    )
    .unwrap();
    laser.next_scan().unwrap();
    first.control().unplug();
    let e = laser.next_scan().unwrap_err();
    assert!(
        e.to_string().contains("H0706400") && e.to_string().contains("H0000001"),
        "{e}"
    );
}

#[test]
fn a_missing_port_is_named_as_missing_not_as_a_disconnect() {
    let e = Urg::open("/dev/goalseek-no-such-port", config()).unwrap_err();
    assert!(matches!(e, UrgError::NoSuchPort { .. }), "{e}");
    assert!(e.to_string().contains("/dev/goalseek-no-such-port"), "{e}");
}
