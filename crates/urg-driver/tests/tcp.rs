//! The driver over TCP (an Ethernet Hokuyo such as the UST-10LX) against the emulator served
//! on loopback: connecting, polled and streamed scans, a client leaving, the server going
//! away and coming back at the same address, and addresses that cannot work.

use std::f64::consts::PI;
use std::net::{SocketAddr, TcpListener};
use std::time::{Duration, Instant};

use scan_types::{LaserSource, RayStatus};
use urg_driver::{
    AcquisitionMode, Backoff, FixedSource, Model, PortSpec, PortUrg, Profile, TcpServer, Urg,
    UrgConfig, UrgError, open_tcp, serve_tcp,
};

fn backoff() -> Backoff {
    Backoff {
        initial: Duration::from_millis(50),
        max: Duration::from_millis(200),
        factor: 2.0,
        max_attempts: Some(40),
        cancel: None,
    }
}

fn config(mode: AcquisitionMode) -> UrgConfig {
    UrgConfig {
        mode,
        time_sync_rounds: 3,
        ..UrgConfig::default()
    }
}

fn loopback_any() -> SocketAddr {
    "127.0.0.1:0".parse().unwrap()
}

fn serve(model: Model, addr: SocketAddr) -> TcpServer {
    let p = Profile::of(model);
    serve_tcp(addr, p.clone(), FixedSource::room(p.params.geometry())).unwrap()
}

#[test]
fn a_ust_10lx_over_tcp_has_1081_steps_over_270_degrees_and_a_25_ms_period() {
    let server = serve(Model::Ust10lx, loopback_any());
    let addr = server.local_addr().to_string();
    let mut urg =
        Urg::connect(open_tcp(&addr).unwrap(), config(AcquisitionMode::Streaming)).unwrap();
    let p = urg.params().clone();
    // UST-10LX data sheet / PP: steps 0..=1080, front 540, 1440 steps per turn, 2400 rpm.
    assert_eq!((p.amin, p.amax, p.afrt, p.ares), (0, 1080, 540, 1440));
    assert_eq!((p.dmin_mm, p.dmax_mm, p.scan_rpm), (20, 30000, 2400));
    let g = *urg.geometry();
    assert_eq!(g.ray_count, 1081);
    // Step s at (s - AFRT) * 2 pi / ARES: step 0 at -135 deg, step 1080 at +135 deg.
    assert!((g.bearing_rad(0) + 0.75 * PI).abs() < 1e-12);
    assert!((g.bearing_rad(1080) - 0.75 * PI).abs() < 1e-12);
    let a = urg.next_scan().unwrap();
    let b = urg.next_scan().unwrap();
    assert_eq!(a.ranges_m.len(), 1081);
    // 60 s / 2400 rpm = 25 ms between streamed scans.
    assert_eq!(b.sensor_time_ms.unwrap() - a.sensor_time_ms.unwrap(), 25);
    // The room: wall 3 m straight ahead (step 540), an error code 7 at -90 deg (step 180).
    assert_eq!(a.ranges_m[540], 3.0);
    assert_eq!(a.status[180], RayStatus::Error(7));
    let version = urg.version().unwrap();
    assert_eq!(version.protocol, "SCIP 2.0");
}

#[test]
fn a_client_leaving_mid_stream_leaves_the_server_ready_for_the_next() {
    let server = serve(Model::Ust10lx, loopback_any());
    let addr = server.local_addr().to_string();
    {
        let mut first =
            Urg::connect(open_tcp(&addr).unwrap(), config(AcquisitionMode::Streaming)).unwrap();
        first.next_scan().unwrap();
        // Dropped while streaming, without QT.
    }
    for mode in [AcquisitionMode::Polled, AcquisitionMode::Streaming] {
        let mut next = Urg::connect(open_tcp(&addr).unwrap(), config(mode)).unwrap();
        let scan = next.next_scan().unwrap();
        assert_eq!(scan.ranges_m[540], 3.0);
    }
    // One scan (at least) for each of the three clients.
    assert!(server.control().scans_served() >= 3);
}

#[test]
fn the_server_going_away_and_back_is_a_reconnect_to_the_same_address() {
    let server = serve(Model::Ust10lx, loopback_any());
    let port = format!("tcp:{}", server.local_addr());
    let mut laser =
        PortUrg::open_port(&port, config(AcquisitionMode::Streaming), backoff()).unwrap();
    assert_eq!(laser.geometry().ray_count, 1081);
    let before = laser.next_scan().unwrap();
    assert_eq!(before.ranges_m[540], 3.0);

    server.control().unplug();
    let unplugged_at = Instant::now();
    // While unplugged nothing listens: a new connection is refused.
    let refused = (0..100).any(|_| {
        std::thread::sleep(Duration::from_millis(20));
        open_tcp(&server.local_addr().to_string()).is_err()
    });
    assert!(refused, "connections are refused while the sensor is away");
    let ctl = server.control().clone();
    let replug = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(800));
        ctl.plug();
    });
    // Scans already in the socket's buffer come first; then the closed connection is seen
    // and the driver reconnects.
    let mut after = laser.next_scan().unwrap();
    for _ in 0..200 {
        if laser.reconnects() == 1 {
            break;
        }
        after = laser.next_scan().unwrap();
    }
    replug.join().unwrap();
    assert!(unplugged_at.elapsed() >= Duration::from_millis(800));
    assert_eq!(after.ranges_m[540], 3.0);
    assert_eq!(laser.reconnects(), 1);
    laser.next_scan().unwrap();
}

#[test]
fn a_different_sensor_at_the_same_address_is_refused() {
    let server = serve(Model::Ust10lx, loopback_any());
    let addr = server.local_addr();
    let mut laser = PortUrg::open_port(
        &format!("tcp:{addr}"),
        config(AcquisitionMode::Polled),
        backoff(),
    )
    .unwrap();
    laser.next_scan().unwrap();
    server.stop();
    let _other = serve(Model::Utm30lx, addr);
    match laser.next_scan() {
        Err(UrgError::ParametersChanged(why)) => {
            assert!(
                why.contains("EMU10LX01") && why.contains("00903971"),
                "{why}"
            )
        }
        other => panic!("expected ParametersChanged, got {other:?}"),
    }
}

#[test]
fn port_values_are_read_as_serial_paths_or_tcp_addresses() {
    assert_eq!(
        PortSpec::parse("/dev/ttyACM0").unwrap(),
        PortSpec::Serial("/dev/ttyACM0".into())
    );
    assert_eq!(
        PortSpec::parse("tcp:192.168.0.10:10940").unwrap(),
        PortSpec::Tcp("192.168.0.10:10940".into())
    );
    assert_eq!(
        PortSpec::parse("tcp:[::1]:10940").unwrap(),
        PortSpec::Tcp("[::1]:10940".into())
    );
    for bad in [
        "tcp:",
        "tcp:192.168.0.10",
        "tcp::10940",
        "tcp:host:0",
        "tcp:host:70000",
    ] {
        match PortSpec::parse(bad) {
            Err(e @ UrgError::BadPort { .. }) => {
                let text = e.to_string();
                assert!(
                    text.contains(bad) && text.contains("tcp:HOST:PORT"),
                    "{text}"
                );
            }
            other => panic!("{bad}: expected BadPort, got {other:?}"),
        }
    }
}

#[test]
fn nothing_listening_is_named_as_such_at_once() {
    // A port that was free a moment ago: nothing listens there.
    let addr = TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap();
    let started = Instant::now();
    let err = PortUrg::open_port(
        &format!("tcp:{addr}"),
        UrgConfig::default(),
        Backoff::default(),
    )
    .err()
    .expect("nothing listens");
    assert!(started.elapsed() < Duration::from_secs(3));
    match &err {
        UrgError::NoSuchAddress { addr: a, .. } => assert_eq!(a, &addr.to_string()),
        other => panic!("expected NoSuchAddress, got {other:?}"),
    }
    assert!(err.to_string().contains(&addr.to_string()));
}
