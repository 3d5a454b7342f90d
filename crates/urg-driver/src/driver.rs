//! `Urg`: a connected Hokuyo that produces scans (`LaserSource`), and `ReconnectingUrg`,
//! which reopens the port with backoff when the device disappears.

use std::io::{self, Read, Write};
use std::ops::{Deref, DerefMut};
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use scan_types::{LaserSource, Scan, ScanGeometry};

use crate::UrgError;
use crate::codec::{DataKind, RawScan, ScanRequest, Status, StatusLine, StreamRequest};
use crate::info::SensorParams;
use crate::port::{PortConfig, ScipPort};
use crate::time::{TimeSample, TimestampUnwrapper, median_offset_s};

/// How `next_scan` gets its scans.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AcquisitionMode {
    /// One `GD`/`GS`/`GE` request per scan: every scan is taken on demand.
    #[default]
    Polled,
    /// `MD`/`MS`/`ME` streaming until `QT`: scans arrive at the sensor's period.
    Streaming,
}

/// How a [`Urg`] connects and acquires.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UrgConfig {
    /// Timeouts of the underlying port.
    pub port: PortConfig,
    /// Polled or streaming acquisition.
    pub mode: AcquisitionMode,
    /// Encoding of the scans (`Range3` for GD/MD).
    pub kind: DataKind,
    /// Steps merged into one value (1 = every step).
    pub cluster: u8,
    /// TM1 round trips for the host-time offset (0: stamp scans with the host receive time).
    pub time_sync_rounds: usize,
    /// Quiet time that ends the drain of stale bytes while connecting.
    pub drain_quiet: Duration,
    /// Consecutive bad replies (checksum, garbage) tolerated in one `next_scan`.
    pub max_bad_replies: usize,
}

impl Default for UrgConfig {
    fn default() -> Self {
        UrgConfig {
            port: PortConfig::default(),
            mode: AcquisitionMode::Polled,
            kind: DataKind::Range3,
            cluster: 1,
            time_sync_rounds: 10,
            drain_quiet: Duration::from_millis(50),
            max_bad_replies: 10,
        }
    }
}

/// Host wall-clock time, seconds since the Unix epoch.
pub fn host_now_s() -> f64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64())
}

/// A connected SCIP 2.0 sensor: its parameters, geometry and scan stream.
///
/// Derefs to [`ScipPort`] for every individual command.
#[derive(Debug)]
pub struct Urg<T> {
    port: ScipPort<T>,
    config: UrgConfig,
    params: SensorParams,
    request: ScanRequest,
    geometry: ScanGeometry,
    raw: RawScan,
    unwrapper: TimestampUnwrapper,
    offset_s: Option<f64>,
}

impl<T: Read + Write> Urg<T> {
    /// Connects the way Hokuyo's own library does (`LF`, `QT`, switching a SCIP 1.1 sensor to
    /// SCIP 2.0 and leaving time-adjust mode if needed), then reads `PP`, synchronises clocks
    /// (`TM0`, N x `TM1`, `TM2`) and, for polled mode, switches the laser on (`BM`).
    pub fn connect(io: T, config: UrgConfig) -> Result<Self, UrgError> {
        let mut port = ScipPort::new(io, config.port);
        port.write_raw(b"\n")?;
        port.drain(config.drain_quiet)?;
        let reply = port.transact(&crate::codec::Command::LaserOff, None)?;
        match reply.status() {
            StatusLine::Scip2(s) if s == Status::OK => {}
            StatusLine::Scip1(_) => {
                tracing::info!("sensor answers in SCIP 1.1: switching to SCIP 2.0");
                port.switch_to_scip2()?;
                port.drain(config.drain_quiet)?;
                port.laser_off()?;
            }
            StatusLine::Scip2(s) if s == Status::UNDEFINED => {
                tracing::info!("sensor is in time-adjust mode: leaving it");
                port.time_adjust(false)?;
                port.laser_off()?;
            }
            StatusLine::Scip2(s) => return Err(UrgError::from_status("QT", s)),
        }
        let params = port.parameters()?;
        Self::with_params(port, config, params)
    }

    /// Builds the driver from a port whose sensor parameters are known (no `PP` is sent);
    /// synchronises clocks and switches the laser on as [`Urg::connect`] does.
    pub fn with_params(
        port: ScipPort<T>,
        config: UrgConfig,
        params: SensorParams,
    ) -> Result<Self, UrgError> {
        let request = ScanRequest {
            cluster: config.cluster.max(1),
            ..params.full_request(config.kind)
        };
        let geometry = params.geometry_for(&request)?;
        let mut urg = Urg {
            port,
            config,
            params,
            request,
            geometry,
            raw: RawScan::with_capacity(request.value_count()),
            unwrapper: TimestampUnwrapper::default(),
            offset_s: None,
        };
        if config.time_sync_rounds > 0 {
            urg.sync_time(config.time_sync_rounds)?;
        }
        if config.mode == AcquisitionMode::Polled {
            urg.port.laser_on()?;
        }
        Ok(urg)
    }

    /// Gives the transport back (the sensor may still be streaming: call `stop` first).
    pub fn into_inner(self) -> T {
        self.port.into_inner()
    }

    /// The sensor's parameters (PP).
    pub fn params(&self) -> &SensorParams {
        &self.params
    }

    /// The request each scan is taken with.
    pub fn request(&self) -> &ScanRequest {
        &self.request
    }

    /// The configuration in use.
    pub fn config(&self) -> &UrgConfig {
        &self.config
    }

    /// Host time minus sensor time, seconds, from the last synchronisation.
    pub fn time_offset_s(&self) -> Option<f64> {
        self.offset_s
    }

    /// Estimates the host-time offset from `rounds` TM1 round trips (median), in time-adjust mode.
    pub fn sync_time(&mut self, rounds: usize) -> Result<f64, UrgError> {
        if self.port.is_streaming() {
            self.port.stop_stream()?;
        }
        self.port.time_adjust(true)?;
        let mut samples = Vec::with_capacity(rounds);
        let mut result = Ok(());
        for _ in 0..rounds.max(1) {
            let host_send_s = host_now_s();
            match self.port.read_time() {
                Ok(sensor_ms) => samples.push(TimeSample {
                    host_send_s,
                    host_recv_s: host_now_s(),
                    sensor_ms,
                }),
                Err(e) => {
                    result = Err(e);
                    break;
                }
            }
        }
        let leave = self.port.time_adjust(false);
        result?;
        leave?;
        let offset = median_offset_s(&samples).ok_or_else(|| UrgError::Timeout {
            command: "TM1".into(),
            waited_ms: 0,
        })?;
        // Seed the unwrapper with the timer as it was during synchronisation.
        self.unwrapper.reset();
        if let Some(last) = samples.last() {
            self.unwrapper.unwrap(last.sensor_ms);
        }
        self.offset_s = Some(offset);
        if self.config.mode == AcquisitionMode::Polled {
            self.port.laser_on()?;
        }
        tracing::debug!(offset, samples = samples.len(), "sensor clock synchronised");
        Ok(offset)
    }

    /// `RS`: resets the sensor (laser, motor speed, bit rate and its timer). The time-stamp
    /// history is cleared and the clocks are synchronised again (if configured); in polled
    /// mode the laser is switched back on.
    pub fn reset(&mut self) -> Result<(), UrgError> {
        self.port.reset()?;
        self.unwrapper.reset();
        self.offset_s = None;
        if self.config.time_sync_rounds > 0 {
            self.sync_time(self.config.time_sync_rounds)?;
        } else if self.config.mode == AcquisitionMode::Polled {
            self.port.laser_on()?;
        }
        Ok(())
    }

    /// Stops streaming (`QT`) if a stream is running.
    pub fn stop(&mut self) -> Result<(), UrgError> {
        if self.port.is_streaming() {
            self.port.stop_stream()?;
        }
        Ok(())
    }

    /// The next scan in sensor units, decoded into a buffer the driver reuses.
    ///
    /// Scans with a checksum error or a malformed reply are dropped and counted (see
    /// [`ScipPort::stats`]); after `max_bad_replies` in a row the last error is returned.
    pub fn next_raw(&mut self) -> Result<&RawScan, UrgError> {
        let mut bad = 0usize;
        loop {
            let res = match self.config.mode {
                AcquisitionMode::Polled => self.port.get_scan(&self.request, &mut self.raw),
                AcquisitionMode::Streaming => {
                    if !self.port.is_streaming() {
                        self.port.start_stream(&StreamRequest {
                            scan: self.request,
                            skip: 0,
                            count: 0,
                        })?;
                    }
                    self.port.read_stream_scan(self.request.kind, &mut self.raw)
                }
            };
            match res {
                Ok(()) => break,
                Err(e) if e.is_reply_error() && bad < self.config.max_bad_replies => {
                    tracing::warn!("dropping one scan: {e}");
                    bad += 1;
                }
                Err(e) => return Err(e),
            }
        }
        if self.raw.ranges_mm.len() != self.geometry.ray_count {
            return Err(UrgError::Framing {
                what: format!(
                    "scan has {} values, the request asks for {}",
                    self.raw.ranges_mm.len(),
                    self.geometry.ray_count
                ),
                offset: 0,
            });
        }
        Ok(&self.raw)
    }
}

impl<T> Deref for Urg<T> {
    type Target = ScipPort<T>;
    fn deref(&self) -> &ScipPort<T> {
        &self.port
    }
}

impl<T> DerefMut for Urg<T> {
    fn deref_mut(&mut self) -> &mut ScipPort<T> {
        &mut self.port
    }
}

impl<T: Read + Write> LaserSource for Urg<T> {
    type Error = UrgError;

    fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }

    fn next_scan(&mut self) -> Result<Scan, UrgError> {
        let recv_s = host_now_s();
        self.next_raw()?;
        let sensor_ms = self.unwrapper.unwrap(self.raw.timestamp_ms);
        let host = match self.offset_s {
            Some(off) => off + sensor_ms as f64 / 1000.0,
            None => recv_s,
        };
        Ok(self.params.to_scan(&self.raw, Some(sensor_ms), host))
    }
}

/// Reconnection delays: `initial`, multiplied by `factor` after each failure, capped at `max`.
#[derive(Debug, Clone, Copy)]
pub struct Backoff {
    /// First delay.
    pub initial: Duration,
    /// Longest delay.
    pub max: Duration,
    /// Growth per failed attempt.
    pub factor: f64,
    /// Give up after this many attempts (`None`: never).
    pub max_attempts: Option<u32>,
    /// Give up as soon as this returns true (checked every 50 ms while waiting): Ctrl-C.
    pub cancel: Option<fn() -> bool>,
}

impl Default for Backoff {
    fn default() -> Self {
        Backoff {
            initial: Duration::from_millis(100),
            max: Duration::from_secs(5),
            factor: 2.0,
            max_attempts: None,
            cancel: None,
        }
    }
}

impl Backoff {
    /// Waits `d` in naps of at most 50 ms; false when `cancel` ended the wait.
    fn wait(&self, d: Duration) -> bool {
        match self.cancel {
            Some(cancelled) => scan_types::sleep_unless(d, cancelled),
            None => {
                std::thread::sleep(d);
                true
            }
        }
    }

    /// The delay before attempt `n` (0-based).
    pub fn delay(&self, attempt: u32) -> Duration {
        let f = self.factor.max(1.0).powi(attempt.min(64) as i32);
        self.initial.mul_f64(f.min(1e9)).min(self.max)
    }
}

/// Opens and connects with `open`, retrying with `backoff` while it fails.
pub fn connect_with_backoff<T, F>(
    open: &mut F,
    config: &UrgConfig,
    backoff: &Backoff,
) -> Result<Urg<T>, UrgError>
where
    T: Read + Write,
    F: FnMut() -> io::Result<T>,
{
    let mut attempt = 0u32;
    loop {
        let err = match open() {
            Ok(io) => match Urg::connect(io, *config) {
                Ok(u) => return Ok(u),
                Err(e) => e,
            },
            Err(e) => UrgError::Disconnected(format!("cannot open the port: {e}")),
        };
        if backoff.max_attempts.is_some_and(|m| attempt + 1 >= m) {
            return Err(err);
        }
        let d = backoff.delay(attempt);
        tracing::warn!(
            "connect attempt {} failed ({err}); retrying in {d:?}",
            attempt + 1
        );
        if !backoff.wait(d) {
            tracing::info!("reconnecting given up: a stop was asked for");
            return Err(err);
        }
        attempt += 1;
    }
}

/// A `LaserSource` that survives unplugging: on `Disconnected` it reopens the port with
/// backoff, checks that it is the same sensor (serial number from `VV`) with unchanged
/// parameters, and resumes the stream.
pub struct ReconnectingUrg<T, F> {
    open: F,
    config: UrgConfig,
    backoff: Backoff,
    urg: Option<Urg<T>>,
    params: SensorParams,
    serial: Option<String>,
    geometry: ScanGeometry,
    reconnects: u32,
}

impl<T: Read + Write, F: FnMut() -> io::Result<T>> ReconnectingUrg<T, F> {
    /// Opens and connects (with backoff).
    pub fn new(mut open: F, config: UrgConfig, backoff: Backoff) -> Result<Self, UrgError> {
        let urg = connect_with_backoff(&mut open, &config, &backoff)?;
        Ok(Self::from_connected(urg, open, config, backoff))
    }

    /// Wraps a connected driver; `open` reopens its device after an unplug.
    pub fn from_connected(mut urg: Urg<T>, open: F, config: UrgConfig, backoff: Backoff) -> Self {
        let serial = serial_of(&mut urg);
        ReconnectingUrg {
            serial,
            params: urg.params().clone(),
            geometry: *LaserSource::geometry(&urg),
            urg: Some(urg),
            open,
            config,
            backoff,
            reconnects: 0,
        }
    }

    /// How many times the device was reconnected.
    pub fn reconnects(&self) -> u32 {
        self.reconnects
    }

    /// The connected driver, if any.
    pub fn urg_mut(&mut self) -> Option<&mut Urg<T>> {
        self.urg.as_mut()
    }
}

impl<T: Read + Write, F: FnMut() -> io::Result<T>> LaserSource for ReconnectingUrg<T, F> {
    type Error = UrgError;

    fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }

    fn next_scan(&mut self) -> Result<Scan, UrgError> {
        loop {
            if self.urg.is_none() {
                let started = Instant::now();
                let mut urg = connect_with_backoff(&mut self.open, &self.config, &self.backoff)?;
                let serial = serial_of(&mut urg);
                if serial != self.serial {
                    return Err(UrgError::ParametersChanged(format!(
                        "serial number {} became {}: a different sensor",
                        self.serial.as_deref().unwrap_or("(none)"),
                        serial.as_deref().unwrap_or("(none)")
                    )));
                }
                if urg.params() != &self.params {
                    return Err(UrgError::ParametersChanged(format!(
                        "{:?} became {:?}",
                        self.params,
                        urg.params()
                    )));
                }
                self.reconnects += 1;
                tracing::warn!("sensor reconnected after {:?}", started.elapsed());
                self.urg = Some(urg);
            }
            let urg = self.urg.as_mut().expect("connected above");
            match urg.next_scan() {
                Err(UrgError::Disconnected(why)) => {
                    tracing::warn!("sensor disconnected ({why}); reconnecting");
                    self.urg = None;
                }
                other => return other,
            }
        }
    }
}

/// The sensor's serial number from `VV`, if it answers.
fn serial_of<T: Read + Write>(urg: &mut Urg<T>) -> Option<String> {
    match urg.version() {
        Ok(v) => Some(v.serial),
        Err(e) => {
            tracing::warn!("VV not answered ({e}): the sensor's identity is not checked");
            None
        }
    }
}

/// A serial port opened through the `serialport` crate.
pub type SerialTransport = Box<dyn serialport::SerialPort>;

/// Opens a serial device (USB CDC-ACM or pseudo-terminal) for SCIP: 115200 8N1 (the rate
/// does not matter over USB), with a short read timeout so the driver's own timeouts rule.
pub fn open_serial(path: &str) -> io::Result<SerialTransport> {
    serialport::new(path, 115_200)
        .timeout(Duration::from_millis(20))
        .open()
        .map_err(io::Error::from)
}

/// How a [`SerialUrg`] reopens its device.
pub type SerialOpener = Box<dyn FnMut() -> io::Result<SerialTransport> + Send>;

/// A sensor on a serial device that survives unplugging.
pub type SerialUrg = ReconnectingUrg<SerialTransport, SerialOpener>;

impl SerialUrg {
    /// Opens the serial device at `path` and connects (failing at once if it is not there),
    /// then reconnects to the same path with `backoff` whenever it disappears.
    pub fn open_path(path: &str, config: UrgConfig, backoff: Backoff) -> Result<Self, UrgError> {
        let urg = Urg::open(path, config)?;
        let owned = path.to_string();
        let open: SerialOpener = Box::new(move || open_serial(&owned));
        Ok(Self::from_connected(urg, open, config, backoff))
    }
}

impl Urg<SerialTransport> {
    /// Opens the serial device at `path` and connects.
    pub fn open(path: &str, config: UrgConfig) -> Result<Self, UrgError> {
        let io = open_serial(path).map_err(|e| open_error(path, e))?;
        Urg::connect(io, config)
    }
}

/// The prefix of a port that names a TCP address (`tcp:HOST:PORT`) rather than a serial device.
pub const TCP_PREFIX: &str = "tcp:";

/// The TCP port Ethernet Hokuyos (UST-10LX/20LX, UTM-30LX-EW) serve SCIP 2.0 on.
pub const SCIP_TCP_PORT: u16 = 10940;

/// How long opening a TCP connection may take before it fails.
const TCP_CONNECT_TIMEOUT: Duration = Duration::from_secs(2);

/// Where a sensor is reached: a serial device path, or `tcp:HOST:PORT` for an Ethernet model.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum PortSpec {
    /// A serial device (USB CDC-ACM or pseudo-terminal) at this path.
    Serial(String),
    /// A TCP address, `HOST:PORT`.
    Tcp(String),
}

impl PortSpec {
    /// Reads a `--port` value: `tcp:HOST:PORT` is a TCP address, anything else a device path.
    ///
    /// A TCP address needs a host and a numeric port (`tcp:192.168.0.10:10940`,
    /// `tcp:[::1]:10940`); otherwise the error names the value and what is missing.
    pub fn parse(port: &str) -> Result<Self, UrgError> {
        let Some(addr) = port.strip_prefix(TCP_PREFIX) else {
            return Ok(PortSpec::Serial(port.to_string()));
        };
        let bad = |why: &str| UrgError::BadPort {
            port: port.to_string(),
            why: format!("{why}; expected tcp:HOST:PORT, e.g. tcp:192.168.0.10:{SCIP_TCP_PORT}"),
        };
        let Some((host, number)) = addr.rsplit_once(':') else {
            return Err(bad("no port number"));
        };
        if host.is_empty() || host == "[]" {
            return Err(bad("no host"));
        }
        match number.parse::<u16>() {
            Ok(n) if n > 0 => Ok(PortSpec::Tcp(addr.to_string())),
            _ => Err(bad(&format!("port number {number:?} is not 1..65535"))),
        }
    }
}

impl std::fmt::Display for PortSpec {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PortSpec::Serial(path) => f.write_str(path),
            PortSpec::Tcp(addr) => write!(f, "{TCP_PREFIX}{addr}"),
        }
    }
}

/// Connects to a sensor's TCP address (`HOST:PORT`), trying each address it resolves to,
/// with a short read timeout so that the driver's own timeouts rule.
pub fn open_tcp(addr: &str) -> io::Result<std::net::TcpStream> {
    use std::net::ToSocketAddrs;
    let mut last = None;
    for a in addr.to_socket_addrs()? {
        match std::net::TcpStream::connect_timeout(&a, TCP_CONNECT_TIMEOUT) {
            Ok(stream) => {
                stream.set_read_timeout(Some(Duration::from_millis(20)))?;
                stream.set_write_timeout(Some(Duration::from_secs(2)))?;
                stream.set_nodelay(true)?;
                return Ok(stream);
            }
            Err(e) => last = Some(e),
        }
    }
    Err(last.unwrap_or_else(|| {
        io::Error::new(
            io::ErrorKind::NotFound,
            format!("{addr} resolves to no address"),
        )
    }))
}

/// A connection to a sensor: a serial device or a TCP socket.
pub enum PortTransport {
    /// A serial device.
    Serial(SerialTransport),
    /// A TCP connection to an Ethernet sensor.
    Tcp(std::net::TcpStream),
}

impl std::fmt::Debug for PortTransport {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            PortTransport::Serial(p) => write!(f, "Serial({:?})", p.name()),
            PortTransport::Tcp(s) => write!(f, "Tcp({:?})", s.peer_addr().ok()),
        }
    }
}

impl Read for PortTransport {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        match self {
            PortTransport::Serial(p) => p.read(buf),
            PortTransport::Tcp(s) => s.read(buf),
        }
    }
}

impl Write for PortTransport {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        match self {
            PortTransport::Serial(p) => p.write(buf),
            PortTransport::Tcp(s) => s.write(buf),
        }
    }

    fn flush(&mut self) -> io::Result<()> {
        match self {
            PortTransport::Serial(p) => p.flush(),
            PortTransport::Tcp(s) => s.flush(),
        }
    }
}

/// Opens the transport `spec` names (a serial device or a TCP connection).
pub fn open_port(spec: &PortSpec) -> io::Result<PortTransport> {
    match spec {
        PortSpec::Serial(path) => open_serial(path).map(PortTransport::Serial),
        PortSpec::Tcp(addr) => open_tcp(addr).map(PortTransport::Tcp),
    }
}

/// How a [`PortUrg`] reopens its serial device or TCP connection.
pub type PortOpener = Box<dyn FnMut() -> io::Result<PortTransport> + Send>;

/// A sensor on a serial device or over TCP that survives disconnection: after an unplug or
/// a dropped connection it reconnects to the same path or `HOST:PORT` and checks it is the
/// same sensor.
pub type PortUrg = ReconnectingUrg<PortTransport, PortOpener>;

impl PortUrg {
    /// Opens `port` (a device path or `tcp:HOST:PORT`) and connects, failing at once if
    /// nothing is there, then reconnects to the same place with `backoff` whenever the
    /// sensor goes away.
    pub fn open_port(port: &str, config: UrgConfig, backoff: Backoff) -> Result<Self, UrgError> {
        let spec = PortSpec::parse(port)?;
        let urg = Urg::open_spec(&spec, config)?;
        let open: PortOpener = Box::new(move || open_port(&spec));
        Ok(Self::from_connected(urg, open, config, backoff))
    }
}

impl Urg<PortTransport> {
    /// Opens `spec` (a serial device or a TCP address) and connects.
    pub fn open_spec(spec: &PortSpec, config: UrgConfig) -> Result<Self, UrgError> {
        let io = open_port(spec).map_err(|e| match spec {
            PortSpec::Serial(path) => open_error(path, e),
            PortSpec::Tcp(addr) => UrgError::NoSuchAddress {
                addr: addr.clone(),
                why: e.to_string(),
            },
        })?;
        Urg::connect(io, config)
    }
}

/// The error of a serial device that cannot be opened: a missing one is `NoSuchPort`.
fn open_error(path: &str, e: io::Error) -> UrgError {
    if e.kind() == io::ErrorKind::NotFound {
        UrgError::NoSuchPort {
            path: path.to_string(),
            why: e.to_string(),
        }
    } else if crate::port::is_disconnect(&e) {
        UrgError::Disconnected(format!("cannot open {path}: {e}"))
    } else {
        UrgError::Io(std::io::Error::new(
            e.kind(),
            format!("cannot open {path}: {e}"),
        ))
    }
}
