//! The real URG-04LX and UTM-30LX captures in ../shared/data/scip decode to their MANIFEST
//! facts, and the driver replays the URG-04LX session with the capture as its transport.

use std::io::{self, Read, Write};
use std::path::PathBuf;

use urg_driver::codec::{self, DataKind, RawScan, ScanRequest, StatusLine};
use urg_driver::{Command, PortConfig, ScipPort, SensorParams};

fn data_dir() -> Option<PathBuf> {
    let d = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../../shared/data/scip"
    ));
    if d.is_dir() {
        Some(d)
    } else {
        #[allow(clippy::print_stdout)]
        {
            println!("note: {} missing; capture tests skipped", d.display());
        }
        None
    }
}

/// Reads a flexiport log: records of u32be seconds, u32be microseconds, u32be length, bytes.
fn read_log(path: &PathBuf) -> Vec<Vec<u8>> {
    let bytes = std::fs::read(path).unwrap();
    let mut out = Vec::new();
    let mut i = 0;
    while i + 12 <= bytes.len() {
        let len = u32::from_be_bytes(bytes[i + 8..i + 12].try_into().unwrap()) as usize;
        out.push(bytes[i + 12..i + 12 + len].to_vec());
        i += 12 + len;
    }
    assert_eq!(i, bytes.len(), "{} ends inside a record", path.display());
    out
}

/// Splits a byte stream into its replies.
fn replies(stream: &[u8]) -> Vec<&[u8]> {
    let mut v = Vec::new();
    let mut rest = stream;
    while let Some(n) = codec::find_reply_end(rest) {
        v.push(&rest[..n]);
        rest = &rest[n..];
    }
    assert!(rest.is_empty(), "trailing bytes: {rest:?}");
    v
}

#[test]
fn urg_04lx_capture_decodes_to_manifest_facts() {
    let Some(d) = data_dir() else { return };
    let stream = std::fs::read(d.join("example_urg_04lx.logr.bin")).unwrap();
    let reps = replies(&stream);
    assert_eq!(reps.len(), 10, "VV VV PP II BM CR00 VV PP II GD");
    // Every info reply verifies with the ';' excluded from the sum.
    for r in &reps[..9] {
        let p = codec::parse_reply(r).unwrap();
        for line in codec::info_lines(&p) {
            line.unwrap();
        }
    }
    let pp = codec::parse_reply(reps[2]).unwrap();
    assert_eq!(
        SensorParams::from_reply(&pp).unwrap(),
        SensorParams::urg_04lx()
    );
    // BM -> 02 (already on), CR00 -> 03 (already at that speed).
    assert_eq!(
        codec::parse_reply(reps[4]).unwrap().status,
        StatusLine::Scip2(urg_driver::Status(*b"02"))
    );
    assert_eq!(
        codec::parse_reply(reps[5]).unwrap().status,
        StatusLine::Scip2(urg_driver::Status(*b"03"))
    );
    let mut raw = RawScan::default();
    codec::decode_scan_reply(reps[9], DataKind::Range3, &mut raw).unwrap();
    assert_eq!(raw.ranges_mm.len(), 682);
    assert_eq!(raw.timestamp_ms, 6_968_830);
    assert_eq!(raw.ranges_mm[340], 4152);
    // Error codes stay codes: the digest counts 94 x 0, 6 x 7 and 1 x 10 in this scan.
    let count = |c| raw.ranges_mm.iter().filter(|&&v| v == c).count();
    assert_eq!((count(0), count(7), count(10)), (94, 6, 1));
    let valid: Vec<u32> = raw.ranges_mm.iter().copied().filter(|&v| v >= 20).collect();
    assert_eq!(valid.iter().min(), Some(&76));
    assert_eq!(valid.iter().max(), Some(&4166));
    // As a Scan: code 0 is "nothing within range", the other codes are invalid readings.
    let p = SensorParams::urg_04lx();
    let scan = p.to_scan(&raw, Some(6_968_830), 0.0);
    use scan_types::RayStatus;
    let n = |s: RayStatus| scan.status.iter().filter(|&&x| x == s).count();
    assert_eq!(n(RayStatus::MaxRange), 94);
    assert_eq!(n(RayStatus::Error(7)), 6);
    assert_eq!(scan.ranges_m[340], 4.152);
}

#[test]
fn utm_30lx_capture_decodes_range_intensity_pairs() {
    let Some(d) = data_dir() else { return };
    let stream = std::fs::read(d.join("example_utm_30lx.logr.bin")).unwrap();
    let reps = replies(&stream);
    let pp = codec::parse_reply(reps[2]).unwrap();
    assert_eq!(
        SensorParams::from_reply(&pp).unwrap(),
        SensorParams::utm_30lx()
    );
    let last = reps.last().unwrap();
    let mut raw = RawScan::default();
    let r = codec::decode_scan_reply(last, DataKind::RangeIntensity, &mut raw).unwrap();
    assert_eq!(r.echo, b"ME0000108001100");
    assert_eq!(raw.timestamp_ms, 4_821_609);
    assert_eq!(raw.ranges_mm.len(), 1081);
    assert_eq!(raw.intensities.len(), 1081);
    assert_eq!((raw.ranges_mm[0], raw.intensities[0]), (45, 1809));
    assert_eq!((raw.ranges_mm[1], raw.intensities[1]), (48, 1780));
    // The ME acknowledgement came first: echo as sent, status 00, no data.
    let ack = codec::parse_reply(reps[reps.len() - 2]).unwrap();
    assert_eq!(ack.echo, b"ME0000108001101");
    assert!(ack.body.is_empty());
}

/// Serves the recorded reads in their recorded chunks and checks every write against the
/// recorded writes.
struct Replay {
    reads: std::collections::VecDeque<Vec<u8>>,
    expected_writes: Vec<u8>,
    written: Vec<u8>,
}

impl Read for Replay {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        let Some(mut chunk) = self.reads.pop_front() else {
            return Err(io::ErrorKind::TimedOut.into());
        };
        let n = chunk.len().min(buf.len());
        buf[..n].copy_from_slice(&chunk[..n]);
        if n < chunk.len() {
            chunk.drain(..n);
            self.reads.push_front(chunk);
        }
        Ok(n)
    }
}

impl Write for Replay {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.written.extend_from_slice(buf);
        assert!(
            self.expected_writes.starts_with(&self.written),
            "driver wrote {:?}, the capture has {:?}",
            String::from_utf8_lossy(&self.written),
            String::from_utf8_lossy(&self.expected_writes)
        );
        Ok(buf.len())
    }
    fn flush(&mut self) -> io::Result<()> {
        Ok(())
    }
}

#[test]
fn driver_replays_the_urg_04lx_session() {
    let Some(d) = data_dir() else { return };
    let reads = read_log(&d.join("example_urg_04lx.logr"));
    assert_eq!(reads.len(), 3222, "one byte per record");
    let writes: Vec<u8> = read_log(&d.join("example_urg_04lx.logw")).concat();
    assert_eq!(
        writes,
        std::fs::read(d.join("example_urg_04lx.logw.bin")).unwrap()
    );
    let replay = Replay {
        reads: reads.into(),
        expected_writes: writes.clone(),
        written: Vec::new(),
    };
    let mut port = ScipPort::new(replay, PortConfig::default());
    let v = port.version().unwrap();
    assert_eq!(v.product, "SOKUIKI Sensor URG-04LX");
    assert_eq!(port.version().unwrap(), v);
    let p = port.parameters().unwrap();
    assert_eq!(p.geometry().ray_count, 682);
    let s = port.state().unwrap();
    assert_eq!(s.time_ms, Some(0x6A5404));
    assert!(s.laser_on);
    assert!(!port.laser_on().unwrap(), "BM answers 02: already on");
    port.set_motor_speed(0).unwrap();
    port.version().unwrap();
    port.parameters().unwrap();
    let s2 = port.state().unwrap();
    assert_eq!(s2.time_ms, Some(0x6A55F8));
    let mut raw = RawScan::default();
    port.get_scan(&p.full_request(DataKind::Range3), &mut raw)
        .unwrap();
    assert_eq!(raw.timestamp_ms, 6_968_830);
    assert_eq!(raw.ranges_mm[340], 4152);
    let stats = port.stats();
    assert_eq!(
        (stats.scans, stats.checksum_errors, stats.malformed_replies),
        (1, 0, 0)
    );
    let replay = port.into_inner();
    assert_eq!(replay.written, writes, "the whole session was written");
    assert!(replay.reads.is_empty(), "every captured byte was read");
    // The request the capture used is the full-range GD.
    let mut line = Vec::new();
    Command::Get(ScanRequest {
        kind: DataKind::Range3,
        start_step: 44,
        end_step: 725,
        cluster: 1,
    })
    .encode(None, &mut line)
    .unwrap();
    assert!(writes.ends_with(&line));
}
