//! Any bytes as a sensor reply: the codec and the driver must never panic, and whatever decodes
//! must re-encode to the same values.
#![no_main]

use libfuzzer_sys::fuzz_target;
use urg_driver::codec::{self, DataKind, RawScan};
use urg_driver::{PortConfig, ScipPort, SensorParams};

fuzz_target!(|data: &[u8]| {
    let mut raw = RawScan::default();
    for kind in [DataKind::Range3, DataKind::Range2, DataKind::RangeIntensity] {
        if let Ok(r) = codec::decode_scan_reply(data, kind, &mut raw) {
            // Round trip: the decoded values encode back into the same body.
            let mut body = Vec::new();
            codec::encode_scan_body(raw.timestamp_ms, &raw.ranges_mm, &raw.intensities, kind, &mut body);
            let mut again = RawScan::default();
            codec::decode_scan_body(&body, 0, 3, kind, &mut again).unwrap();
            assert_eq!(again.ranges_mm, raw.ranges_mm);
            assert_eq!(again.intensities, raw.intensities);
            let _ = r.echo;
        }
    }
    if let Ok(r) = codec::parse_reply(data) {
        for l in codec::info_lines(&r) {
            let _ = l;
        }
        let _ = SensorParams::from_reply(&r);
    }
    let _ = codec::Command::parse(data);
    let t = std::time::Duration::from_millis(1);
    let mut port = ScipPort::new(
        std::io::Cursor::new(data.to_vec()),
        PortConfig { command_timeout: t, scan_timeout: t },
    );
    let _ = port.parameters();
    let _ = port.get_scan(&SensorParams::urg_04lx().full_request(DataKind::Range3), &mut raw);
});
