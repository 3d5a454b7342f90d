//! Driver against the in-memory emulator: normal operation and every fault the issue names.

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use scan_types::{LaserSource, RayStatus, Scan, ScanGeometry};
use urg_driver::{
    AcquisitionMode, Backoff, Emulator, EmulatorControl, Fault, FixedSource, Model, PortConfig,
    Profile, ReconnectingUrg, Urg, UrgConfig, UrgError,
};

fn streaming() -> UrgConfig {
    UrgConfig {
        mode: AcquisitionMode::Streaming,
        time_sync_rounds: 3,
        ..UrgConfig::default()
    }
}

fn quick_timeouts(c: UrgConfig) -> UrgConfig {
    UrgConfig {
        port: PortConfig {
            command_timeout: Duration::from_millis(150),
            scan_timeout: Duration::from_millis(150),
        },
        ..c
    }
}

#[test]
fn fixed_scan_reads_back_as_its_geometry_says() {
    for mode in [AcquisitionMode::Polled, AcquisitionMode::Streaming] {
        let cfg = UrgConfig {
            mode,
            ..UrgConfig::default()
        };
        let mut urg = Urg::connect(Emulator::fixed(Model::Urg04lx), cfg).unwrap();
        let g = *urg.geometry();
        let s = urg.next_scan().unwrap();
        s.validate(&g).unwrap();
        // Wall x = 3 m straight ahead (index 340 = step 384 = AFRT).
        assert_eq!(s.ranges_m[340], 3.0);
        // Step 128 is -90 deg: the injected error code 7.
        assert_eq!(s.status[84], RayStatus::Error(7));
        assert!(s.ranges_m[84].is_nan());
        // 45 deg left: wall y = 2.5 at 2.5/sin(45 deg) = 3.5355 m (mm resolution).
        let i45 = g.nearest_index(45f64.to_radians()).unwrap();
        let expected = 2.5 / g.bearing_rad(i45).sin();
        assert!(
            (s.ranges_m[i45] - expected).abs() <= 0.0005,
            "{}",
            s.ranges_m[i45]
        );
        // The door at 60..70 deg reads "nothing within range" at DMAX.
        let door = g.nearest_index(65f64.to_radians()).unwrap();
        assert_eq!(s.status[door], RayStatus::MaxRange);
        assert_eq!(s.ranges_m[door], 5.6);
    }
}

#[test]
fn utm_30lx_profile_streams_intensities() {
    let cfg = UrgConfig {
        kind: urg_driver::DataKind::RangeIntensity,
        ..streaming()
    };
    let mut urg = Urg::connect(Emulator::fixed(Model::Utm30lx), cfg).unwrap();
    assert_eq!(urg.geometry().ray_count, 1081);
    let s = urg.next_scan().unwrap();
    assert_eq!(s.ranges_m[540], 3.0);
    let i = s.intensities.as_ref().unwrap();
    assert_eq!(i.len(), 1081);
    assert_eq!(i[540], 1000.0);
    let b = urg.next_scan().unwrap();
    // 2400 rpm: 25 ms per scan.
    assert_eq!(b.sensor_time_ms.unwrap() - s.sensor_time_ms.unwrap(), 25);
}

#[test]
fn intensity_on_urg_04lx_is_unsupported_and_the_device_keeps_working() {
    let mut urg = Urg::connect(Emulator::fixed(Model::Urg04lx), UrgConfig::default()).unwrap();
    let req = urg
        .params()
        .full_request(urg_driver::DataKind::RangeIntensity);
    let mut raw = urg_driver::RawScan::default();
    let e = urg.get_scan(&req, &mut raw).unwrap_err();
    assert!(
        matches!(e, UrgError::Unsupported { ref command } if command == "GE"),
        "{e}"
    );
    assert!(matches!(
        urg.set_high_sensitivity(true),
        Err(UrgError::Unsupported { .. })
    ));
    assert_eq!(urg.next_scan().unwrap().ranges_m[340], 3.0);
}

#[test]
fn all_info_and_setting_commands_answer() {
    let emu = Emulator::fixed(Model::Urg04lx);
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, UrgConfig::default()).unwrap();
    let v = urg.version().unwrap();
    assert_eq!(v.firmware, "3.1.04(02/Aug./2007)");
    let st = urg.state().unwrap();
    assert!(st.laser_on && st.status == "Sensor works well.");
    urg.set_motor_speed(0).unwrap(); // 03 "already" is fine
    urg.set_motor_speed(5).unwrap();
    assert!(matches!(
        urg.set_motor_speed(42),
        Err(UrgError::Status { .. })
    ));
    urg.set_bit_rate(115_200).unwrap();
    let e = urg.set_bit_rate(1234).unwrap_err();
    assert!(e.to_string().contains("invalid bit rate"), "{e}");
    urg.laser_off().unwrap();
    assert!(!urg.state().unwrap().laser_on);
    // GD with the laser off: status 10, named.
    let mut raw = urg_driver::RawScan::default();
    let req = *urg.request();
    let e = urg.get_scan(&req, &mut raw).unwrap_err();
    assert!(e.to_string().contains("laser is off"), "{e}");
    assert!(urg.laser_on().unwrap());
    urg.reset().unwrap();
    assert!(urg.time_adjust(true).is_ok());
    let t1 = urg.read_time().unwrap();
    let t2 = urg.read_time().unwrap();
    assert!(t2 > t1);
    urg.time_adjust(false).unwrap();
    assert!(matches!(urg.read_time(), Err(UrgError::Status { .. })));
    let cmds = ctl.commands();
    for c in [
        "VV", "II", "CR00", "CR05", "SS115200", "QT", "BM", "RS", "TM0", "TM1", "TM2",
    ] {
        assert!(cmds.iter().any(|x| x == c), "{c} never sent: {cmds:?}");
    }
}

#[test]
fn connect_sequence_matches_urg_library_and_switches_scip1() {
    // urg_library opens with LF, QT, then PP. A factory URG-04LX answers QT in SCIP 1.1.
    let emu = Emulator::fixed(Model::Urg04lx).scip1_at_power_up();
    let ctl = emu.control();
    let cfg = UrgConfig {
        time_sync_rounds: 0,
        ..UrgConfig::default()
    };
    let mut urg = Urg::connect(emu, cfg).unwrap();
    assert_eq!(
        ctl.commands(),
        vec!["QT", "SCIP2.0", "QT", "PP", "BM"],
        "the lone LF is not a command"
    );
    assert_eq!(urg.next_scan().unwrap().ranges_m[340], 3.0);
    // Already in SCIP 2.0: LF, QT, PP.
    let emu = Emulator::fixed(Model::Urg04lx);
    let ctl = emu.control();
    Urg::connect(emu, cfg).unwrap();
    assert_eq!(ctl.commands()[..2], ["QT", "PP"]);
}

#[test]
fn connect_leaves_time_adjust_mode() {
    let mut emu = Emulator::fixed(Model::Urg04lx);
    use std::io::{Read, Write};
    emu.write_all(b"TM0\n").unwrap();
    let mut b = [0u8; 64];
    let _ = emu.read(&mut b).unwrap();
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, UrgConfig::default()).unwrap();
    assert_eq!(ctl.commands()[1..4], ["QT", "TM2", "QT"]);
    urg.next_scan().unwrap();
}

/// A source that counts its scans and puts the count in ray 0 (as millimetres).
#[derive(Clone)]
struct Counting {
    g: ScanGeometry,
    n: Arc<Mutex<u32>>,
}
impl LaserSource for Counting {
    type Error = std::convert::Infallible;
    fn geometry(&self) -> &ScanGeometry {
        &self.g
    }
    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        let mut n = self.n.lock().unwrap();
        *n += 1;
        let mut r = vec![1.0; self.g.ray_count];
        r[0] = f64::from(*n) / 10.0;
        Ok(Scan::from_ranges(&self.g, &r, 0.0))
    }
}

#[test]
fn one_source_scan_per_driver_scan_in_both_modes() {
    for mode in [AcquisitionMode::Polled, AcquisitionMode::Streaming] {
        let p = Profile::of(Model::Urg04lx);
        let src = Counting {
            g: p.params.geometry(),
            n: Arc::default(),
        };
        let n = src.n.clone();
        let cfg = UrgConfig {
            mode,
            ..UrgConfig::default()
        };
        let mut urg = Urg::connect(Emulator::new(p, src), cfg).unwrap();
        let mut last_stamp = None;
        for k in 1..=5u32 {
            let s = urg.next_scan().unwrap();
            let stamp = s.sensor_time_ms.unwrap();
            if let Some(l) = last_stamp {
                assert_eq!(stamp - l, 100, "{mode:?}: one sensor period per scan");
            }
            last_stamp = Some(stamp);
            assert_eq!(s.ranges_m[0], f64::from(k) / 10.0, "{mode:?}");
            assert_eq!(*n.lock().unwrap(), k, "{mode:?}");
        }
    }
}

#[test]
fn timestamps_unwrap_across_the_24_bit_wrap_and_map_to_host_time() {
    let emu = Emulator::fixed(Model::Urg04lx).timer_at((1 << 24) - 350);
    let mut urg = Urg::connect(emu, streaming()).unwrap();
    let off = urg.time_offset_s().unwrap();
    let mut last = None;
    for _ in 0..8 {
        let s = urg.next_scan().unwrap();
        let t = s.sensor_time_ms.unwrap();
        if let Some(l) = last {
            assert_eq!(t - l, 100, "monotonic across the wrap");
        }
        assert!((s.host_time_s - (off + t as f64 / 1000.0)).abs() < 1e-9);
        last = Some(t);
    }
    assert!(last.unwrap() > 1 << 24, "the stream crossed the wrap");
}

#[test]
fn reset_restarts_the_sensor_clock_and_scans_go_on() {
    let mut urg = Urg::connect(
        Emulator::fixed(Model::Urg04lx).timer_at(5_000_000),
        UrgConfig::default(),
    )
    .unwrap();
    let before = urg.next_scan().unwrap().sensor_time_ms.unwrap();
    assert!(before >= 5_000_000);
    urg.reset().unwrap();
    // RS set the sensor timer to 0: the next stamps are small, not a wrap.
    let after = urg.next_scan().unwrap().sensor_time_ms.unwrap();
    assert!(after < 1_000, "{after}");
    assert!(urg.time_offset_s().is_some());
}

#[test]
fn checksum_error_drops_one_scan_and_is_counted() {
    let emu = Emulator::fixed(Model::Urg04lx);
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, streaming()).unwrap();
    let a = urg.next_scan().unwrap();
    ctl.inject(Fault::CorruptChecksum);
    let b = urg.next_scan().unwrap();
    // The corrupted scan (a + 100 ms) was dropped; the next one arrived.
    assert_eq!(b.sensor_time_ms.unwrap() - a.sensor_time_ms.unwrap(), 200);
    assert_eq!(urg.stats().checksum_errors, 1);
    assert_eq!(b.ranges_m[340], 3.0);
    // Polled mode: the dropped scan is taken again.
    let emu = Emulator::fixed(Model::Urg04lx);
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, UrgConfig::default()).unwrap();
    ctl.inject(Fault::CorruptChecksum);
    urg.next_scan().unwrap();
    assert_eq!(urg.stats().checksum_errors, 1);
    assert_eq!(ctl.scans_served(), 2);
}

#[test]
fn garbage_and_truncation_resynchronise_on_the_next_blank_line() {
    let emu = Emulator::fixed(Model::Urg04lx).max_read_chunk(7);
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, streaming()).unwrap();
    let a = urg.next_scan().unwrap().sensor_time_ms.unwrap();
    ctl.inject(Fault::Garbage(b"\x00\xffnoise;;\n\x7f\n\n".to_vec()));
    let b = urg.next_scan().unwrap().sensor_time_ms.unwrap();
    assert_eq!(b - a, 100, "garbage ends at its blank line; no scan lost");
    ctl.inject(Fault::TruncateReply);
    let c = urg.next_scan().unwrap().sensor_time_ms.unwrap();
    // The truncated scan merges with the next up to its blank line: both are lost.
    assert_eq!(c - b, 300);
    assert!(urg.stats().malformed_replies + urg.stats().checksum_errors >= 1);
    let d = urg.next_scan().unwrap().sensor_time_ms.unwrap();
    assert_eq!(d - c, 100);
}

#[test]
fn a_stalled_sensor_is_a_timeout_not_a_hang() {
    let emu = Emulator::fixed(Model::Urg04lx);
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, quick_timeouts(streaming())).unwrap();
    urg.next_scan().unwrap();
    ctl.set_stalled(true);
    let t = Instant::now();
    let e = urg.next_scan().unwrap_err();
    assert!(matches!(e, UrgError::Timeout { .. }), "{e}");
    assert!(t.elapsed() < Duration::from_secs(2));
    let t = Instant::now();
    assert!(matches!(urg.version(), Err(UrgError::Timeout { .. })));
    assert!(t.elapsed() < Duration::from_secs(2));
    ctl.set_stalled(false);
    assert_eq!(urg.version().unwrap().serial, "H0706400");
}

#[test]
fn hardware_fault_status_is_named() {
    let emu = Emulator::fixed(Model::Urg04lx);
    let ctl = emu.control();
    let mut urg = Urg::connect(emu, streaming()).unwrap();
    urg.next_scan().unwrap();
    ctl.inject(Fault::HardwareStatus(*b"55"));
    let e = urg.next_scan().unwrap_err();
    match &e {
        UrgError::HardwareFault { status, .. } => assert_eq!(status.as_str(), "55"),
        other => panic!("{other}"),
    }
    assert!(e.to_string().contains("hardware fault"), "{e}");
    // The stream stopped; the next call restarts it.
    urg.next_scan().unwrap();
}

#[test]
fn unplug_gives_disconnected_and_reconnect_resumes_the_stream() {
    let ctl = EmulatorControl::default();
    let opens = Arc::new(Mutex::new(0u32));
    let (c2, o2) = (ctl.clone(), opens.clone());
    let open = move || {
        *o2.lock().unwrap() += 1;
        if c2.is_plugged() {
            Ok(Emulator::with_control(
                Profile::of(Model::Urg04lx),
                FixedSource::room(Profile::of(Model::Urg04lx).params.geometry()),
                c2.clone(),
            ))
        } else {
            Err(std::io::Error::new(
                std::io::ErrorKind::NotFound,
                "no such device",
            ))
        }
    };
    // The bare driver reports Disconnected.
    let mut plain = Urg::connect(open.clone()().unwrap(), streaming()).unwrap();
    plain.next_scan().unwrap();
    ctl.unplug();
    assert!(matches!(plain.next_scan(), Err(UrgError::Disconnected(_))));
    ctl.plug();

    let backoff = Backoff {
        initial: Duration::from_millis(5),
        max: Duration::from_millis(40),
        factor: 2.0,
        max_attempts: Some(50),
        cancel: None,
    };
    let mut src = ReconnectingUrg::new(open, streaming(), backoff).unwrap();
    src.next_scan().unwrap();
    ctl.unplug();
    let c3 = ctl.clone();
    let replug = std::thread::spawn(move || {
        std::thread::sleep(Duration::from_millis(60));
        c3.plug();
    });
    let s = src.next_scan().unwrap();
    replug.join().unwrap();
    assert_eq!(s.ranges_m[340], 3.0);
    assert_eq!(src.reconnects(), 1);
    assert!(*opens.lock().unwrap() >= 3, "it retried while unplugged");
    src.next_scan().unwrap();
    assert_eq!(backoff.delay(0), Duration::from_millis(5));
    assert_eq!(backoff.delay(2), Duration::from_millis(20));
    assert_eq!(backoff.delay(10), Duration::from_millis(40));

    // Giving up: a bounded backoff returns Disconnected.
    ctl.unplug();
    let give_up = Backoff {
        max_attempts: Some(3),
        ..backoff
    };
    let c4 = ctl.clone();
    let mut open2 = move || {
        if c4.is_plugged() {
            unreachable!()
        } else {
            Err::<Emulator<FixedSource>, _>(std::io::Error::from(std::io::ErrorKind::NotFound))
        }
    };
    let e = urg_driver::connect_with_backoff(&mut open2, &streaming(), &give_up).unwrap_err();
    assert!(matches!(e, UrgError::Disconnected(_)), "{e}");
}

#[test]
fn counted_stream_ends_after_its_scans() {
    let mut urg = Urg::connect(
        Emulator::fixed(Model::Urg04lx),
        quick_timeouts(UrgConfig::default()),
    )
    .unwrap();
    let req = urg_driver::StreamRequest {
        scan: *urg.request(),
        skip: 1,
        count: 2,
    };
    urg.start_stream(&req).unwrap();
    let mut raw = urg_driver::RawScan::default();
    urg.read_stream_scan(req.scan.kind, &mut raw).unwrap();
    let t0 = raw.timestamp_ms;
    urg.read_stream_scan(req.scan.kind, &mut raw).unwrap();
    // skip 1: every other scan, 200 ms apart.
    assert_eq!(raw.timestamp_ms - t0, 200);
    assert!(matches!(
        urg.read_stream_scan(req.scan.kind, &mut raw),
        Err(UrgError::Timeout { .. })
    ));
}

#[test]
fn decoding_reuses_the_callers_buffers() {
    let mut urg = Urg::connect(Emulator::fixed(Model::Urg04lx), streaming()).unwrap();
    let p = urg.next_raw().unwrap().ranges_mm.as_ptr();
    for _ in 0..20 {
        let raw = urg.next_raw().unwrap();
        assert_eq!(raw.ranges_mm.as_ptr(), p, "no reallocation in steady state");
    }
}

#[test]
fn polled_scans_come_at_the_sensor_period_on_the_real_clock() {
    // A real sensor answers GD with its next scan: N polled scans take about N - 1 periods of
    // wall time, their stamps are one period apart, and none lies ahead of the sensor's own
    // clock (II TIME) read after them.
    let emu = Emulator::fixed(Model::Urg04lx).real_time();
    let cfg = UrgConfig {
        time_sync_rounds: 3,
        ..UrgConfig::default()
    };
    let mut urg = Urg::connect(emu, cfg).unwrap();
    let period_ms = urg.params().scan_period().as_millis() as u64;
    assert_eq!(period_ms, 100, "URG-04LX: 600 rpm");
    let started = Instant::now();
    let mut stamps = Vec::new();
    for _ in 0..8 {
        stamps.push(urg.next_scan().unwrap().sensor_time_ms.unwrap());
    }
    let elapsed = started.elapsed();
    assert!(
        elapsed >= Duration::from_millis(6 * period_ms),
        "8 polled scans in {elapsed:?}"
    );
    for w in stamps.windows(2) {
        assert_eq!(w[1] - w[0], period_ms, "{stamps:?}");
    }
    let time = u64::from(urg.state().unwrap().time_ms.unwrap());
    assert!(
        time >= *stamps.last().unwrap(),
        "II TIME {time} < last stamp {stamps:?}"
    );
}
