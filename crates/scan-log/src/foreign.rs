//! Laser scans written by other tools: ROS 2 `sensor_msgs/msg/LaserScan` in CDR, Foxglove
//! `foxglove.LaserScan` in protobuf and in plain JSON, decoded into one form and turned into
//! goalseek scans with the writer's meaning of every reading kept.
//!
//! The decoders take any byte string: every length is checked against the bytes that are
//! left before anything is allocated, so a length field claiming gigabytes is refused.

use scan_types::{RayStatus, Scan, ScanGeometry};
use serde::Deserialize;

use crate::LogRecord;

/// Error code of a reading that is not a number (NaN).
pub const INVALID_NAN: u16 = 1;
/// Error code of a reading below the minimum range (ROS `range_min`; -inf; Foxglove: 0 or less).
pub const INVALID_BELOW_MIN: u16 = 2;
/// Error code of a finite reading beyond ROS `range_max`.
pub const INVALID_ABOVE_MAX: u16 = 3;

/// ROS 2 type name of a laser scan.
pub const ROS2_LASER_SCAN: &str = "sensor_msgs/msg/LaserScan";
/// Foxglove schema name of a laser scan.
pub const FOXGLOVE_LASER_SCAN: &str = "foxglove.LaserScan";

/// A decoded laser scan of another tool, before it becomes a goalseek [`Scan`].
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ForeignScan {
    /// Time stamp, seconds.
    pub stamp_s: f64,
    /// Bearing of the first ray, radians.
    pub first_rad: f64,
    /// Angle between rays, radians (Foxglove: from `end_angle`).
    pub increment_rad: f64,
    /// ROS `range_min`, `range_max`; Foxglove gives none.
    pub limits_m: Option<(f64, f64)>,
    /// The readings as written.
    pub ranges: Vec<f64>,
    /// Intensities, empty when none are written.
    pub intensities: Vec<f64>,
}

/// Reads CDR (the encapsulation header, then the message) with bounds checks.
struct Cdr<'a> {
    body: &'a [u8],
    pos: usize,
    little: bool,
}

impl<'a> Cdr<'a> {
    fn new(bytes: &'a [u8]) -> Result<Self, String> {
        let Some((head, body)) = bytes.split_first_chunk::<4>() else {
            return Err(format!(
                "{} bytes, too short for the 4-byte CDR encapsulation header",
                bytes.len()
            ));
        };
        // Representation identifiers: plain CDR and plain CDR2 (the same layout for a
        // message without 8-byte fields), big- and little-endian.
        let little = match [head[0], head[1]] {
            [0, 0] | [0, 6] => false,
            [0, 1] | [0, 7] => true,
            id => {
                return Err(format!(
                    "CDR encapsulation {:02x}{:02x} is not supported (plain CDR or CDR2, 0000/0001/0006/0007)",
                    id[0], id[1]
                ));
            }
        };
        Ok(Cdr {
            body,
            pos: 0,
            little,
        })
    }

    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let left = self.body.len() - self.pos;
        if n > left {
            return Err(format!(
                "{what}: needs {n} bytes at offset {}, {left} left",
                self.pos + 4
            ));
        }
        let s = &self.body[self.pos..self.pos + n];
        self.pos += n;
        Ok(s)
    }

    fn align4(&mut self, what: &str) -> Result<(), String> {
        let pad = (4 - self.pos % 4) % 4;
        self.take(pad, what).map(|_| ())
    }

    fn word(&mut self, what: &str) -> Result<[u8; 4], String> {
        self.align4(what)?;
        let b = self.take(4, what)?;
        let w = [b[0], b[1], b[2], b[3]];
        Ok(if self.little {
            w
        } else {
            [w[3], w[2], w[1], w[0]]
        })
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        self.word(what).map(u32::from_le_bytes)
    }

    fn f32(&mut self, what: &str) -> Result<f64, String> {
        self.word(what).map(|w| f64::from(f32::from_le_bytes(w)))
    }

    /// A string: length (with its terminating NUL), bytes.
    fn string(&mut self, what: &str) -> Result<String, String> {
        let n = self.u32(what)? as usize;
        let b = self.take(n, what)?;
        let b = b.strip_suffix(&[0]).unwrap_or(b);
        Ok(String::from_utf8_lossy(b).into_owned())
    }

    /// A `float32[]`: count, values. The count is checked against the bytes left first.
    fn f32_seq(&mut self, what: &str) -> Result<Vec<f64>, String> {
        let n = self.u32(what)? as usize;
        let left = self.body.len() - self.pos;
        if n > left / 4 {
            return Err(format!(
                "{what}: {n} values announced, only {left} bytes left (at most {})",
                left / 4
            ));
        }
        (0..n).map(|_| self.f32(what)).collect()
    }
}

/// Decodes a CDR `sensor_msgs/msg/LaserScan` (with its 4-byte encapsulation header).
pub(crate) fn decode_ros2_laser_scan(bytes: &[u8]) -> Result<ForeignScan, String> {
    let mut c = Cdr::new(bytes)?;
    let sec = c.u32("header.stamp.sec")? as i32;
    let nanosec = c.u32("header.stamp.nanosec")?;
    let _frame_id = c.string("header.frame_id")?;
    let angle_min = c.f32("angle_min")?;
    let _angle_max = c.f32("angle_max")?;
    let angle_increment = c.f32("angle_increment")?;
    let _time_increment = c.f32("time_increment")?;
    let _scan_time = c.f32("scan_time")?;
    let range_min = c.f32("range_min")?;
    let range_max = c.f32("range_max")?;
    let ranges = c.f32_seq("ranges")?;
    let intensities = c.f32_seq("intensities")?;
    Ok(ForeignScan {
        stamp_s: f64::from(sec) + f64::from(nanosec) * 1e-9,
        first_rad: angle_min,
        increment_rad: angle_increment,
        limits_m: Some((range_min, range_max)),
        ranges,
        intensities,
    })
}

/// Reads protobuf wire format with bounds checks.
struct Proto<'a> {
    buf: &'a [u8],
    pos: usize,
}

impl<'a> Proto<'a> {
    fn varint(&mut self) -> Result<u64, String> {
        let mut v = 0u64;
        for shift in (0..64).step_by(7) {
            let Some(&b) = self.buf.get(self.pos) else {
                return Err(format!("varint cut at byte {}", self.pos));
            };
            self.pos += 1;
            v |= u64::from(b & 0x7f) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(format!("varint longer than 10 bytes at byte {}", self.pos))
    }

    fn take(&mut self, n: u64) -> Result<&'a [u8], String> {
        let left = self.buf.len() - self.pos;
        if n > left as u64 {
            return Err(format!(
                "field of {n} bytes at byte {}, {left} left",
                self.pos
            ));
        }
        let s = &self.buf[self.pos..self.pos + n as usize];
        self.pos += n as usize;
        Ok(s)
    }

    fn f64(&mut self) -> Result<f64, String> {
        let b = self.take(8)?;
        Ok(f64::from_le_bytes(b.try_into().expect("8 bytes")))
    }

    fn done(&self) -> bool {
        self.pos >= self.buf.len()
    }

    /// Skips a field of wire type `wire`.
    fn skip(&mut self, wire: u64, field: u64) -> Result<(), String> {
        match wire {
            0 => self.varint().map(|_| ()),
            1 => self.take(8).map(|_| ()),
            2 => {
                let n = self.varint()?;
                self.take(n).map(|_| ())
            }
            5 => self.take(4).map(|_| ()),
            w => Err(format!("field {field} has wire type {w}, not supported")),
        }
    }

    /// A `repeated double`: packed (wire type 2) or one value (wire type 1) added to `out`.
    fn doubles(&mut self, wire: u64, field: u64, out: &mut Vec<f64>) -> Result<(), String> {
        match wire {
            1 => out.push(self.f64()?),
            2 => {
                let n = self.varint()?;
                let b = self.take(n)?;
                if b.len() % 8 != 0 {
                    return Err(format!(
                        "field {field}: packed doubles of {} bytes",
                        b.len()
                    ));
                }
                out.extend(
                    b.chunks_exact(8)
                        .map(|c| f64::from_le_bytes(c.try_into().expect("8 bytes"))),
                );
            }
            w => return Err(format!("field {field} (doubles) has wire type {w}")),
        }
        Ok(())
    }
}

/// Decodes a protobuf `foxglove.LaserScan`.
///
/// Fields (Foxglove's `LaserScan.proto`): 1 timestamp (`google.protobuf.Timestamp`: 1 seconds,
/// 2 nanos), 2 frame_id, 3 pose, 4 start_angle, 5 end_angle, 6 ranges, 7 intensities.
pub(crate) fn decode_foxglove_protobuf(bytes: &[u8]) -> Result<ForeignScan, String> {
    let mut p = Proto { buf: bytes, pos: 0 };
    let (mut sec, mut nsec) = (0i64, 0i64);
    let (mut start, mut end) = (None, None);
    let mut ranges = Vec::new();
    let mut intensities = Vec::new();
    while !p.done() {
        let key = p.varint()?;
        let (field, wire) = (key >> 3, key & 7);
        match (field, wire) {
            (1, 2) => {
                let n = p.varint()?;
                let mut t = Proto {
                    buf: p.take(n)?,
                    pos: 0,
                };
                while !t.done() {
                    let key = t.varint()?;
                    match (key >> 3, key & 7) {
                        (1, 0) => sec = t.varint()? as i64,
                        (2, 0) => nsec = i64::from(t.varint()? as i32),
                        (f, w) => t.skip(w, f)?,
                    }
                }
            }
            (4, 1) => start = Some(p.f64()?),
            (5, 1) => end = Some(p.f64()?),
            (6, _) => p.doubles(wire, field, &mut ranges)?,
            (7, _) => p.doubles(wire, field, &mut intensities)?,
            _ => p.skip(wire, field)?,
        }
    }
    foxglove_scan(
        sec as f64 + nsec as f64 * 1e-9,
        start.unwrap_or(0.0),
        end.unwrap_or(0.0),
        ranges,
        intensities,
    )
}

/// The time stamp of a Foxglove JSON message.
#[derive(Deserialize)]
struct JsonTime {
    sec: i64,
    #[serde(default)]
    nsec: i64,
}

/// A `foxglove.LaserScan` in JSON, fields as Foxglove names them.
#[derive(Deserialize)]
struct JsonLaserScan {
    timestamp: Option<JsonTime>,
    #[serde(default)]
    start_angle: f64,
    #[serde(default)]
    end_angle: f64,
    ranges: Vec<f64>,
    #[serde(default)]
    intensities: Vec<f64>,
}

/// Decodes a plain JSON `foxglove.LaserScan` (no goalseek extension fields).
pub(crate) fn decode_foxglove_json(bytes: &[u8]) -> Result<ForeignScan, String> {
    let m: JsonLaserScan = serde_json::from_slice(bytes)
        .map_err(|e| format!("not a foxglove.LaserScan in JSON: {e}"))?;
    let stamp = m
        .timestamp
        .map_or(0.0, |t| t.sec as f64 + t.nsec as f64 * 1e-9);
    foxglove_scan(stamp, m.start_angle, m.end_angle, m.ranges, m.intensities)
}

fn foxglove_scan(
    stamp_s: f64,
    start: f64,
    end: f64,
    ranges: Vec<f64>,
    intensities: Vec<f64>,
) -> Result<ForeignScan, String> {
    let n = ranges.len();
    // One ray has no spacing; any non-zero increment draws it at `start_angle`.
    let increment_rad = if n > 1 {
        (end - start) / (n - 1) as f64
    } else {
        1.0
    };
    Ok(ForeignScan {
        stamp_s,
        first_rad: start,
        increment_rad,
        limits_m: None,
        ranges,
        intensities,
    })
}

impl ForeignScan {
    /// The largest finite positive reading (for Foxglove scans, which state no range limit).
    pub(crate) fn largest_reading(&self) -> Option<f64> {
        self.ranges
            .iter()
            .copied()
            .filter(|r| r.is_finite() && *r > 0.0)
            .reduce(f64::max)
    }

    /// The goalseek record of scan number `index`.
    ///
    /// ROS: a finite reading within `[range_min, range_max]` is a hit; +inf is "no return"
    /// (REP 117: `MaxRange`); NaN, -inf and readings outside the limits are invalid
    /// (`RayStatus::Error` with [`INVALID_NAN`], [`INVALID_BELOW_MIN`], [`INVALID_ABOVE_MAX`]).
    /// Foxglove states no limits: the range limits are 0 and `max_range_m` (the largest
    /// reading of the topic), positive finite readings are hits, 0 and less are invalid.
    pub(crate) fn into_record(self, index: usize, max_range_m: f64) -> Result<LogRecord, String> {
        let n = self.ranges.len();
        if n == 0 {
            return Err("a scan without ranges".into());
        }
        let (min, max) = self.limits_m.unwrap_or((0.0, max_range_m));
        let geometry = ScanGeometry::new(self.first_rad, self.increment_rad, n, min, max)
            .map_err(|e| e.to_string())?;
        let intensities = match self.intensities.len() {
            0 => None,
            k if k == n => Some(self.intensities.iter().map(|&v| v as f32).collect()),
            k => return Err(format!("{k} intensities for {n} ranges")),
        };
        let foxglove = self.limits_m.is_none();
        let mut ranges_m = Vec::with_capacity(n);
        let mut status = Vec::with_capacity(n);
        for &r in &self.ranges {
            let s = if r.is_nan() {
                RayStatus::Error(INVALID_NAN)
            } else if r == f64::INFINITY {
                RayStatus::MaxRange
            } else if r < min || (foxglove && r <= 0.0) {
                RayStatus::Error(INVALID_BELOW_MIN)
            } else if r > max {
                RayStatus::Error(INVALID_ABOVE_MAX)
            } else {
                RayStatus::Hit
            };
            ranges_m.push(match s {
                RayStatus::Hit => r,
                RayStatus::MaxRange => max,
                RayStatus::Error(_) => f64::NAN,
            });
            status.push(s);
        }
        let scan = Scan {
            ranges_m,
            status,
            intensities,
            sensor_time_ms: None,
            host_time_s: self.stamp_s,
        };
        Ok(LogRecord::new(index, geometry, scan))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// A little-endian CDR LaserScan built field by field (the layout of the IDL).
    fn cdr(ranges: &[f32], intensities: &[f32]) -> Vec<u8> {
        let mut b = vec![0, 1, 0, 0];
        b.extend(7i32.to_le_bytes());
        b.extend(500u32.to_le_bytes());
        b.extend(3u32.to_le_bytes());
        b.extend(b"ab\0\0"); // "ab" + NUL, padded to 4
        for v in [-1.0f32, 1.0, 0.5, 0.0, 0.1, 0.1, 3.0] {
            b.extend(v.to_le_bytes());
        }
        for seq in [ranges, intensities] {
            b.extend((seq.len() as u32).to_le_bytes());
            for v in seq {
                b.extend(v.to_le_bytes());
            }
        }
        b
    }

    #[test]
    fn cdr_readings_keep_their_ros_meaning() {
        let raw = [
            1.0,
            f32::INFINITY,
            f32::NAN,
            0.05,
            4.0,
            f32::NEG_INFINITY,
            3.0,
        ];
        let s = decode_ros2_laser_scan(&cdr(&raw, &[])).unwrap();
        assert_eq!(s.stamp_s, 7.0 + 500e-9);
        assert_eq!((s.first_rad, s.increment_rad), (-1.0, 0.5));
        let r = s.into_record(0, 0.0).unwrap();
        use RayStatus::*;
        assert_eq!(
            r.scan.status,
            [
                Hit,
                MaxRange,
                Error(INVALID_NAN),
                Error(INVALID_BELOW_MIN),
                Error(INVALID_ABOVE_MAX),
                Error(INVALID_BELOW_MIN),
                Hit
            ]
        );
        assert_eq!(r.scan.ranges_m[1], 3.0);
        assert_eq!(r.scan.intensities, None);
    }

    #[test]
    fn a_huge_cdr_count_is_refused() {
        let mut b = cdr(&[1.0], &[]);
        let at = b.len() - 12; // the ranges count: count, one value, intensities count
        b[at..at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
        let e = decode_ros2_laser_scan(&b).unwrap_err();
        assert!(e.contains("4294967295 values announced"), "{e}");
    }

    #[test]
    fn a_huge_protobuf_length_is_refused() {
        // Field 6 (ranges), wire type 2, length 2^40.
        let mut b = vec![(6 << 3) | 2];
        b.extend([0x80, 0x80, 0x80, 0x80, 0x80, 0x20]);
        let e = decode_foxglove_protobuf(&b).unwrap_err();
        assert!(e.contains("1099511627776 bytes"), "{e}");
    }

    proptest! {
        #[test]
        fn cdr_decoding_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            if let Ok(s) = decode_ros2_laser_scan(&bytes) {
                prop_assert!(s.ranges.len() * 4 <= bytes.len());
                let _ = s.into_record(0, 1.0);
            }
        }

        #[test]
        fn cdr_with_a_valid_header_never_panics(tail in proptest::collection::vec(any::<u8>(), 0..256)) {
            let mut bytes = vec![0, 1, 0, 0];
            bytes.extend(tail);
            let _ = decode_ros2_laser_scan(&bytes).map(|s| s.into_record(0, 1.0));
        }

        #[test]
        fn cdr_cut_anywhere_is_an_error(cut in 0usize..60) {
            let b = cdr(&[1.0, 2.0], &[5.0, 6.0]);
            prop_assume!(cut < b.len());
            prop_assert!(decode_ros2_laser_scan(&b[..cut]).is_err());
        }

        #[test]
        fn protobuf_decoding_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            if let Ok(s) = decode_foxglove_protobuf(&bytes) {
                prop_assert!(s.ranges.len() * 8 <= bytes.len());
                let _ = s.into_record(0, 1.0);
            }
        }

        #[test]
        fn json_decoding_never_panics(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
            let _ = decode_foxglove_json(&bytes).map(|s| s.into_record(0, 1.0));
        }
    }
}
