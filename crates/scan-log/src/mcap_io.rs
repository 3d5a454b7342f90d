//! goalseek's MCAP recordings: Foxglove `foxglove.LaserScan` and `foxglove.PoseInFrame`
//! messages in JSON encoding, plus the exact values goalseek needs to replay them bit for bit.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path, PathBuf};

use mcap::read::Options;
use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};
use serde::{Deserialize, Serialize};

use crate::foreign::{self, FOXGLOVE_LASER_SCAN, ROS2_LASER_SCAN};
use crate::topics::{Decoded, Found};
use crate::{LogError, LogRecord};

/// Topic of the scans.
pub const SCAN_TOPIC: &str = "/scan";
/// Topic of the simulator's true poses (the same in both recording profiles).
pub const TRUE_POSE_TOPIC: &str = "/pose_truth";
/// Topic of the estimated poses (the same in both recording profiles).
pub const EST_POSE_TOPIC: &str = "/pose_estimate";
/// The true poses' topic in recordings before the profiles shared their names.
const OLD_TRUE_POSE_TOPIC: &str = "/pose/true";
/// The estimated poses' topic in recordings before the profiles shared their names.
const OLD_EST_POSE_TOPIC: &str = "/pose/estimated";
/// The fixed frame of poses, and of scans drawn at a pose.
pub const MAP_FRAME: &str = "map";
/// The frame of a scan recorded without a pose.
pub const LASER_FRAME: &str = "laser";

/// Status code of a hit ray in the `goalseek.status` array.
pub const STATUS_HIT: i32 = -1;
/// Status code of a max-range ray in the `goalseek.status` array (error codes are >= 0).
pub const STATUS_MAX_RANGE: i32 = -2;

// Foxglove's JSON-schema reader (studio `parseJsonSchema`) needs every object to list its
// `properties` and accepts only boolean, string, number, integer, object and array types, so
// the `goalseek` extension is declared field by field.
const TIME_SCHEMA: &str = r#"{"type": "object", "title": "time", "properties": {"sec": {"type": "integer", "minimum": 0}, "nsec": {"type": "integer", "minimum": 0, "maximum": 999999999}}}"#;

const POSE_PART: &str = r#"{"title": "foxglove.Pose", "type": "object", "properties": {
      "position": {"title": "foxglove.Vector3", "type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}}},
      "orientation": {"title": "foxglove.Quaternion", "type": "object", "properties": {"x": {"type": "number"}, "y": {"type": "number"}, "z": {"type": "number"}, "w": {"type": "number"}}}}}"#;

fn laser_scan_schema() -> String {
    format!(
        r#"{{
  "title": "foxglove.LaserScan",
  "description": "A single scan from a planar laser range-finder (goalseek adds the exact values in 'goalseek')",
  "type": "object",
  "properties": {{
    "timestamp": {TIME_SCHEMA},
    "frame_id": {{"type": "string"}},
    "pose": {POSE_PART},
    "start_angle": {{"type": "number"}},
    "end_angle": {{"type": "number"}},
    "ranges": {{"type": "array", "items": {{"type": "number"}}}},
    "intensities": {{"type": "array", "items": {{"type": "number"}}}},
    "goalseek": {{"type": "object", "properties": {{
      "seq": {{"type": "integer"}},
      "host_time_s": {{"type": "number"}},
      "sensor_time_ms": {{"type": "integer", "description": "absent when the sensor gives no time stamp"}},
      "first_bearing_rad": {{"type": "number"}},
      "increment_rad": {{"type": "number"}},
      "ray_count": {{"type": "integer"}},
      "min_range_m": {{"type": "number"}},
      "max_range_m": {{"type": "number"}},
      "status": {{"type": "array", "items": {{"type": "integer"}}, "description": "-1 hit, -2 max range, >= 0 error code"}}}}}}
  }}
}}"#
    )
}

fn pose_schema() -> String {
    format!(
        r#"{{
  "title": "foxglove.PoseInFrame",
  "description": "A timestamped pose in a named coordinate frame (goalseek adds the exact pose in 'goalseek')",
  "type": "object",
  "properties": {{
    "timestamp": {TIME_SCHEMA},
    "frame_id": {{"type": "string"}},
    "pose": {POSE_PART},
    "goalseek": {{"type": "object", "properties": {{
      "seq": {{"type": "integer"}},
      "x_m": {{"type": "number"}},
      "y_m": {{"type": "number"}},
      "heading_rad": {{"type": "number"}}}}}}
  }}
}}"#
    )
}

/// The JSON schemas of the recording's channels: (schema name, schema text), as written.
pub fn recording_schemas() -> [(&'static str, String); 2] {
    [
        ("foxglove.LaserScan", laser_scan_schema()),
        ("foxglove.PoseInFrame", pose_schema()),
    ]
}

/// A time stamp: whole seconds and nanoseconds.
#[derive(Serialize, Deserialize)]
pub(crate) struct Time {
    pub(crate) sec: u64,
    pub(crate) nsec: u32,
}

#[derive(Serialize, Deserialize)]
struct Vec3 {
    x: f64,
    y: f64,
    z: f64,
}

#[derive(Serialize, Deserialize)]
struct Quat {
    x: f64,
    y: f64,
    z: f64,
    w: f64,
}

#[derive(Serialize, Deserialize)]
struct FoxPose {
    position: Vec3,
    orientation: Quat,
}

impl FoxPose {
    fn of(p: Option<Pose2>) -> Self {
        let p = p.unwrap_or_default();
        let h = p.theta_rad / 2.0;
        FoxPose {
            position: Vec3 {
                x: p.x_m,
                y: p.y_m,
                z: 0.0,
            },
            orientation: Quat {
                x: 0.0,
                y: 0.0,
                z: h.sin(),
                w: h.cos(),
            },
        }
    }
}

/// The exact scan as goalseek wrote it.
#[derive(Serialize, Deserialize)]
struct ScanExtra {
    seq: u64,
    host_time_s: f64,
    /// Left out (not `null`, which its schema's `integer` does not allow) when absent.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    sensor_time_ms: Option<u64>,
    first_bearing_rad: f64,
    increment_rad: f64,
    ray_count: usize,
    min_range_m: f64,
    max_range_m: f64,
    status: Vec<i32>,
}

#[derive(Serialize, Deserialize)]
struct LaserScanMsg {
    timestamp: Time,
    frame_id: String,
    pose: FoxPose,
    start_angle: f64,
    end_angle: f64,
    ranges: Vec<f64>,
    intensities: Vec<f64>,
    goalseek: ScanExtra,
}

#[derive(Serialize, Deserialize)]
struct PoseExtra {
    seq: u64,
    x_m: f64,
    y_m: f64,
    /// `theta_rad` in recordings before the unit names were unified.
    #[serde(alias = "theta_rad")]
    heading_rad: f64,
}

#[derive(Serialize, Deserialize)]
struct PoseMsg {
    timestamp: Time,
    frame_id: String,
    pose: FoxPose,
    goalseek: PoseExtra,
}

/// The stamp of a host time in seconds (0 for a negative or non-finite time), and in
/// nanoseconds.
pub(crate) fn time_of(host_time_s: f64) -> (Time, u64) {
    let t = if host_time_s.is_finite() && host_time_s > 0.0 {
        host_time_s
    } else {
        0.0
    };
    let ns = (t * 1e9).round();
    let ns = if ns >= u64::MAX as f64 {
        u64::MAX
    } else {
        ns as u64
    };
    (
        Time {
            sec: ns / 1_000_000_000,
            nsec: (ns % 1_000_000_000) as u32,
        },
        ns,
    )
}

/// An MCAP file written as `<path>.partial` and renamed to its final name when finished.
pub(crate) struct PartialMcap {
    writer: Option<mcap::Writer<BufWriter<File>>>,
    tmp_path: PathBuf,
    path: PathBuf,
}

impl PartialMcap {
    /// Starts `<path>.partial` with the MCAP `profile` (uncompressed chunks).
    pub(crate) fn create(path: &Path, profile: &str) -> Result<Self, LogError> {
        let tmp_path = partial_path(path);
        let file = File::create(&tmp_path).map_err(|source| LogError::Io {
            path: tmp_path.clone(),
            source,
        })?;
        let writer = mcap::WriteOptions::new()
            .compression(None)
            .profile(profile)
            .create(BufWriter::new(file))
            .map_err(|source| LogError::Mcap {
                path: tmp_path.clone(),
                source,
            })?;
        tracing::info!("recording to {}", path.display());
        Ok(Self {
            writer: Some(writer),
            tmp_path,
            path: path.to_path_buf(),
        })
    }

    /// The final path.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// True until the file is finished.
    pub(crate) fn is_open(&self) -> bool {
        self.writer.is_some()
    }

    /// Runs `f` on the open writer, its MCAP errors naming the temporary file.
    pub(crate) fn with<T>(
        &mut self,
        f: impl FnOnce(&mut mcap::Writer<BufWriter<File>>) -> Result<T, mcap::McapError>,
    ) -> Result<T, LogError> {
        let writer = self.writer.as_mut().ok_or_else(|| LogError::Finished {
            path: self.path.clone(),
        })?;
        f(writer).map_err(|source| LogError::Mcap {
            path: self.tmp_path.clone(),
            source,
        })
    }

    /// Writes an MCAP metadata record.
    pub(crate) fn write_metadata(
        &mut self,
        name: &str,
        values: &BTreeMap<String, String>,
    ) -> Result<(), LogError> {
        let record = mcap::records::Metadata {
            name: name.to_string(),
            metadata: values.clone(),
        };
        self.with(|w| w.write_metadata(&record))
    }

    /// What a recorder dropped unfinished (an error or a panic unwinding) does with its file
    /// of `scans` scans: finishes it, or, before the first scan (a run that failed to start),
    /// removes it, so that an earlier file at the final path stays as it was.
    pub(crate) fn close_dropped(&mut self, scans: u64) {
        if !self.is_open() {
            return;
        }
        if scans == 0 {
            tracing::info!(
                "recording {} dropped before its first scan: not written",
                self.path.display()
            );
            self.writer = None;
            if let Err(e) = std::fs::remove_file(&self.tmp_path) {
                tracing::warn!("cannot remove {}: {e}", self.tmp_path.display());
            }
            return;
        }
        match self.finish() {
            Ok(()) => tracing::warn!(
                "recording {} dropped without finish: closed it with {scans} scans",
                self.path.display()
            ),
            Err(e) => {
                tracing::error!("recording dropped without finish and could not be closed: {e}")
            }
        }
    }

    /// Writes the summary, syncs and renames the file; nothing when already finished.
    pub(crate) fn finish(&mut self) -> Result<(), LogError> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(());
        };
        let tmp = self.tmp_path.clone();
        writer.finish().map_err(|source| LogError::Mcap {
            path: tmp.clone(),
            source,
        })?;
        let mut inner = writer.into_inner();
        let io = |source| LogError::Io {
            path: tmp.clone(),
            source,
        };
        std::io::Write::flush(&mut inner).map_err(io)?;
        let file = inner.into_inner().map_err(|e| io(e.into_error()))?;
        file.sync_all().map_err(io)?;
        drop(file);
        std::fs::rename(&tmp, &self.path).map_err(|source| LogError::Io {
            path: self.path.clone(),
            source,
        })
    }
}

/// Writes a goalseek MCAP recording, atomically.
///
/// The file is written as `<path>.partial` in the same directory and renamed to `path` by
/// [`McapRecorder::finish`]. Every scan ends an MCAP chunk and is flushed, so if the process
/// dies, `<path>.partial` holds every scan recorded so far and [`read_mcap`] reads them (it
/// reports the cut as an error after the last whole scan). Dropping the recorder without
/// `finish` (an error or panic unwinding) finishes and renames the file as `finish` would.
pub struct McapRecorder {
    file: PartialMcap,
    scan_ch: u16,
    true_ch: u16,
    est_ch: u16,
    seq: u64,
    geometry: Option<ScanGeometry>,
}

/// The temporary name a recording has until it is finished.
pub fn partial_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".partial");
    path.with_file_name(name)
}

impl McapRecorder {
    /// Starts a recording that will be at `path` once finished.
    pub fn create(path: &Path) -> Result<Self, LogError> {
        let mut file = PartialMcap::create(path, "")?;
        let (scan_ch, true_ch, est_ch) = file.with(|writer| {
            let scan_schema = writer.add_schema(
                "foxglove.LaserScan",
                "jsonschema",
                laser_scan_schema().as_bytes(),
            )?;
            let pose_schema = writer.add_schema(
                "foxglove.PoseInFrame",
                "jsonschema",
                pose_schema().as_bytes(),
            )?;
            let meta = BTreeMap::new();
            Ok((
                writer.add_channel(scan_schema, SCAN_TOPIC, "json", &meta)?,
                writer.add_channel(pose_schema, TRUE_POSE_TOPIC, "json", &meta)?,
                writer.add_channel(pose_schema, EST_POSE_TOPIC, "json", &meta)?,
            ))
        })?;
        Ok(Self {
            file,
            scan_ch,
            true_ch,
            est_ch,
            seq: 0,
            geometry: None,
        })
    }

    /// Sets the geometry of the scans [`McapRecorder::write`] records.
    pub fn with_geometry(mut self, geometry: &ScanGeometry) -> Self {
        self.geometry = Some(*geometry);
        self
    }

    /// Records a scan without poses, of the geometry given to [`McapRecorder::with_geometry`].
    pub fn write(&mut self, scan: &Scan) -> Result<(), LogError> {
        let geometry = self.geometry.ok_or_else(|| LogError::NoGeometry {
            path: self.file.path().to_path_buf(),
        })?;
        self.record_scan(&geometry, scan, None, None)
    }

    /// The final path of the recording.
    pub fn path(&self) -> &Path {
        self.file.path()
    }

    /// Scans recorded so far.
    pub fn scans(&self) -> u64 {
        self.seq
    }

    /// Records one scan with its geometry and, where known, the true and estimated poses.
    ///
    /// In Foxglove the scan is drawn in frame `map` at the estimated pose (else the true
    /// pose) when one is given, and in frame `laser` otherwise.
    pub fn record_scan(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        true_pose: Option<Pose2>,
        est_pose: Option<Pose2>,
    ) -> Result<(), LogError> {
        let seq = self.seq;
        let (stamp, ns) = time_of(scan.host_time_s);
        let msg = laser_scan_msg(geometry, scan, seq, &stamp, est_pose.or(true_pose));
        let data = serde_json::to_vec(&msg).expect("plain data serialises");
        let header = |channel_id| mcap::records::MessageHeader {
            channel_id,
            sequence: seq as u32,
            log_time: ns,
            publish_time: ns,
        };
        let mut messages = vec![(self.scan_ch, data)];
        for (ch, pose) in [(self.true_ch, true_pose), (self.est_ch, est_pose)] {
            let Some(p) = pose else { continue };
            let msg = pose_msg(p, seq, &stamp);
            messages.push((ch, serde_json::to_vec(&msg).expect("plain data serialises")));
        }
        self.file.with(|writer| {
            for (ch, data) in &messages {
                writer.write_to_known_channel(&header(*ch), data)?;
            }
            // End the chunk so a crash keeps every scan recorded so far.
            writer.flush()
        })?;
        self.seq += 1;
        Ok(())
    }

    /// Writes an MCAP metadata record: a name and string pairs (e.g. the settings of a run).
    pub fn write_metadata(
        &mut self,
        name: &str,
        values: &BTreeMap<String, String>,
    ) -> Result<(), LogError> {
        self.file.write_metadata(name, values)
    }

    /// Writes the MCAP summary and moves the file to its final name; returns the scan count.
    pub fn finish(mut self) -> Result<u64, LogError> {
        self.finish_inner()
    }

    fn finish_inner(&mut self) -> Result<u64, LogError> {
        if self.file.is_open() {
            self.file.finish()?;
            tracing::info!("recorded {} scans to {}", self.seq, self.path().display());
        }
        Ok(self.seq)
    }
}

/// The Foxglove `LaserScan` message of scan number `seq`, drawn at `shown` (in frame `map`)
/// or in frame `laser` without a pose.
fn laser_scan_msg(
    geometry: &ScanGeometry,
    scan: &Scan,
    seq: u64,
    stamp: &Time,
    shown: Option<Pose2>,
) -> LaserScanMsg {
    LaserScanMsg {
        timestamp: Time {
            sec: stamp.sec,
            nsec: stamp.nsec,
        },
        frame_id: if shown.is_some() {
            MAP_FRAME
        } else {
            LASER_FRAME
        }
        .into(),
        pose: FoxPose::of(shown),
        start_angle: geometry.first_bearing_rad,
        end_angle: geometry.last_bearing_rad(),
        ranges: scan
            .ranges_m
            .iter()
            .map(|&r| if r.is_finite() { r } else { 0.0 })
            .collect(),
        intensities: scan
            .intensities
            .as_ref()
            .map(|v| v.iter().map(|&x| f64::from(x)).collect())
            .unwrap_or_default(),
        goalseek: ScanExtra {
            seq,
            host_time_s: scan.host_time_s,
            sensor_time_ms: scan.sensor_time_ms,
            first_bearing_rad: geometry.first_bearing_rad,
            increment_rad: geometry.increment_rad,
            ray_count: geometry.ray_count,
            min_range_m: geometry.min_range_m,
            max_range_m: geometry.max_range_m,
            status: scan
                .status
                .iter()
                .map(|s| match s {
                    RayStatus::Hit => STATUS_HIT,
                    RayStatus::MaxRange => STATUS_MAX_RANGE,
                    RayStatus::Error(c) => i32::from(*c),
                })
                .collect(),
        },
    }
}

/// The Foxglove `PoseInFrame` message of pose `p` of scan number `seq`.
fn pose_msg(p: Pose2, seq: u64, stamp: &Time) -> PoseMsg {
    PoseMsg {
        timestamp: Time {
            sec: stamp.sec,
            nsec: stamp.nsec,
        },
        frame_id: MAP_FRAME.into(),
        pose: FoxPose::of(Some(p)),
        goalseek: PoseExtra {
            seq,
            x_m: p.x_m,
            y_m: p.y_m,
            heading_rad: p.theta_rad,
        },
    }
}

impl Drop for McapRecorder {
    fn drop(&mut self) {
        self.file.close_dropped(self.seq);
    }
}

/// Reads every scan of an MCAP file's laser topic (there must be one), in order.
///
/// A damaged or cut file yields the scans before the damage, then one error.
pub fn read_mcap(path: &Path) -> Result<Vec<Result<LogRecord, LogError>>, LogError> {
    read_mcap_topic(path, None)
}

/// Reads every scan of the laser topic `topic` of an MCAP file (`None`: its only one), in
/// order: a goalseek recording (each scan with its poses), ROS 2 `sensor_msgs/msg/LaserScan`
/// in CDR, `foxglove.LaserScan` in protobuf or JSON; chunks plain, zstd or lz4.
pub fn read_mcap_topic(
    path: &Path,
    topic: Option<&str>,
) -> Result<Vec<Result<LogRecord, LogError>>, LogError> {
    let bytes = std::fs::read(path).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    scan_mcap(&bytes, path).select(path, topic)
}

/// An MCAP metadata record: its name and string pairs.
pub type MetadataRecord = (String, BTreeMap<String, String>);

/// The metadata records of a recording, in file order.
///
/// A cut file gives the records before the cut (and a warning).
pub fn read_mcap_metadata(path: &Path) -> Result<Vec<MetadataRecord>, LogError> {
    let bytes = std::fs::read(path).map_err(|source| LogError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    let reader = mcap::read::LinearReader::new_with_options(&bytes, Options::IgnoreEndMagic.into())
        .map_err(|source| LogError::Mcap {
            path: path.to_path_buf(),
            source,
        })?;
    let mut out = Vec::new();
    for record in reader {
        match record {
            Ok(mcap::records::Record::Metadata(m)) => out.push((m.name, m.metadata)),
            Ok(_) => {}
            Err(e) => {
                tracing::warn!(
                    "{}: metadata after a damaged record not read: {e}",
                    path.display()
                );
                break;
            }
        }
    }
    Ok(out)
}

/// Parses MCAP bytes (see [`read_mcap`]); `path` names the source in errors.
///
/// A file with several laser topics, or none, gives one error.
pub fn parse_mcap(bytes: &[u8], path: &Path) -> Vec<Result<LogRecord, LogError>> {
    scan_mcap(bytes, path)
        .select(path, None)
        .unwrap_or_else(|e| vec![Err(e)])
}

/// How the messages of a channel are laser scans.
#[derive(Clone, Copy, PartialEq)]
enum Kind {
    /// `foxglove.LaserScan` in JSON: goalseek's recording (exact) or plain.
    Json,
    /// `sensor_msgs/msg/LaserScan` in CDR.
    Cdr,
    /// `foxglove.LaserScan` in protobuf.
    Protobuf,
}

/// How a channel's messages are laser scans, or `None` for another type.
fn channel_kind(channel: &mcap::Channel<'_>) -> Option<Kind> {
    let name = channel.schema.as_ref().map_or("", |s| s.name.as_str());
    match (channel.message_encoding.as_str(), name) {
        ("json", FOXGLOVE_LASER_SCAN) => Some(Kind::Json),
        ("cdr", ROS2_LASER_SCAN) => Some(Kind::Cdr),
        ("protobuf", FOXGLOVE_LASER_SCAN) => Some(Kind::Protobuf),
        _ => None,
    }
}

/// Whether `topic` holds goalseek's true poses (`Some(true)`), its estimates (`Some(false)`),
/// or neither; the names of older recordings included.
fn pose_topic(topic: &str) -> Option<bool> {
    match topic {
        TRUE_POSE_TOPIC | OLD_TRUE_POSE_TOPIC => Some(true),
        EST_POSE_TOPIC | OLD_EST_POSE_TOPIC => Some(false),
        _ => None,
    }
}

/// Every laser topic of MCAP bytes, decoded; goalseek's poses joined to their scans.
pub(crate) fn scan_mcap(bytes: &[u8], path: &Path) -> Found {
    let mut found = Found::default();
    // Index into the entries of goalseek's scan topic of each scan sequence number.
    let mut by_seq: BTreeMap<u64, usize> = BTreeMap::new();
    let mut kinds: BTreeMap<u16, Option<Kind>> = BTreeMap::new();
    let stream = Messages::new(bytes);
    let mut messages = 0usize;
    for (index, msg) in stream.enumerate() {
        let msg = match msg {
            Ok(m) => m,
            Err(source) => {
                found.tail.push(LogError::Mcap {
                    path: path.to_path_buf(),
                    source,
                });
                break;
            }
        };
        messages += 1;
        let topic = msg.channel.topic.as_str();
        let bad = |message: String| LogError::Message {
            path: path.to_path_buf(),
            index,
            topic: topic.to_string(),
            message,
        };
        let kind = *kinds
            .entry(msg.channel.id)
            .or_insert_with(|| channel_kind(&msg.channel));
        let decoded = match kind {
            Some(Kind::Json) => match decode_json_scan(&msg.data) {
                Ok(JsonScan::Exact((seq, rec))) if topic == SCAN_TOPIC => {
                    by_seq.insert(seq, found.laser_topic(topic).entries.len());
                    Ok(Decoded::Exact(rec))
                }
                Ok(JsonScan::Exact((_, rec))) => Ok(Decoded::Exact(rec)),
                Ok(JsonScan::Foreign(s)) => Ok(Decoded::Foreign(s)),
                Err(m) => Err(bad(m)),
            },
            Some(Kind::Cdr) => foreign::decode_ros2_laser_scan(&msg.data)
                .map(Decoded::Foreign)
                .map_err(|m| bad(format!("not a CDR {ROS2_LASER_SCAN}: {m}"))),
            Some(Kind::Protobuf) => foreign::decode_foxglove_protobuf(&msg.data)
                .map(Decoded::Foreign)
                .map_err(|m| bad(format!("not a protobuf {FOXGLOVE_LASER_SCAN}: {m}"))),
            // goalseek's JSON poses; a ROS 2 recording's CDR poses on the same topics are not.
            None if msg.channel.message_encoding == "json" && pose_topic(topic).is_some() => {
                // Named among the other topics (for a --topic that is not a laser topic).
                if !found
                    .other
                    .iter()
                    .any(|o| o.split(' ').next() == Some(topic))
                {
                    found.other_topic(format!("{topic} (goalseek poses of {SCAN_TOPIC})"));
                }
                let pose: PoseMsg = match serde_json::from_slice(&msg.data) {
                    Ok(p) => p,
                    Err(e) => {
                        let e = bad(format!("not a goalseek pose: {e}"));
                        found.laser_topic(SCAN_TOPIC).entries.push(Err(e));
                        continue;
                    }
                };
                let g = pose.goalseek;
                let p = Pose2 {
                    x_m: g.x_m,
                    y_m: g.y_m,
                    theta_rad: g.heading_rad,
                };
                let scans = &mut found.laser_topic(SCAN_TOPIC).entries;
                let rec = by_seq.get(&g.seq).and_then(|&i| match scans.get_mut(i) {
                    Some(Ok(Decoded::Exact(r))) => Some(r),
                    _ => None,
                });
                match rec {
                    Some(rec) if pose_topic(topic) == Some(true) => rec.true_pose = Some(p),
                    Some(rec) => rec.pose = Some(p),
                    None => scans.push(Err(bad(format!("pose for unknown scan {}", g.seq)))),
                }
                continue;
            }
            None => {
                let schema = msg.channel.schema.as_ref();
                found.other_topic(format!(
                    "{topic} ({} in {}, schema encoding {})",
                    schema.map_or("no schema", |s| s.name.as_str()),
                    msg.channel.message_encoding,
                    schema.map_or("none", |s| s.encoding.as_str()),
                ));
                continue;
            }
        };
        found.laser_topic(topic).entries.push(decoded);
    }
    // The file starts and ends with the magic: a file of the opening magic alone is cut too.
    let complete = bytes.len() >= 2 * mcap::MAGIC.len() && bytes.ends_with(mcap::MAGIC);
    if found.tail.is_empty() && !complete {
        let scans: usize = found
            .laser
            .iter()
            .map(|t| t.entries.iter().filter(|e| e.is_ok()).count())
            .sum();
        found.tail.push(LogError::Message {
            path: path.to_path_buf(),
            index: messages,
            topic: found
                .laser
                .first()
                .map_or(SCAN_TOPIC.to_string(), |t| t.topic.clone()),
            message: format!(
                "the file ends without its MCAP footer (a recording cut short): {scans} whole scans read, {} bytes",
                bytes.len()
            ),
        });
    }
    found
}

/// The largest MCAP record (or decompressed chunk) read: a damaged length field beyond it is
/// refused instead of allocated.
pub const MAX_MCAP_RECORD_BYTES: usize = 64 << 20;

/// The messages of MCAP bytes in file order, each record and chunk at most
/// [`MAX_MCAP_RECORD_BYTES`] (`mcap::MessageStream` sets no limit inside chunks).
struct Messages<'a> {
    reader: mcap::sans_io::MessageReader,
    rest: &'a [u8],
}

impl<'a> Messages<'a> {
    fn new(bytes: &'a [u8]) -> Self {
        let options = mcap::sans_io::LinearReaderOptions::default()
            .with_skip_end_magic(true)
            .with_record_length_limit(MAX_MCAP_RECORD_BYTES);
        Messages {
            reader: mcap::sans_io::MessageReader::new_with_options(options),
            rest: bytes,
        }
    }
}

impl Iterator for Messages<'_> {
    type Item = Result<mcap::Message<'static>, mcap::McapError>;

    fn next(&mut self) -> Option<Self::Item> {
        loop {
            match self.reader.next_event()? {
                Ok(mcap::sans_io::MessageReadEvent::ReadRequest(need)) => {
                    let n = need.min(self.rest.len());
                    self.reader.insert(n).copy_from_slice(&self.rest[..n]);
                    self.reader.notify_read(n);
                    self.rest = &self.rest[n..];
                }
                Ok(mcap::sans_io::MessageReadEvent::Message(m)) => return Some(Ok(m)),
                Err(e) => return Some(Err(e)),
            }
        }
    }
}

/// A JSON `foxglove.LaserScan`: goalseek's exact scan (with its sequence number) or plain.
enum JsonScan {
    Exact((u64, LogRecord)),
    Foreign(foreign::ForeignScan),
}

/// The fields of a JSON laser scan goalseek's exact reading needs.
#[derive(Deserialize)]
struct ScanJson {
    ranges: Vec<f64>,
    #[serde(default)]
    intensities: Vec<f64>,
    goalseek: Option<ScanExtra>,
}

fn decode_json_scan(data: &[u8]) -> Result<JsonScan, String> {
    let m: ScanJson = serde_json::from_slice(data)
        .map_err(|e| format!("not a {FOXGLOVE_LASER_SCAN} in JSON: {e}"))?;
    match m.goalseek {
        Some(x) => decode_scan(m.ranges, m.intensities, x).map(JsonScan::Exact),
        None => foreign::decode_foxglove_json(data).map(JsonScan::Foreign),
    }
}

fn decode_scan(
    ranges: Vec<f64>,
    intensities: Vec<f64>,
    x: ScanExtra,
) -> Result<(u64, LogRecord), String> {
    let geometry = ScanGeometry::new(
        x.first_bearing_rad,
        x.increment_rad,
        x.ray_count,
        x.min_range_m,
        x.max_range_m,
    )
    .map_err(|e| e.to_string())?;
    if ranges.len() != x.ray_count || x.status.len() != x.ray_count {
        return Err(format!(
            "{} ranges and {} statuses for {} rays",
            ranges.len(),
            x.status.len(),
            x.ray_count
        ));
    }
    let mut status = Vec::with_capacity(x.ray_count);
    let mut ranges_m = ranges;
    for (i, &s) in x.status.iter().enumerate() {
        status.push(match s {
            STATUS_HIT => RayStatus::Hit,
            STATUS_MAX_RANGE => RayStatus::MaxRange,
            c if (0..=i32::from(u16::MAX)).contains(&c) => {
                ranges_m[i] = f64::NAN;
                RayStatus::Error(c as u16)
            }
            c => return Err(format!("ray {i} has unknown status {c}")),
        });
    }
    let intensities = if intensities.is_empty() {
        None
    } else if intensities.len() == x.ray_count {
        Some(intensities.iter().map(|&v| v as f32).collect())
    } else {
        return Err(format!(
            "{} intensities for {} rays",
            intensities.len(),
            x.ray_count
        ));
    };
    let scan = Scan {
        ranges_m,
        status,
        intensities,
        sensor_time_ms: x.sensor_time_ms,
        host_time_s: x.host_time_s,
    };
    Ok((x.seq, LogRecord::new(x.seq as usize, geometry, scan)))
}
