//! End to end: the driver opens the emulator through a real pseudo-terminal, as it would open
//! `/dev/ttyACM0`, connects, reads VV/PP/II, synchronises clocks, streams and polls scans.
#![allow(clippy::print_stderr, clippy::print_stdout)] // benches and tests report to the terminal

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
    // A stable link to the current pseudo-terminal, as udev makes for a USB sensor.
    let device = std::fs::read_link(server.path()).expect("a link");
    assert!(device.starts_with("/dev/pts/"), "{}", device.display());
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

/// Writes `cmd` and reads one whole reply (up to its blank line), as a raw serial client does.
fn exchange(port: &mut Box<dyn serialport::SerialPort>, cmd: &[u8]) -> Vec<u8> {
    port.write_all(cmd).unwrap();
    read_reply(port)
}

fn read_reply(port: &mut Box<dyn serialport::SerialPort>) -> Vec<u8> {
    let deadline = std::time::Instant::now() + Duration::from_secs(2);
    let mut got = Vec::new();
    let mut buf = [0u8; 512];
    while urg_driver::codec::find_reply_end(&got) != Some(got.len()) || got.is_empty() {
        assert!(
            std::time::Instant::now() < deadline,
            "no complete reply: {got:?}"
        );
        if let Ok(n) = port.read(&mut buf) {
            got.extend_from_slice(&buf[..n]);
        }
    }
    got
}

fn quiet_bytes(port: &mut Box<dyn serialport::SerialPort>) -> usize {
    let mut n = 0;
    let mut buf = [0u8; 512];
    let end = std::time::Instant::now() + Duration::from_millis(150);
    while std::time::Instant::now() < end {
        if let Ok(k) = port.read(&mut buf) {
            n += k;
        }
    }
    n
}

fn capture_replies() -> Option<Vec<Vec<u8>>> {
    let p = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../shared/data/scip/example_urg_04lx.logr.bin"
    );
    let Ok(stream) = std::fs::read(p) else {
        #[allow(clippy::print_stdout)]
        {
            println!("note: {p} missing; byte comparison with the capture skipped");
        }
        return None;
    };
    let mut v = Vec::new();
    let mut rest = &stream[..];
    while let Some(n) = urg_driver::codec::find_reply_end(rest) {
        v.push(rest[..n].to_vec());
        rest = &rest[n..];
    }
    Some(v)
}

use std::io::{Read, Write};

/// Hokuyo's urg_library is not packaged for Debian, so this client replays, byte for byte, the
/// exchanges urg_library makes: its connect procedure (LF, QT; a one-character `E` means
/// SCIP 1.1 -> SCIP2.0; `0Ee` means time-adjust mode -> TM2), PP, laser on, single scans,
/// streaming, stopping and time-stamp synchronisation. Each reply is checked the way
/// urg_library checks it (echo, status, per-line checksums, line counts).
#[test]
fn emulator_answers_the_urg_library_exchanges_byte_for_byte() {
    let mut profile = Profile::of(Model::Urg04lx);
    profile.scip1_at_power_up = true;
    let server = serve_pty(
        profile.clone(),
        FixedSource::room(profile.params.geometry()),
    )
    .unwrap();
    let mut port = serialport::new(server.path(), 115_200)
        .timeout(Duration::from_millis(10))
        .open()
        .unwrap();

    // Connect: a lone LF is drained (nothing comes back), then QT.
    port.write_all(b"\n").unwrap();
    assert_eq!(quiet_bytes(&mut port), 0);
    assert_eq!(
        exchange(&mut port, b"QT\n"),
        b"QT\nE\n\n",
        "SCIP 1.1 answer"
    );
    assert_eq!(exchange(&mut port, b"SCIP2.0\n"), b"SCIP2.0\n0\n\n");
    assert_eq!(exchange(&mut port, b"QT\n"), b"QT\n00P\n\n");

    check_info_replies(&mut port);
    check_scans(&mut port);
    check_streaming(&mut port);
    check_time_stamps(&mut port);
}

/// The emulator's serial port, as urg_library opens it.
type Port = Box<dyn serialport::SerialPort>;

/// PP and VV are byte-identical to the real URG-04LX; II has the same lines but TIME.
fn check_info_replies(port: &mut Port) {
    let pp = exchange(port, b"PP\n");
    let vv = exchange(port, b"VV\n");
    let ii = exchange(port, b"II\n");
    // urg_library's line counts: PP 10, VV 7, II 9 (after the echo, blank line included).
    let lines = |r: &[u8]| r.iter().filter(|&&c| c == b'\n').count() - 1;
    assert_eq!((lines(&pp), lines(&vv), lines(&ii)), (10, 7, 9));
    if let Some(cap) = capture_replies() {
        assert_eq!(pp, cap[2]);
        assert_eq!(vv, cap[0]);
        let keep = |r: &[u8]| -> Vec<String> {
            String::from_utf8_lossy(r)
                .lines()
                .filter(|l| !l.starts_with("TIME:") && !l.starts_with("LASR:"))
                .map(str::to_string)
                .collect()
        };
        assert_eq!(keep(&ii), keep(&cap[3]));
    }
}

/// Laser on, then one scan (GD): status 00, time stamp line, 32 data lines, blank line; GS too.
fn check_scans(port: &mut Port) {
    assert_eq!(exchange(port, b"BM\n"), b"BM\n00P\n\n");
    assert_eq!(exchange(port, b"BM\n"), b"BM\n02R\n\n");
    let gd = exchange(port, b"GD0044072501\n");
    let gd_lines: Vec<&[u8]> = gd.split(|&c| c == b'\n').collect();
    assert_eq!(gd_lines[0], b"GD0044072501");
    assert_eq!(gd_lines[1], b"00P");
    assert_eq!(gd_lines.len(), 2 + 1 + 32 + 2);
    for l in &gd_lines[2..gd_lines.len() - 2] {
        let (body, sum) = l.split_at(l.len() - 1);
        assert_eq!(urg_driver::codec::checksum(body), sum[0]);
    }
    // GS (2-character values) too.
    let gs = exchange(port, b"GS0044072501\n");
    assert!(gs.starts_with(b"GS0044072501\n00P\n"));
}

/// Streaming: the acknowledgement, then scans whose echo counts down; QT stops it.
fn check_streaming(port: &mut Port) {
    assert_eq!(
        exchange(port, b"MD0044072501002\n"),
        b"MD0044072501002\n00P\n\n"
    );
    assert!(read_reply(port).starts_with(b"MD0044072501001\n99b\n"));
    assert!(read_reply(port).starts_with(b"MD0044072501000\n99b\n"));
    assert_eq!(
        exchange(port, b"MD0044072501000\n"),
        b"MD0044072501000\n00P\n\n"
    );
    assert!(read_reply(port).starts_with(b"MD0044072501000\n99b\n"));
    port.write_all(b"QT\n").unwrap();
    let mut seen_qt = false;
    for _ in 0..4 {
        if read_reply(port) == b"QT\n00P\n\n" {
            seen_qt = true;
            break;
        }
    }
    assert!(seen_qt, "QT acknowledged within a few in-flight scans");
}

/// Time stamps: TM0, TM1 (one 4-character time line with its checksum), TM2; the time-adjust
/// mode's connect; intensities refused on a URG-04LX.
fn check_time_stamps(port: &mut Port) {
    assert_eq!(exchange(port, b"TM0\n"), b"TM0\n00P\n\n");
    let tm1 = exchange(port, b"TM1\n");
    assert_eq!(&tm1[..8], b"TM1\n00P\n");
    assert_eq!(tm1.len(), 8 + 5 + 2);
    assert_eq!(urg_driver::codec::checksum(&tm1[8..12]), tm1[12]);
    // A connect while in time-adjust mode: QT answers 0Ee, and TM2 leaves the mode.
    assert_eq!(exchange(port, b"QT\n"), b"QT\n0Ee\n\n");
    assert_eq!(exchange(port, b"TM2\n"), b"TM2\n00P\n\n");
    assert_eq!(exchange(port, b"QT\n"), b"QT\n00P\n\n");
    // Intensities on a URG-04LX: 0E, and the device keeps working.
    assert_eq!(exchange(port, b"GE0044072501\n"), b"GE0044072501\n0Ee\n\n");
    assert_eq!(exchange(port, b"QT\n"), b"QT\n00P\n\n");
}
