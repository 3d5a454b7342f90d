//! Property tests: random and mutated bytes never panic, and every single-character corruption
//! of a scan's time stamp or data lines is reported as an error.

use proptest::prelude::*;
use urg_driver::codec::{self, Command, DataKind, RawScan};
use urg_driver::{Emulator, Model, PortConfig, ScipPort};

/// A well-formed GD reply with `values` (3-character encoding).
fn gd_reply(values: &[u32], stamp: u32) -> Vec<u8> {
    let mut v = b"GD0044072501\n00P\n".to_vec();
    codec::encode_scan_body(stamp, values, &[], DataKind::Range3, &mut v);
    v.push(b'\n');
    v
}

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 256,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn random_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..600)) {
        let mut raw = RawScan::default();
        for kind in [DataKind::Range3, DataKind::Range2, DataKind::RangeIntensity] {
            let _ = codec::decode_scan_reply(&bytes, kind, &mut raw);
            let _ = codec::decode_scan_body(&bytes, 0, 3, kind, &mut raw);
        }
        if let Ok(r) = codec::parse_reply(&bytes) {
            for l in codec::info_lines(&r) { let _ = l; }
            let _ = urg_driver::SensorParams::from_reply(&r);
            let _ = urg_driver::StateInfo::from_reply(&r);
        }
        let _ = codec::find_reply_end(&bytes);
        let _ = Command::parse(&bytes);
        let _ = codec::decode_value(&bytes[..bytes.len().min(6)]);
    }

    #[test]
    fn the_emulator_survives_any_command_bytes(bytes in proptest::collection::vec(any::<u8>(), 0..300)) {
        use std::io::{Read, Write};
        let mut emu = Emulator::fixed(Model::Urg04lx);
        emu.write_all(&bytes).unwrap();
        emu.write_all(b"\nVV\n").unwrap();
        let mut out = Vec::new();
        let mut buf = [0u8; 4096];
        // Drain until quiet (streams started by random MD lines are stopped by QT below).
        for _ in 0..50 {
            match emu.read(&mut buf) { Ok(n) => out.extend_from_slice(&buf[..n]), Err(_) => break }
            if out.windows(4).any(|w| w == b"VV\n0") { break; }
        }
        prop_assert!(out.windows(4).any(|w| w == b"VV\n0"), "VV still answered");
    }

    #[test]
    fn the_driver_survives_random_replies(bytes in proptest::collection::vec(any::<u8>(), 0..800)) {
        let t = std::time::Duration::from_millis(5);
        let mut p = ScipPort::new(std::io::Cursor::new(bytes), PortConfig { command_timeout: t, scan_timeout: t });
        // A Cursor ignores writes past its data and reads its bytes back: any outcome but a panic.
        let _ = p.version();
        let _ = p.parameters();
        let mut raw = RawScan::default();
        let _ = p.get_scan(&urg_driver::SensorParams::urg_04lx().full_request(DataKind::Range3), &mut raw);
    }

    #[test]
    fn every_single_character_corruption_is_an_error(
        values in proptest::collection::vec(0u32..4096, 1..120),
        stamp in 0u32..(1 << 24),
        pick in any::<proptest::sample::Index>(),
        replacement in any::<u8>(),
    ) {
        let reply = gd_reply(&values, stamp);
        let mut raw = RawScan::default();
        codec::decode_scan_reply(&reply, DataKind::Range3, &mut raw).unwrap();
        prop_assert_eq!(&raw.ranges_mm, &values);
        prop_assert_eq!(raw.timestamp_ms, stamp);
        // Corrupt one character of the time stamp or data lines (not their LFs).
        let body_start = 17;
        let body_end = reply.len() - 1;
        let positions: Vec<usize> = (body_start..body_end).filter(|&i| reply[i] != b'\n').collect();
        let at = positions[pick.index(positions.len())];
        prop_assume!(replacement != reply[at]);
        let mut bad = reply.clone();
        bad[at] = replacement;
        let r = codec::decode_scan_reply(&bad, DataKind::Range3, &mut raw);
        prop_assert!(r.is_err(), "corruption at {} to {:#x} went unnoticed", at, replacement);
    }
}

#[test]
fn a_full_urg_04lx_reply_round_trips() {
    let values: Vec<u32> = (0..682).map(|i| (i * 37) % 5600).collect();
    let reply = gd_reply(&values, 6_968_830);
    // Echo 13, status 4, time stamp 6, 2046 data characters in 32 lines (+ checksum and LF each), blank 1.
    assert_eq!(reply.len(), 13 + 4 + 6 + 2046 + 32 * 2 + 1);
    let mut raw = RawScan::default();
    codec::decode_scan_reply(&reply, DataKind::Range3, &mut raw).unwrap();
    assert_eq!(raw.ranges_mm, values);
}
