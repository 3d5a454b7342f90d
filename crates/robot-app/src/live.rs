//! `--live [ADDR:PORT]`: a Foxglove WebSocket server (the official `foxglove` crate) that shows
//! a run while it happens to Foxglove, Lichtblick or any client of the `foxglove.sdk.v1`
//! protocol. See `docs/live-view.md`.
//!
//! Topics (protobuf, Foxglove schemas), named as in both recording profiles: `/scan`
//! (`foxglove.LaserScan`, frame `laser`), `/pose_estimate` and, in the simulator,
//! `/pose_truth` (`foxglove.PoseInFrame`, frame `map`), `/tf` (`foxglove.FrameTransforms`,
//! map -> base_link by the estimate), `/tf_static` (base_link -> laser, the identity), `/map`
//! (`foxglove.Grid`, occupancy 100 / 0 / -1 as ROS maps) and `/markers`
//! (`foxglove.SceneUpdate`: the target, landmarks and points B). `/map` and `/tf_static` are
//! latched: a client that subscribes late gets their last message at once.
//!
//! A run never waits for a client unless `--live-wait` asks it to, and never fails because
//! of one: messages for a slow or absent client are dropped by the server.

use std::time::{Duration, Instant};

use anyhow::Context as _;
use clap::Args;
use foxglove::messages::{
    Color, CubePrimitive, CylinderPrimitive, FrameTransform, FrameTransforms, Grid, LaserScan,
    PackedElementField, Pose, PoseInFrame, Quaternion, SceneEntity, SceneUpdate, SpherePrimitive,
    Timestamp, Vector2, Vector3, packed_element_field::NumericType,
};
use foxglove::websocket::{ChannelView, Client, ServerListener};
use foxglove::{Channel, Context, PartialMetadata, WebSocketServerHandle};
use localiser::OccupancyGrid;
use scan_types::{Pose2, RayStatus, Scan, ScanGeometry, WorldPoint};
use std::sync::{Arc, Mutex, OnceLock};

/// The address `--live` serves on when given without one (Foxglove's usual port).
pub const DEFAULT_ADDR: &str = "127.0.0.1:8765";

/// Topic of the laser scans.
pub const SCAN_TOPIC: &str = "/scan";
/// Topic of the estimated pose.
pub const ESTIMATE_TOPIC: &str = "/pose_estimate";
/// Topic of the simulator's true pose.
pub const TRUTH_TOPIC: &str = "/pose_truth";
/// Topic of the transforms (map -> base_link).
pub const TF_TOPIC: &str = "/tf";
/// Topic of the fixed transform base_link -> laser.
pub const TF_STATIC_TOPIC: &str = "/tf_static";
/// Topic of the occupancy grid.
pub const MAP_TOPIC: &str = "/map";
/// Topic of the target, landmarks and points B.
pub const MARKERS_TOPIC: &str = "/markers";

/// The map frame.
const MAP_FRAME: &str = scan_log::MAP_FRAME;
/// The robot's frame (goalseek tracks the laser, so `laser` sits at it).
const BASE_FRAME: &str = scan_log::ROS2_BASE_FRAME;
/// The scans' frame.
const LASER_FRAME: &str = scan_log::LASER_FRAME;
/// The map is sent at most this often between leg ends.
const MAP_PERIOD: Duration = Duration::from_secs(1);

/// How long the server stays up after the run when a client is connected, so that the last
/// messages (the final map) reach it.
const LINGER: Duration = Duration::from_secs(1);

/// `--live` and `--live-wait`, shared by `sim`, `explore`, `run`, `replay` and `slam`.
#[derive(Debug, Clone, Default, Args)]
pub struct LiveOptions {
    /// Serve a live view of the run (Foxglove WebSocket protocol) on ADDR:PORT; without a
    /// value on 127.0.0.1:8765. Open Foxglove or Lichtblick and connect to
    /// ws://ADDR:PORT (see docs/live-view.md).
    #[arg(
        long,
        value_name = "ADDR:PORT",
        num_args = 0..=1,
        default_missing_value = DEFAULT_ADDR
    )]
    pub live: Option<String>,
    /// With --live: before the run starts, wait up to SECONDS for a client to subscribe to a
    /// topic (then start anyway), so that a viewer sees the run from its first scan.
    #[arg(long, value_name = "SECONDS", requires = "live", value_parser = crate::cmd::non_negative)]
    pub live_wait: Option<f64>,
}

impl LiveOptions {
    /// Starts the server when `--live` is given (waiting for a client if `--live-wait` says
    /// so); `map_resolution_m` is the cell size of the map it builds from the scans.
    pub fn start(&self, map_resolution_m: f64) -> anyhow::Result<Option<LiveView>> {
        let Some(addr) = &self.live else {
            return Ok(None);
        };
        let view = LiveView::start(addr, map_resolution_m)?;
        if let Some(s) = self.live_wait {
            view.wait_for_subscriber(Duration::from_secs_f64(s.min(86_400.0)));
        }
        Ok(Some(view))
    }
}

/// `--live`, `--live-wait` and `--live-rate`: the live view of a simulated run, paced by its
/// clock (`sim`, `explore`).
#[derive(Debug, Clone, Default, Args)]
pub struct PacedLiveOptions {
    /// Live view.
    #[command(flatten)]
    pub live: LiveOptions,
    /// With --live: play the run at this many times the simulated clock's speed, so a viewer
    /// can follow it (0: as fast as it computes).
    #[arg(long, value_name = "RATE", default_value_t = 1.0, requires = "live", value_parser = crate::cmd::non_negative)]
    pub live_rate: f64,
}

impl PacedLiveOptions {
    /// Starts the server when `--live` is given ([`LiveOptions::start`]), paced at
    /// `--live-rate`.
    pub fn start(&self, map_resolution_m: f64) -> anyhow::Result<Option<LiveView>> {
        Ok(self
            .live
            .start(map_resolution_m)?
            .map(|v| v.with_rate(self.live_rate)))
    }
}

/// Splits `ADDR:PORT` (`[v6]:PORT` for IPv6) into a host and a port.
pub fn parse_addr(text: &str) -> anyhow::Result<(String, u16)> {
    let bad = || anyhow::anyhow!("--live {text}: expected ADDR:PORT, e.g. {DEFAULT_ADDR}");
    let (host, port) = text.rsplit_once(':').ok_or_else(bad)?;
    let host = host.trim_start_matches('[').trim_end_matches(']');
    if host.is_empty() {
        return Err(bad());
    }
    let port: u16 = port.parse().map_err(|_| bad())?;
    Ok((host.to_string(), port))
}

/// The latched topics: their channels and last messages, handed to each new subscriber.
#[derive(Default)]
struct Latch {
    map: OnceLock<Arc<Channel<Grid>>>,
    tf_static: OnceLock<Arc<Channel<FrameTransforms>>>,
    last_map: Mutex<Option<(Grid, u64)>>,
}

impl Latch {
    /// Publishes `grid` at `ns` and keeps it for later subscribers.
    fn publish_map(&self, grid: Grid, ns: u64) {
        if let Some(ch) = self.map.get() {
            ch.log_with_time(&grid, ns);
        }
        if let Ok(mut last) = self.last_map.lock() {
            *last = Some((grid, ns));
        }
    }
}

impl ServerListener for Latch {
    fn on_subscribe(&self, client: Client, channel: ChannelView) {
        let to = |ns: u64| PartialMetadata { log_time: Some(ns) };
        if channel.topic() == MAP_TOPIC {
            let last = self.last_map.lock().ok().and_then(|m| m.clone());
            if let (Some(ch), Some((grid, ns))) = (self.map.get(), last) {
                ch.log_with_meta_to_sink(&grid, to(ns), client.sink_id());
            }
        } else if channel.topic() == TF_STATIC_TOPIC
            && let Some(ch) = self.tf_static.get()
        {
            ch.log_with_meta_to_sink(&laser_transform(), to(0), client.sink_id());
        }
    }
}

/// The fixed transform base_link -> laser: the identity.
fn laser_transform() -> FrameTransforms {
    FrameTransforms {
        transforms: vec![FrameTransform {
            timestamp: Some(Timestamp::new(0, 0)),
            parent_frame_id: BASE_FRAME.into(),
            child_frame_id: LASER_FRAME.into(),
            translation: Some(vec3(0.0, 0.0, 0.0)),
            rotation: Some(yaw(0.0)),
        }],
    }
}

/// A running live-view server and the channels it publishes on.
pub struct LiveView {
    /// The channels' context, kept for as long as they publish.
    _ctx: std::sync::Arc<Context>,
    addr: String,
    server: Option<WebSocketServerHandle>,
    scan: Channel<LaserScan>,
    estimate: Channel<PoseInFrame>,
    truth: Channel<PoseInFrame>,
    tf: Channel<FrameTransforms>,
    latch: Arc<Latch>,
    markers: Channel<SceneUpdate>,
    grid: OccupancyGrid,
    map_sent: Option<Instant>,
    stamp_s: f64,
    goal: Option<WorldPoint>,
    landmarks: Vec<WorldPoint>,
    points_b: Vec<WorldPoint>,
    pace: Option<Pace>,
    scans: u64,
}

/// Pacing of the scans by their own clock.
struct Pace {
    rate: f64,
    started: Instant,
    first_stamp_s: Option<f64>,
}

impl LiveView {
    /// Starts serving on `addr` (`ADDR:PORT`); `map_resolution_m` is the cell size of the map
    /// built from the scans and their estimates.
    pub fn start(addr: &str, map_resolution_m: f64) -> anyhow::Result<LiveView> {
        let (host, port) = parse_addr(addr)?;
        let ctx = Context::new();
        let latch = Arc::new(Latch::default());
        let server = ctx
            .websocket_server()
            .name(format!("goalseek robot-app {}", env!("CARGO_PKG_VERSION")))
            .listener(latch.clone())
            .bind(host.clone(), port)
            .start_blocking()
            .with_context(|| {
                format!(
                    "--live {addr}: cannot serve the live view there (the port is taken, or the address is not one of this machine's); give another with --live ADDR:PORT"
                )
            })?;
        let bound = if host.contains(':') {
            format!("[{host}]:{}", server.port())
        } else {
            format!("{host}:{}", server.port())
        };
        tracing::info!("live view on ws://{bound}: connect Foxglove or Lichtblick to it");
        let _ = latch
            .map
            .set(Arc::new(ctx.channel_builder(MAP_TOPIC).build()));
        let _ = latch
            .tf_static
            .set(Arc::new(ctx.channel_builder(TF_STATIC_TOPIC).build()));
        Ok(LiveView {
            _ctx: ctx.clone(),
            addr: bound,
            server: Some(server),
            scan: ctx.channel_builder(SCAN_TOPIC).build(),
            estimate: ctx.channel_builder(ESTIMATE_TOPIC).build(),
            truth: ctx.channel_builder(TRUTH_TOPIC).build(),
            tf: ctx.channel_builder(TF_TOPIC).build(),
            latch,
            markers: ctx.channel_builder(MARKERS_TOPIC).build(),
            grid: OccupancyGrid::new(map_resolution_m),
            map_sent: None,
            stamp_s: 0.0,
            goal: None,
            landmarks: Vec::new(),
            points_b: Vec::new(),
            pace: None,
            scans: 0,
        })
    }

    /// Paces the scans by their time stamps at `rate` times real time (0: no waiting).
    pub fn with_rate(mut self, rate: f64) -> Self {
        self.pace = (rate > 0.0).then_some(Pace {
            rate,
            started: Instant::now(),
            first_stamp_s: None,
        });
        self
    }

    /// Shows the target among the markers.
    pub fn with_goal(mut self, goal: WorldPoint) -> Self {
        self.goal = Some(goal);
        self
    }

    /// The port the server listens on.
    pub fn port(&self) -> Option<u16> {
        self.server.as_ref().map(WebSocketServerHandle::port)
    }

    /// True when a client subscribes to any topic.
    fn subscribed(&self) -> bool {
        self.scan.has_sinks()
            || self.estimate.has_sinks()
            || self.truth.has_sinks()
            || self.tf.has_sinks()
            || self.latch.map.get().is_some_and(|c| c.has_sinks())
            || self.latch.tf_static.get().is_some_and(|c| c.has_sinks())
            || self.markers.has_sinks()
    }

    /// Waits up to `timeout` (or a Ctrl-C) for a client to subscribe to a topic.
    pub fn wait_for_subscriber(&self, timeout: Duration) {
        tracing::info!(
            "live view: waiting up to {:.0} s for a client on ws://{}",
            timeout.as_secs_f64(),
            self.addr
        );
        let started = Instant::now();
        while !self.subscribed() {
            if started.elapsed() >= timeout || crate::interrupt::requested() {
                tracing::warn!("live view: no client subscribed; starting without one");
                return;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        // Let the client subscribe to the rest of the topics it asked for.
        std::thread::sleep(Duration::from_millis(200));
        tracing::info!("live view: a client subscribed; starting");
    }

    /// Publishes one scan with the estimate of its pose and, in the simulator, the true pose;
    /// the estimate also enters the view's map.
    pub fn scan(
        &mut self,
        geometry: &ScanGeometry,
        scan: &Scan,
        estimate: Option<Pose2>,
        truth: Option<Pose2>,
    ) {
        self.pace(scan.host_time_s);
        if scan.host_time_s.is_finite() && scan.host_time_s >= 0.0 {
            self.stamp_s = scan.host_time_s;
        }
        let ts = timestamp(self.stamp_s);
        let nanos = ts.total_nanos();
        self.scans += 1;
        self.scan
            .log_with_time(&laser_scan(geometry, scan, ts), nanos);
        if let Some(e) = estimate {
            self.estimate.log_with_time(&pose_in_map(e, ts), nanos);
            let tf = FrameTransforms {
                transforms: vec![FrameTransform {
                    timestamp: Some(ts),
                    parent_frame_id: MAP_FRAME.into(),
                    child_frame_id: BASE_FRAME.into(),
                    translation: Some(vec3(e.x_m, e.y_m, 0.0)),
                    rotation: Some(yaw(e.theta_rad)),
                }],
            };
            self.tf.log_with_time(&tf, nanos);
            self.grid.integrate(&e, geometry, scan);
            if self.map_sent.is_none_or(|t| t.elapsed() >= MAP_PERIOD) {
                self.send_own_map();
            }
        }
        if let Some(t) = truth {
            self.truth.log_with_time(&pose_in_map(t, ts), nanos);
        }
    }

    /// Publishes a leg end: its landmark and point B join the markers, and the map is sent.
    pub fn leg(&mut self, leg: &navigator::Leg) {
        self.landmarks.extend(leg.landmark);
        self.points_b.extend(leg.point_b);
        self.send_markers();
        self.send_own_map();
    }

    /// Publishes the map built from the scans so far.
    fn send_own_map(&mut self) {
        self.map_sent = Some(Instant::now());
        publish_map(&self.latch, &self.grid, self.stamp_s);
    }

    /// Publishes `grid` as the map (the run's own, at its end).
    pub fn send_map(&mut self, grid: &OccupancyGrid) {
        self.map_sent = Some(Instant::now());
        publish_map(&self.latch, grid, self.stamp_s);
    }

    /// Sends the target, landmarks and points B so far.
    fn send_markers(&mut self) {
        let ts = timestamp(self.stamp_s);
        let entity = |id: &str| SceneEntity {
            timestamp: Some(ts),
            frame_id: MAP_FRAME.into(),
            id: id.into(),
            ..SceneEntity::default()
        };
        let mut entities = Vec::new();
        if let Some(g) = self.goal {
            entities.push(SceneEntity {
                cylinders: vec![CylinderPrimitive {
                    pose: Some(pose_at(g, 0.15)),
                    size: Some(vec3(0.3, 0.3, 0.3)),
                    bottom_scale: 1.0,
                    top_scale: 1.0,
                    color: Some(color(0.1, 0.7, 0.2)),
                }],
                ..entity("target")
            });
        }
        entities.push(SceneEntity {
            spheres: self
                .landmarks
                .iter()
                .map(|p| SpherePrimitive {
                    pose: Some(pose_at(*p, 0.1)),
                    size: Some(vec3(0.2, 0.2, 0.2)),
                    color: Some(color(0.9, 0.5, 0.0)),
                })
                .collect(),
            ..entity("landmarks")
        });
        entities.push(SceneEntity {
            cubes: self
                .points_b
                .iter()
                .map(|p| CubePrimitive {
                    pose: Some(pose_at(*p, 0.05)),
                    size: Some(vec3(0.1, 0.1, 0.1)),
                    color: Some(color(0.2, 0.4, 1.0)),
                })
                .collect(),
            ..entity("points_b")
        });
        self.markers.log_with_time(
            &SceneUpdate {
                deletions: Vec::new(),
                entities,
            },
            ts.total_nanos(),
        );
    }

    /// Sleeps until the scan stamped `stamp_s` is due at the pacing rate.
    fn pace(&mut self, stamp_s: f64) {
        let Some(p) = self.pace.as_mut() else {
            return;
        };
        if !stamp_s.is_finite() {
            return;
        }
        let t0 = *p.first_stamp_s.get_or_insert(stamp_s);
        let due = (stamp_s - t0) / p.rate;
        let now = p.started.elapsed().as_secs_f64();
        // In slices, so that Ctrl-C is heard; at most 60 s per scan.
        let end = p.started + Duration::from_secs_f64(now + (due - now).clamp(0.0, 60.0));
        while !crate::interrupt::requested() {
            let left = end.saturating_duration_since(Instant::now());
            if left.is_zero() {
                break;
            }
            std::thread::sleep(left.min(Duration::from_millis(100)));
        }
    }

    /// Sends the final map (`grid`, or without one the map built from the scans) and the
    /// markers, then shuts the server down.
    pub fn finish(mut self, grid: Option<&OccupancyGrid>) {
        match grid {
            Some(g) => self.send_map(g),
            None => self.send_own_map(),
        }
        self.send_markers();
        self.shutdown();
    }

    fn shutdown(&mut self) {
        if let Some(server) = self.server.take() {
            let clients = server.client_count();
            if clients > 0 {
                // Stopping drops what the clients' queues still hold: let them drain first.
                std::thread::sleep(LINGER);
            }
            server.stop().wait_blocking();
            tracing::info!(
                scans = self.scans,
                clients,
                "live view on {} closed",
                self.addr
            );
        }
    }
}

impl Drop for LiveView {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Publishes `grid` on the latched `/map` stamped `stamp_s` (nothing for an empty grid).
fn publish_map(latch: &Latch, grid: &OccupancyGrid, stamp_s: f64) {
    let ts = timestamp(stamp_s);
    if let Some(msg) = grid_message(grid, ts) {
        latch.publish_map(msg, ts.total_nanos());
    }
}

/// Seconds as a Foxglove time stamp (0 for a negative or non-finite time).
fn timestamp(s: f64) -> Timestamp {
    Timestamp::try_from_epoch_secs_f64(s).unwrap_or_else(|_| Timestamp::new(0, 0))
}

fn vec3(x: f64, y: f64, z: f64) -> Vector3 {
    Vector3 { x, y, z }
}

/// A turn of `theta_rad` about z.
fn yaw(theta_rad: f64) -> Quaternion {
    let h = theta_rad / 2.0;
    Quaternion {
        x: 0.0,
        y: 0.0,
        z: h.sin(),
        w: h.cos(),
    }
}

fn color(r: f64, g: f64, b: f64) -> Color {
    Color { r, g, b, a: 1.0 }
}

/// A point at height `z_m`, unrotated.
fn pose_at(p: WorldPoint, z_m: f64) -> Pose {
    Pose {
        position: Some(vec3(p.x_m(), p.y_m(), z_m)),
        orientation: Some(yaw(0.0)),
    }
}

fn pose_in_map(p: Pose2, ts: Timestamp) -> PoseInFrame {
    PoseInFrame {
        timestamp: Some(ts),
        frame_id: MAP_FRAME.into(),
        pose: Some(Pose {
            position: Some(vec3(p.x_m, p.y_m, 0.0)),
            orientation: Some(yaw(p.theta_rad)),
        }),
    }
}

/// A scan as `foxglove.LaserScan` in `laser`: a ray with nothing in range reads +inf, a
/// ray the sensor reported an error for reads NaN (as the ROS 2 profile writes them).
fn laser_scan(geometry: &ScanGeometry, scan: &Scan, ts: Timestamp) -> LaserScan {
    let ranges = scan
        .ranges_m
        .iter()
        .zip(&scan.status)
        .map(|(r, s)| match s {
            RayStatus::Hit => *r,
            RayStatus::MaxRange => f64::INFINITY,
            RayStatus::Error(_) => f64::NAN,
        })
        .collect();
    LaserScan {
        timestamp: Some(ts),
        frame_id: LASER_FRAME.into(),
        pose: Some(Pose {
            position: Some(vec3(0.0, 0.0, 0.0)),
            orientation: Some(yaw(0.0)),
        }),
        start_angle: geometry.first_bearing_rad,
        end_angle: geometry.last_bearing_rad(),
        ranges,
        intensities: scan
            .intensities
            .as_ref()
            .map(|v| v.iter().map(|&i| f64::from(i)).collect())
            .unwrap_or_default(),
    }
}

/// The grid as `foxglove.Grid` in `map`: one int8 field `occupancy` (100 occupied, 0 free,
/// -1 unknown), rows from the lowest y; `None` for an empty grid.
fn grid_message(grid: &OccupancyGrid, ts: Timestamp) -> Option<Grid> {
    let map = crate::record::ros2_map(grid)?;
    let data: Vec<u8> = map.cells.iter().map(|&c| c as u8).collect();
    Some(Grid {
        timestamp: Some(ts),
        frame_id: MAP_FRAME.into(),
        pose: Some(Pose {
            position: Some(vec3(map.origin_m.0, map.origin_m.1, 0.0)),
            orientation: Some(yaw(0.0)),
        }),
        column_count: map.width,
        cell_size: Some(Vector2 {
            x: map.resolution_m,
            y: map.resolution_m,
        }),
        row_stride: map.width,
        cell_stride: 1,
        fields: vec![PackedElementField {
            name: "occupancy".into(),
            offset: 0,
            r#type: NumericType::Int8 as i32,
        }],
        data: data.into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn addresses() {
        assert_eq!(
            parse_addr("127.0.0.1:8765").unwrap(),
            ("127.0.0.1".into(), 8765)
        );
        assert_eq!(parse_addr("[::1]:9000").unwrap(), ("::1".into(), 9000));
        assert!(parse_addr("8765").is_err());
        assert!(parse_addr("host:port").is_err());
        assert!(parse_addr(":8765").is_err());
    }
}
