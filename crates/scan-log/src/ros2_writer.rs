//! Recordings that ROS 2 tools open: an MCAP file with the `ros2` profile, standard messages in
//! CDR and their `ros2msg` definitions, as rosbag2 writes them (see `docs/logs.md`).

use std::collections::BTreeMap;
use std::path::Path;

use scan_types::{Pose2, RayStatus, Scan, ScanGeometry};

use crate::LogError;
use crate::foreign::ROS2_LASER_SCAN;
use crate::mcap_io::{
    EST_POSE_TOPIC, LASER_FRAME, MAP_FRAME, PartialMcap, SCAN_TOPIC, TRUE_POSE_TOPIC, time_of,
};

/// Topic of the estimated poses in a ROS 2 recording (the same as goalseek's recording).
pub const ROS2_POSE_ESTIMATE_TOPIC: &str = EST_POSE_TOPIC;
/// Topic of the simulator's true poses in a ROS 2 recording (the same as goalseek's recording).
pub const ROS2_POSE_TRUTH_TOPIC: &str = TRUE_POSE_TOPIC;
/// Topic of the map at the end of a run in a ROS 2 recording.
pub const ROS2_MAP_TOPIC: &str = "/map";
/// Topic of the `map` to `base_link` transforms in a ROS 2 recording.
pub const ROS2_TF_TOPIC: &str = "/tf";
/// Topic of the fixed `base_link` to `laser` transform in a ROS 2 recording.
pub const ROS2_TF_STATIC_TOPIC: &str = "/tf_static";
/// Frame of the map, the poses and the grid.
pub const ROS2_MAP_FRAME: &str = MAP_FRAME;
/// Frame of the robot: goalseek tracks the laser's pose, so `base_link` is the laser's.
pub const ROS2_BASE_FRAME: &str = "base_link";
/// Frame of the scans, at `base_link` (an identity transform on `/tf_static`).
pub const ROS2_LASER_FRAME: &str = LASER_FRAME;

/// The QoS rosbag2 records for a latched topic (`/tf_static`, `/map`): reliable,
/// transient local, keep last 1, so a player hands it to late subscribers.
const LATCHED_QOS: &str = "- history: 1\n  depth: 1\n  reliability: 1\n  durability: 1\n  deadline:\n    sec: 2147483647\n    nsec: 4294967295\n  lifespan:\n    sec: 2147483647\n    nsec: 4294967295\n  liveliness: 1\n  liveliness_lease_duration:\n    sec: 2147483647\n    nsec: 4294967295\n  avoid_ros_namespace_conventions: false\n";

/// ROS 2 type name of a stamped pose.
pub const ROS2_POSE_STAMPED: &str = "geometry_msgs/msg/PoseStamped";
/// ROS 2 type name of an occupancy grid.
pub const ROS2_OCCUPANCY_GRID: &str = "nav_msgs/msg/OccupancyGrid";
/// ROS 2 type name of a list of transforms.
pub const ROS2_TF_MESSAGE: &str = "tf2_msgs/msg/TFMessage";

// Message definitions, one (name, fields) pair per type.
const TIME: (&str, &str) = ("builtin_interfaces/Time", "int32 sec\nuint32 nanosec\n");
const HEADER: (&str, &str) = (
    "std_msgs/Header",
    "builtin_interfaces/Time stamp\nstring frame_id\n",
);
const POINT: (&str, &str) = ("geometry_msgs/Point", "float64 x\nfloat64 y\nfloat64 z\n");
const VECTOR3: (&str, &str) = ("geometry_msgs/Vector3", "float64 x\nfloat64 y\nfloat64 z\n");
const QUATERNION: (&str, &str) = (
    "geometry_msgs/Quaternion",
    "float64 x\nfloat64 y\nfloat64 z\nfloat64 w\n",
);
const POSE: (&str, &str) = (
    "geometry_msgs/Pose",
    "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
);
const TRANSFORM: (&str, &str) = (
    "geometry_msgs/Transform",
    "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
);
const TRANSFORM_STAMPED: (&str, &str) = (
    "geometry_msgs/TransformStamped",
    "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
);
const MAP_META: (&str, &str) = (
    "nav_msgs/MapMetaData",
    "builtin_interfaces/Time map_load_time\nfloat32 resolution\nuint32 width\nuint32 height\ngeometry_msgs/Pose origin\n",
);
const LASER_SCAN: &str = "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\nfloat32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\nfloat32[] intensities\n";
const POSE_STAMPED: &str = "std_msgs/Header header\ngeometry_msgs/Pose pose\n";
const OCCUPANCY_GRID: &str = "std_msgs/Header header\nnav_msgs/MapMetaData info\nint8[] data\n";
const TF_MESSAGE: &str = "geometry_msgs/TransformStamped[] transforms\n";

/// A message definition in `ros2msg` encoding: the type's fields, then one section per type it
/// uses.
fn definition(fields: &str, uses: &[(&str, &str)]) -> String {
    let mut text = fields.to_string();
    for (name, body) in uses {
        text.push_str(&"=".repeat(80));
        text.push_str("\nMSG: ");
        text.push_str(name);
        text.push('\n');
        text.push_str(body);
    }
    text
}

/// The ROS 2 type and `ros2msg` definition of each topic a recording may hold.
pub fn ros2_schema(topic: &str) -> Option<(&'static str, String)> {
    Some(match topic {
        SCAN_TOPIC => (ROS2_LASER_SCAN, definition(LASER_SCAN, &[HEADER, TIME])),
        ROS2_POSE_ESTIMATE_TOPIC | ROS2_POSE_TRUTH_TOPIC => (
            ROS2_POSE_STAMPED,
            definition(POSE_STAMPED, &[HEADER, TIME, POSE, POINT, QUATERNION]),
        ),
        ROS2_MAP_TOPIC => (
            ROS2_OCCUPANCY_GRID,
            definition(
                OCCUPANCY_GRID,
                &[HEADER, TIME, MAP_META, POSE, POINT, QUATERNION],
            ),
        ),
        ROS2_TF_TOPIC | ROS2_TF_STATIC_TOPIC => (
            ROS2_TF_MESSAGE,
            definition(
                TF_MESSAGE,
                &[
                    TRANSFORM_STAMPED,
                    HEADER,
                    TIME,
                    TRANSFORM,
                    VECTOR3,
                    QUATERNION,
                ],
            ),
        ),
        _ => return None,
    })
}

/// Little-endian plain CDR: the encapsulation header, then fields aligned to their size
/// counted from the header's end.
struct CdrOut(Vec<u8>);

impl CdrOut {
    fn new() -> Self {
        CdrOut(vec![0, 1, 0, 0])
    }

    fn align(&mut self, n: usize) {
        while !(self.0.len() - 4).is_multiple_of(n) {
            self.0.push(0);
        }
    }

    fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }

    fn i32(&mut self, v: i32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }

    fn f32(&mut self, v: f32) {
        self.align(4);
        self.0.extend(v.to_le_bytes());
    }

    fn f64(&mut self, v: f64) {
        self.align(8);
        self.0.extend(v.to_le_bytes());
    }

    /// Length with the terminating NUL, bytes, NUL.
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend(s.as_bytes());
        self.0.push(0);
    }

    fn f32_seq(&mut self, v: &[f32]) {
        self.u32(v.len() as u32);
        for &x in v {
            self.f32(x);
        }
    }

    fn i8_seq(&mut self, v: &[i8]) {
        self.u32(v.len() as u32);
        self.0.extend(v.iter().map(|&x| x as u8));
    }

    fn header(&mut self, stamp: Stamp, frame_id: &str) {
        self.i32(stamp.sec);
        self.u32(stamp.nanosec);
        self.string(frame_id);
    }

    /// A `Point` or `Vector3` at (x, y, 0), then the `Quaternion` of a turn by theta about z.
    fn planar_pose(&mut self, p: Pose2) {
        let half = p.theta_rad / 2.0;
        for v in [p.x_m, p.y_m, 0.0, 0.0, 0.0, half.sin(), half.cos()] {
            self.f64(v);
        }
    }
}

/// A ROS time stamp.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
struct Stamp {
    sec: i32,
    nanosec: u32,
}

/// The stamp of a host time in seconds, and the same in nanoseconds for the MCAP log time.
fn stamp_of(host_time_s: f64) -> (Stamp, u64) {
    let (t, ns) = time_of(host_time_s);
    let stamp = Stamp {
        sec: i32::try_from(t.sec).unwrap_or(i32::MAX),
        nanosec: t.nsec,
    };
    (stamp, ns)
}

/// `time_increment` and `scan_time` of a LaserScan, seconds, for a sensor turning once per
/// `scan_period_s` (0 and 0 when unknown, as ROS asks): the mirror turns `increment_rad` of
/// a full turn between two rays.
fn scan_times(geometry: &ScanGeometry, scan_period_s: Option<f64>) -> (f64, f64) {
    match scan_period_s {
        Some(t) if t.is_finite() && t > 0.0 => {
            (t * geometry.increment_rad / std::f64::consts::TAU, t)
        }
        _ => (0.0, 0.0),
    }
}

/// A CDR `sensor_msgs/msg/LaserScan` in frame `laser`: hits as read, +inf for no return
/// (REP 117), NaN for an invalid reading; times from `scan_period_s` ([`scan_times`]).
fn laser_scan_cdr(
    geometry: &ScanGeometry,
    scan: &Scan,
    stamp: Stamp,
    scan_period_s: Option<f64>,
) -> Vec<u8> {
    let mut c = CdrOut::new();
    c.header(stamp, ROS2_LASER_FRAME);
    let (time_increment_s, scan_time_s) = scan_times(geometry, scan_period_s);
    for v in [
        geometry.first_bearing_rad,
        geometry.last_bearing_rad(),
        geometry.increment_rad,
        time_increment_s,
        scan_time_s,
        geometry.min_range_m,
        geometry.max_range_m,
    ] {
        c.f32(v as f32);
    }
    let ranges: Vec<f32> = scan
        .ranges_m
        .iter()
        .zip(&scan.status)
        .map(|(&r, s)| match s {
            RayStatus::Hit => r as f32,
            RayStatus::MaxRange => f32::INFINITY,
            RayStatus::Error(_) => f32::NAN,
        })
        .collect();
    c.f32_seq(&ranges);
    c.f32_seq(scan.intensities.as_deref().unwrap_or_default());
    c.0
}

/// A CDR `geometry_msgs/msg/PoseStamped` of `p` in frame `map`.
fn pose_stamped_cdr(p: Pose2, stamp: Stamp) -> Vec<u8> {
    let mut c = CdrOut::new();
    c.header(stamp, ROS2_MAP_FRAME);
    c.planar_pose(p);
    c.0
}

/// A CDR `tf2_msgs/msg/TFMessage` with the one transform `parent` to `child` at `p`.
fn tf_cdr(parent: &str, child: &str, p: Pose2, stamp: Stamp) -> Vec<u8> {
    let mut c = CdrOut::new();
    c.u32(1);
    c.header(stamp, parent);
    c.string(child);
    c.planar_pose(p);
    c.0
}

/// An occupancy grid as ROS publishes it: cells row by row from the origin (the lower-left
/// corner of the first cell), x along a row, each 0 (free) to 100 (occupied) or -1 (unknown).
#[derive(Debug, Clone, PartialEq)]
pub struct Ros2Map {
    /// Cell side, metres.
    pub resolution_m: f64,
    /// Cells per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Position of the lower-left corner of the first cell in frame `map`, metres.
    pub origin_m: (f64, f64),
    /// `width * height` cells.
    pub cells: Vec<i8>,
}

/// A CDR `nav_msgs/msg/OccupancyGrid` of `map` in frame `map`.
fn occupancy_grid_cdr(map: &Ros2Map, stamp: Stamp) -> Vec<u8> {
    let mut c = CdrOut::new();
    c.header(stamp, ROS2_MAP_FRAME);
    c.i32(stamp.sec);
    c.u32(stamp.nanosec);
    c.f32(map.resolution_m as f32);
    c.u32(map.width);
    c.u32(map.height);
    c.planar_pose(Pose2::new(map.origin_m.0, map.origin_m.1, 0.0));
    c.i8_seq(&map.cells);
    c.0
}

/// Writes a recording ROS 2 tools open (MCAP, profile `ros2`), atomically as
/// [`crate::McapRecorder`] does: `/scan`, the estimated and true poses, `/tf`, `/tf_static`
/// and `/map`.
///
/// Every scan ends an MCAP chunk, so a cut `<path>.partial` keeps the scans before the cut;
/// dropping the recorder without `finish` finishes it.
pub struct Ros2Recorder {
    file: PartialMcap,
    channels: BTreeMap<&'static str, u16>,
    seq: u64,
    last: (Stamp, u64),
    geometry: Option<ScanGeometry>,
    scan_period_s: Option<f64>,
}

impl Ros2Recorder {
    /// Starts a recording that will be at `path` once finished.
    pub fn create(path: &Path) -> Result<Self, LogError> {
        Ok(Self {
            file: PartialMcap::create(path, "ros2")?,
            channels: BTreeMap::new(),
            seq: 0,
            last: (Stamp::default(), 0),
            geometry: None,
            scan_period_s: None,
        })
    }

    /// Sets the sensor's scan period, seconds, from which the scans' `scan_time` and
    /// `time_increment` are filled (without it both are 0, "unknown").
    pub fn with_scan_period(mut self, scan_period_s: f64) -> Self {
        self.scan_period_s = Some(scan_period_s);
        self
    }

    /// Sets the geometry of the scans [`Ros2Recorder::write`] records.
    pub fn with_geometry(mut self, geometry: &ScanGeometry) -> Self {
        self.geometry = Some(*geometry);
        self
    }

    /// The final path of the recording.
    pub fn path(&self) -> &Path {
        self.file.path()
    }

    /// The geometry given to [`Ros2Recorder::with_geometry`].
    pub fn geometry(&self) -> Option<ScanGeometry> {
        self.geometry
    }

    /// Scans recorded so far.
    pub fn scans(&self) -> u64 {
        self.seq
    }

    /// The channel of `topic`, its schema and channel written on first use.
    fn channel(&mut self, topic: &'static str) -> Result<u16, LogError> {
        if let Some(&id) = self.channels.get(topic) {
            return Ok(id);
        }
        let (name, text) = ros2_schema(topic).expect("a topic of the recording");
        let mut meta = BTreeMap::new();
        if topic == ROS2_TF_STATIC_TOPIC || topic == ROS2_MAP_TOPIC {
            meta.insert("offered_qos_profiles".to_string(), LATCHED_QOS.to_string());
        }
        let id = self.file.with(|w| {
            let schema = w.add_schema(name, "ros2msg", text.as_bytes())?;
            w.add_channel(schema, topic, "cdr", &meta)
        })?;
        self.channels.insert(topic, id);
        Ok(id)
    }

    /// Writes one message on `topic` at log time `ns`.
    fn message(&mut self, topic: &'static str, ns: u64, data: &[u8]) -> Result<(), LogError> {
        let channel_id = self.channel(topic)?;
        let header = mcap::records::MessageHeader {
            channel_id,
            sequence: self.seq as u32,
            log_time: ns,
            publish_time: ns,
        };
        self.file.with(|w| w.write_to_known_channel(&header, data))
    }

    /// Records a scan without poses, of the geometry given to [`Ros2Recorder::with_geometry`].
    pub fn write(&mut self, scan: &Scan) -> Result<(), LogError> {
        let geometry = self.geometry.ok_or_else(|| LogError::NoGeometry {
            path: self.path().to_path_buf(),
        })?;
        self.record_scan(&geometry, scan, None, None)
    }

    /// Records one scan stamped with its host time and, where known, the true pose and the
    /// estimated pose (with its `map` to `base_link` transform); the first scan also gets the
    /// `base_link` to `laser` identity on `/tf_static`.
    pub fn record_scan(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        true_pose: Option<Pose2>,
        est_pose: Option<Pose2>,
    ) -> Result<(), LogError> {
        let (stamp, ns) = stamp_of(scan.host_time_s);
        if self.seq == 0 {
            let fixed = tf_cdr(ROS2_BASE_FRAME, ROS2_LASER_FRAME, Pose2::default(), stamp);
            self.message(ROS2_TF_STATIC_TOPIC, ns, &fixed)?;
        }
        let msg = laser_scan_cdr(geometry, scan, stamp, self.scan_period_s);
        self.message(SCAN_TOPIC, ns, &msg)?;
        if let Some(p) = est_pose {
            self.message(ROS2_POSE_ESTIMATE_TOPIC, ns, &pose_stamped_cdr(p, stamp))?;
            let tf = tf_cdr(ROS2_MAP_FRAME, ROS2_BASE_FRAME, p, stamp);
            self.message(ROS2_TF_TOPIC, ns, &tf)?;
        }
        if let Some(p) = true_pose {
            self.message(ROS2_POSE_TRUTH_TOPIC, ns, &pose_stamped_cdr(p, stamp))?;
        }
        // End the chunk so a crash keeps every scan recorded so far.
        self.file.with(|w| w.flush())?;
        self.seq += 1;
        self.last = (stamp, ns);
        Ok(())
    }

    /// Records the map on `/map`, stamped with the last scan's time.
    pub fn write_map(&mut self, map: &Ros2Map) -> Result<(), LogError> {
        let cells = u64::from(map.width) * u64::from(map.height);
        if map.cells.len() as u64 != cells {
            return Err(LogError::MapSize {
                path: self.path().to_path_buf(),
                width: map.width,
                height: map.height,
                cells: map.cells.len(),
            });
        }
        let (stamp, ns) = self.last;
        self.message(ROS2_MAP_TOPIC, ns, &occupancy_grid_cdr(map, stamp))?;
        self.file.with(|w| w.flush())
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

impl Drop for Ros2Recorder {
    fn drop(&mut self) {
        self.file.close_dropped(self.seq);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::foreign::{INVALID_NAN, decode_ros2_laser_scan};

    fn geometry() -> ScanGeometry {
        ScanGeometry::new(-1.0, 0.25, 5, 0.1, 4.0).unwrap()
    }

    fn scan() -> Scan {
        Scan {
            ranges_m: vec![1.1, 4.0, f64::NAN, 0.3, 2.5],
            status: vec![
                RayStatus::Hit,
                RayStatus::MaxRange,
                RayStatus::Error(7),
                RayStatus::Hit,
                RayStatus::Hit,
            ],
            intensities: None,
            sensor_time_ms: None,
            host_time_s: 12.25,
        }
    }

    #[test]
    fn a_laser_scan_reads_back_through_the_cdr_reader() {
        let (stamp, _) = stamp_of(12.25);
        let bytes = laser_scan_cdr(&geometry(), &scan(), stamp, None);
        let s = decode_ros2_laser_scan(&bytes).unwrap();
        assert_eq!(s.stamp_s, 12.25);
        assert_eq!(s.first_rad, f64::from(-1.0f32));
        assert_eq!(s.increment_rad, 0.25);
        assert_eq!(s.limits_m, Some((f64::from(0.1f32), 4.0)));
        let r = s.into_record(0, 0.0).unwrap();
        use RayStatus::*;
        assert_eq!(r.scan.status, [Hit, MaxRange, Error(INVALID_NAN), Hit, Hit]);
        assert_eq!(r.scan.ranges_m[0], f64::from(1.1f32));
        assert_eq!(r.scan.ranges_m[3], f64::from(0.3f32));
        assert_eq!(r.scan.ranges_m[4], 2.5);
    }

    #[test]
    fn doubles_are_aligned_to_eight_bytes_after_the_encapsulation_header() {
        let stamp = Stamp { sec: 3, nanosec: 4 };
        let p = Pose2::new(1.5, -2.0, std::f64::consts::PI);
        // "map": stamp 8 bytes, length 4, "map\0" 4: the pose starts at 16, no padding.
        let b = pose_stamped_cdr(p, stamp);
        assert_eq!(b.len(), 4 + 16 + 7 * 8);
        assert_eq!(&b[4 + 16..4 + 24], &1.5f64.to_le_bytes());
        // TFMessage: count 4, header 16, child frame length 4 and "base_link\0" 10: 34 bytes,
        // padded to 40 for the first double.
        let b = tf_cdr(ROS2_MAP_FRAME, ROS2_BASE_FRAME, p, stamp);
        assert_eq!(b.len(), 4 + 40 + 7 * 8);
        assert_eq!(&b[4 + 34..4 + 40], &[0; 6]);
        assert_eq!(&b[4 + 40..4 + 48], &1.5f64.to_le_bytes());
        // A half turn: the quaternion's z is sin(pi/2) = 1.
        assert_eq!(&b[b.len() - 16..b.len() - 8], &1.0f64.to_le_bytes());
    }

    #[test]
    fn scan_times_follow_the_mirror() {
        // URG-04LX: 100 ms a turn, 1024 steps a turn: 100 ms / 1024 = 97.65625 us a ray.
        let g = ScanGeometry::new(-2.0, std::f64::consts::TAU / 1024.0, 682, 0.02, 5.6).unwrap();
        let (dt, t) = scan_times(&g, Some(0.1));
        assert!((dt - 97.65625e-6).abs() < 1e-15, "{dt}");
        assert_eq!(t, 0.1);
        // Unknown period: both 0.
        assert_eq!(scan_times(&g, None), (0.0, 0.0));
        assert_eq!(scan_times(&g, Some(f64::NAN)), (0.0, 0.0));
        // In the message: after the header (stamp 8, "laser\0" with its length 10, padded to
        // 20) come the three angles, then time_increment and scan_time as float32.
        let (stamp, _) = stamp_of(1.0);
        let b = laser_scan_cdr(&g, &scan(), stamp, Some(0.1));
        assert_eq!(
            &b[4 + 20 + 12..4 + 20 + 16],
            &(97.65625e-6f32).to_le_bytes()
        );
        assert_eq!(&b[4 + 20 + 16..4 + 20 + 20], &0.1f32.to_le_bytes());
    }

    #[test]
    fn definitions_name_every_type_they_use() {
        let (name, text) = ros2_schema(ROS2_TF_TOPIC).unwrap();
        assert_eq!(name, "tf2_msgs/msg/TFMessage");
        assert!(text.starts_with("geometry_msgs/TransformStamped[] transforms\n"));
        for used in [
            "\nMSG: geometry_msgs/TransformStamped\n",
            "\nMSG: std_msgs/Header\n",
            "\nMSG: builtin_interfaces/Time\n",
            "\nMSG: geometry_msgs/Vector3\n",
        ] {
            assert!(text.contains(used), "{used} missing in\n{text}");
        }
    }

    #[test]
    fn a_recording_reads_back_as_scans_and_is_renamed_when_finished() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("r.mcap");
        let mut r = Ros2Recorder::create(&path)
            .unwrap()
            .with_geometry(&geometry());
        r.write(&scan()).unwrap();
        r.record_scan(&geometry(), &scan(), None, Some(Pose2::new(1.0, 2.0, 0.5)))
            .unwrap();
        let bad = Ros2Map {
            resolution_m: 0.5,
            width: 2,
            height: 2,
            origin_m: (0.0, 0.0),
            cells: vec![0; 3],
        };
        assert!(matches!(r.write_map(&bad), Err(LogError::MapSize { .. })));
        assert!(crate::partial_path(&path).exists());
        assert_eq!(r.finish().unwrap(), 2);
        assert!(!crate::partial_path(&path).exists());
        let records = crate::read_mcap_topic(&path, Some(SCAN_TOPIC)).unwrap();
        assert_eq!(records.len(), 2);
        let first = records[0].as_ref().unwrap();
        assert_eq!(first.scan.host_time_s, 12.25);
        assert_eq!(first.scan.status[1], RayStatus::MaxRange);
    }
}
