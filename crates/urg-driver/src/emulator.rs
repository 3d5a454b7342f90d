//! The sensor side of SCIP 2.0: an emulated URG-04LX or UTM-30LX that takes its ranges from
//! any `LaserSource`, usable in memory as a driver transport or on a pseudo-terminal.
//!
//! ```
//! use urg_driver::{Emulator, Model, Urg, UrgConfig};
//! use scan_types::LaserSource;
//! let mut urg = Urg::connect(Emulator::fixed(Model::Urg04lx), UrgConfig::default()).unwrap();
//! let scan = urg.next_scan().unwrap();
//! // The default fixed scan: the wall ahead is 3 m away.
//! assert_eq!(scan.ranges_m[340], 3.0);
//! ```

use std::collections::VecDeque;
use std::io::{self, Read, Write};
use std::str::FromStr;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use scan_types::{LaserSource, RayStatus, Scan, ScanGeometry};

use crate::codec::{
    self, Command, DataKind, LF, ScanRequest, Status, StreamRequest, TimeCode, encode_info_line,
    encode_scan_body, encode_status_line,
};
use crate::info::SensorParams;

/// The emulated sensor model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Model {
    /// Hokuyo URG-04LX (firmware 3.1.04, as in the shared capture).
    Urg04lx,
    /// Hokuyo UTM-30LX (firmware 1.05, as in the shared capture), with intensities.
    Utm30lx,
}

impl FromStr for Model {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s.to_ascii_lowercase().as_str() {
            "urg-04lx" | "urg04lx" => Ok(Model::Urg04lx),
            "utm-30lx" | "utm30lx" => Ok(Model::Utm30lx),
            _ => Err(format!(
                "unknown sensor model {s:?}: expected urg-04lx or utm-30lx"
            )),
        }
    }
}

/// What an emulated model reports and supports.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Profile {
    /// PP values.
    pub params: SensorParams,
    /// VV lines, in order.
    pub version: Vec<(String, String)>,
    /// `SBPS` text of II.
    pub bit_rate_text: String,
    /// `SCSP` text of II at the default speed.
    pub motor_text: String,
    /// Whether GE/ME (range + intensity) exist.
    pub intensity: bool,
    /// Whether SS/CR are supported (URG-04LX) or answer `04` (UTM-30LX).
    pub serial_settings: bool,
    /// Whether the sensor powers up in SCIP 1.1 (a factory URG-04LX does).
    pub scip1_at_power_up: bool,
}

impl Profile {
    /// The profile of `model`, with VV/PP/II text as the real captures show it.
    pub fn of(model: Model) -> Profile {
        let kv = |a: &str, b: &str| (a.to_string(), b.to_string());
        match model {
            Model::Urg04lx => Profile {
                params: SensorParams::urg_04lx(),
                version: vec![
                    kv("VEND", "Hokuyo Automatic Co.,Ltd."),
                    kv("PROD", "SOKUIKI Sensor URG-04LX"),
                    kv("FIRM", "3.1.04(02/Aug./2007)"),
                    kv("PROT", "SCIP 2.0"),
                    kv("SERI", "H0706400"),
                ],
                bit_rate_text: "19200[bps]<-Default setting by user".into(),
                motor_text: "Initial(600[rpm])<-Default setting by user".into(),
                intensity: false,
                serial_settings: true,
                scip1_at_power_up: false,
            },
            Model::Utm30lx => Profile {
                params: SensorParams::utm_30lx(),
                version: vec![
                    kv("VEND", "Hokuyo Automatic Co.,Ltd."),
                    kv("PROD", "SOKUIKI Sensor TOP-URG UTM-30LX"),
                    kv("FIRM", "P.1.05(17/Apr./2009)"),
                    kv("PROT", "SCIP 2.0"),
                    kv("SERI", "00903971"),
                ],
                bit_rate_text: "USB Full Speed".into(),
                motor_text: "Initial(2400[rpm])<-Default setting by user".into(),
                intensity: true,
                serial_settings: false,
                scip1_at_power_up: false,
            },
        }
    }
}

/// A fault the emulator injects into its next reply (or next scan reply).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Fault {
    /// The next scan reply has one data line with a wrong checksum.
    CorruptChecksum,
    /// The next scan reply stops halfway, without its blank line.
    TruncateReply,
    /// These bytes are sent before the next reply.
    Garbage(Vec<u8>),
    /// The next scan command is answered with this status (e.g. `*b"50"`, a hardware fault),
    /// and streaming stops.
    HardwareStatus([u8; 2]),
}

#[derive(Debug, Default)]
struct ControlState {
    faults: VecDeque<Fault>,
    stalled: bool,
    unplugged: bool,
    commands: Vec<String>,
    scans_served: u64,
}

/// A shared handle to steer an emulator from outside (faults, stalls, unplugging) and to see
/// what it received.
#[derive(Debug, Clone, Default)]
pub struct EmulatorControl(Arc<Mutex<ControlState>>);

impl EmulatorControl {
    fn lock(&self) -> MutexGuard<'_, ControlState> {
        self.0.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Queues a fault.
    pub fn inject(&self, fault: Fault) {
        self.lock().faults.push_back(fault);
    }

    /// Stops (true) or resumes (false) all replies; commands sent while stalled are lost.
    pub fn set_stalled(&self, stalled: bool) {
        self.lock().stalled = stalled;
    }

    /// Simulates pulling the USB cable: reads and writes fail with `BrokenPipe`.
    pub fn unplug(&self) {
        self.lock().unplugged = true;
    }

    /// Plugs the device back in.
    pub fn plug(&self) {
        self.lock().unplugged = false;
    }

    /// True while plugged in.
    pub fn is_plugged(&self) -> bool {
        !self.lock().unplugged
    }

    /// Every command line received so far (terminators removed), in order.
    pub fn commands(&self) -> Vec<String> {
        self.lock().commands.clone()
    }

    /// Scans sent so far (GD replies and streamed scans).
    pub fn scans_served(&self) -> u64 {
        self.lock().scans_served
    }
}

/// A fixed `LaserSource`: the default ranges of the emulator.
#[derive(Debug, Clone)]
pub struct FixedSource {
    geometry: ScanGeometry,
    scan: Scan,
}

impl FixedSource {
    /// A fixed scan in `geometry` as seen from a sensor in a 4.5 m x 4.5 m room: walls at
    /// x = 3.0 and x = -1.5, y = 2.5 and y = -2.0 (metres, sensor frame), an open door
    /// (nothing within range) at bearings 60..70 deg, and one error ray (code 7) at -90 deg.
    pub fn room(geometry: ScanGeometry) -> Self {
        let mut ranges = Vec::with_capacity(geometry.ray_count);
        let mut status = Vec::with_capacity(geometry.ray_count);
        for i in 0..geometry.ray_count {
            let b = geometry.bearing_rad(i);
            let (c, s) = (b.cos(), b.sin());
            let mut d = f64::INFINITY;
            if c > 1e-12 {
                d = d.min(3.0 / c);
            }
            if c < -1e-12 {
                d = d.min(-1.5 / c);
            }
            if s > 1e-12 {
                d = d.min(2.5 / s);
            }
            if s < -1e-12 {
                d = d.min(-2.0 / s);
            }
            let deg = b.to_degrees();
            if (60.0..70.0).contains(&deg) || d >= geometry.max_range_m {
                ranges.push(geometry.max_range_m);
                status.push(RayStatus::MaxRange);
            } else if (deg + 90.0).abs() < geometry.increment_rad.to_degrees() / 2.0 {
                ranges.push(f64::NAN);
                status.push(RayStatus::Error(7));
            } else {
                ranges.push(d);
                status.push(RayStatus::Hit);
            }
        }
        let scan = Scan {
            ranges_m: ranges,
            status,
            intensities: None,
            sensor_time_ms: None,
            host_time_s: 0.0,
        };
        FixedSource { geometry, scan }
    }

    /// A source that always returns `scan`.
    pub fn new(geometry: ScanGeometry, scan: Scan) -> Self {
        FixedSource { geometry, scan }
    }
}

impl LaserSource for FixedSource {
    type Error = std::convert::Infallible;
    fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }
    fn next_scan(&mut self) -> Result<Scan, Self::Error> {
        Ok(self.scan.clone())
    }
}

#[derive(Debug, Clone)]
struct StreamJob {
    req: StreamRequest,
    echo: Vec<u8>,
    remaining: Option<u32>,
    next_due_ms: u64,
    interval_ms: u64,
}

/// The emulated sensor's state machine, driven by command bytes and a millisecond clock.
pub struct SensorCore<S> {
    profile: Profile,
    source: S,
    control: EmulatorControl,
    step_map: Vec<Option<usize>>,
    scip1: bool,
    laser_on: bool,
    time_adjust: bool,
    motor_code: u8,
    bit_rate: u32,
    timer_origin_ms: u64,
    last_get_stamp_ms: Option<u64>,
    stream: Option<StreamJob>,
    inbuf: Vec<u8>,
    out: VecDeque<u8>,
}

impl<S: LaserSource> SensorCore<S> {
    /// A sensor of `profile` whose ranges come from `source`.
    pub fn new(profile: Profile, source: S, control: EmulatorControl) -> Self {
        let p = &profile.params;
        let g = *source.geometry();
        let step_map = (0..=p.amax)
            .map(|s| g.nearest_index(p.step_bearing_rad(f64::from(s))))
            .collect();
        SensorCore {
            scip1: profile.scip1_at_power_up,
            profile,
            source,
            control,
            step_map,
            laser_on: true,
            time_adjust: false,
            motor_code: 0,
            bit_rate: 19_200,
            timer_origin_ms: 0,
            last_get_stamp_ms: None,
            stream: None,
            inbuf: Vec::new(),
            out: VecDeque::new(),
        }
    }

    /// The sensor's 24-bit timer at `now_ms`.
    fn timer(&self, now_ms: u64) -> u32 {
        (now_ms.wrapping_sub(self.timer_origin_ms) & 0xFF_FFFF) as u32
    }

    /// Sets the timer so that it reads `value` at `now_ms` (e.g. close to the 24-bit wrap).
    pub fn set_timer(&mut self, now_ms: u64, value: u32) {
        self.timer_origin_ms = now_ms.wrapping_sub(u64::from(value));
    }

    /// The control handle.
    pub fn control(&self) -> &EmulatorControl {
        &self.control
    }

    /// When the next streamed scan is due, if streaming.
    pub fn next_due_ms(&self) -> Option<u64> {
        self.stream.as_ref().map(|s| s.next_due_ms)
    }

    /// Bytes waiting to be sent.
    pub fn pending(&self) -> usize {
        self.out.len()
    }

    /// Moves up to `buf.len()` pending bytes into `buf`.
    pub fn take_output(&mut self, buf: &mut [u8]) -> usize {
        let n = buf.len().min(self.out.len());
        for (d, s) in buf.iter_mut().zip(self.out.drain(..n)) {
            *d = s;
        }
        n
    }

    /// Feeds bytes written by the host; complete lines are executed at `now_ms`.
    pub fn feed(&mut self, bytes: &[u8], now_ms: u64) {
        if self.control.lock().stalled {
            return;
        }
        for &b in bytes {
            if b == b'\n' || b == b'\r' {
                let line = std::mem::take(&mut self.inbuf);
                if !line.is_empty() {
                    self.execute(&line, now_ms);
                }
            } else if self.inbuf.len() < 256 {
                self.inbuf.push(b);
            }
        }
    }

    /// Emits the streamed scan due at or before `now_ms`, if any; returns whether it did.
    pub fn poll(&mut self, now_ms: u64) -> bool {
        let Some(job) = &self.stream else {
            return false;
        };
        if job.next_due_ms > now_ms || self.control.lock().stalled {
            return false;
        }
        let mut job = job.clone();
        let stamp_ms = job.next_due_ms;
        job.next_due_ms += job.interval_ms;
        let remaining_after = job.remaining.map(|r| r.saturating_sub(1));
        let mut echo = job.echo.clone();
        let count = remaining_after.unwrap_or(0).min(99);
        echo[13] = b'0' + (count / 10) as u8;
        echo[14] = b'0' + (count % 10) as u8;
        let ok = self.scan_reply(&echo, &job.req.scan, Status::SCAN_DATA, stamp_ms);
        job.remaining = remaining_after;
        self.stream = if !ok || remaining_after == Some(0) {
            None
        } else {
            Some(job)
        };
        true
    }

    fn reply(&mut self, echo: &[u8], status: Status) {
        self.begin_reply();
        self.out.extend(echo);
        self.out.push_back(LF);
        let mut v = Vec::with_capacity(4);
        encode_status_line(status, &mut v);
        self.out.extend(v);
        self.out.push_back(LF);
    }

    fn begin_reply(&mut self) {
        let mut c = self.control.lock();
        if let Some(pos) = c.faults.iter().position(|f| matches!(f, Fault::Garbage(_)))
            && let Some(Fault::Garbage(g)) = c.faults.remove(pos)
        {
            self.out.extend(g);
        }
    }

    fn info_reply(&mut self, echo: &[u8], lines: &[(String, String)]) {
        self.begin_reply();
        let mut v = Vec::with_capacity(256);
        v.extend_from_slice(echo);
        v.push(LF);
        encode_status_line(Status::OK, &mut v);
        for (k, val) in lines {
            encode_info_line(k, val, &mut v);
        }
        v.push(LF);
        self.out.extend(v);
    }

    fn execute(&mut self, line: &[u8], now_ms: u64) {
        self.control
            .lock()
            .commands
            .push(String::from_utf8_lossy(line).into_owned());
        if self.scip1 {
            if line == b"SCIP2.0" {
                self.scip1 = false;
                self.begin_reply();
                self.out.extend(b"SCIP2.0\n0\n\n");
            } else {
                // SCIP 1.1 answers SCIP 2.0 commands with a one-character error status.
                self.begin_reply();
                self.out.extend(line);
                self.out.extend(b"\nE\n\n");
            }
            return;
        }
        let (cmd, _tag) = match Command::parse(line) {
            Ok(c) => c,
            Err(status) => return self.reply(line, status),
        };
        if self.time_adjust && !matches!(cmd, Command::Time(_)) {
            // In time-adjust mode every other command is refused as undefined.
            return self.reply(line, Status::UNDEFINED);
        }
        let p = self.profile.params.clone();
        let st = |s: &[u8; 2]| Status(*s);
        match cmd {
            Command::Scip2 => self.reply(line, Status::UNDEFINED),
            Command::Version => {
                let v = self.profile.version.clone();
                self.info_reply(line, &v);
            }
            Command::Parameters => {
                let kv = |k: &str, v: String| (k.to_string(), v);
                let lines = vec![
                    kv("MODL", p.model.clone()),
                    kv("DMIN", p.dmin_mm.to_string()),
                    kv("DMAX", p.dmax_mm.to_string()),
                    kv("ARES", p.ares.to_string()),
                    kv("AMIN", p.amin.to_string()),
                    kv("AMAX", p.amax.to_string()),
                    kv("AFRT", p.afrt.to_string()),
                    kv("SCAN", p.scan_rpm.to_string()),
                ];
                self.info_reply(line, &lines);
            }
            Command::State => {
                let kv = |k: &str, v: String| (k.to_string(), v);
                let motor = if self.motor_code == 0 {
                    self.profile.motor_text.clone()
                } else {
                    format!("Level {}", self.motor_code)
                };
                let lines = vec![
                    kv("MODL", p.model.clone()),
                    kv("LASR", if self.laser_on { "ON" } else { "OFF" }.into()),
                    kv("SCSP", motor),
                    kv("MESM", "CLASSIC".into()),
                    kv("SBPS", self.profile.bit_rate_text.clone()),
                    kv("TIME", format!("{:06X}", self.timer(now_ms))),
                    kv("STAT", "Sensor works well.".into()),
                ];
                self.info_reply(line, &lines);
            }
            Command::LaserOn => {
                let s = if self.laser_on { st(b"02") } else { Status::OK };
                self.laser_on = true;
                self.reply(line, s);
            }
            Command::LaserOff => {
                self.laser_on = false;
                self.stream = None;
                self.reply(line, Status::OK);
            }
            Command::Reset => {
                self.laser_on = false;
                self.stream = None;
                self.motor_code = 0;
                self.bit_rate = 19_200;
                self.timer_origin_ms = now_ms;
                self.reply(line, Status::OK);
            }
            Command::Time(code) => match (code, self.time_adjust) {
                (TimeCode::Enter, true) => self.reply(line, st(b"02")),
                (TimeCode::Enter, false) => {
                    self.time_adjust = true;
                    self.laser_on = false;
                    self.stream = None;
                    self.reply(line, Status::OK);
                }
                (TimeCode::Read, false) => self.reply(line, st(b"04")),
                (TimeCode::Read, true) => {
                    self.reply_no_blank(line, Status::OK);
                    let mut v = Vec::with_capacity(8);
                    let t = self.timer(now_ms);
                    codec::encode_value(t, 4, &mut v).expect("24-bit timer fits 4 chars");
                    let sum = codec::checksum(&v);
                    v.push(sum);
                    v.extend_from_slice(b"\n\n");
                    self.out.extend(v);
                }
                (TimeCode::Leave, false) => self.reply(line, st(b"03")),
                (TimeCode::Leave, true) => {
                    self.time_adjust = false;
                    self.reply(line, Status::OK);
                }
            },
            Command::BitRate(b) => {
                let s = if !self.profile.serial_settings {
                    st(b"04")
                } else if ![19_200, 38_400, 57_600, 115_200, 250_000, 500_000, 750_000].contains(&b)
                {
                    st(b"02")
                } else if b == self.bit_rate {
                    st(b"03")
                } else {
                    self.bit_rate = b;
                    Status::OK
                };
                self.reply(line, s);
            }
            Command::MotorSpeed(c) => {
                let s = if !self.profile.serial_settings {
                    st(b"04")
                } else if c == 99 {
                    self.motor_code = 0;
                    Status::OK
                } else if c > 10 {
                    st(b"02")
                } else if c == self.motor_code {
                    st(b"03")
                } else {
                    self.motor_code = c;
                    Status::OK
                };
                self.reply(line, s);
            }
            // Neither emulated firmware has high-sensitivity mode.
            Command::HighSensitivity(_) => self.reply(line, Status::UNDEFINED),
            Command::Get(req) => {
                if let Some(s) = self.check_request(&req) {
                    return self.reply(line, s);
                }
                if !self.laser_on {
                    return self.reply(line, st(b"10"));
                }
                let period = p.scan_period().as_millis().max(1) as u64;
                // Each GD takes a fresh scan from the source, so it gets a fresh scan time:
                // the latest scan start, or the next one if that was already served.
                let mut stamp = now_ms - now_ms % period;
                if let Some(last) = self.last_get_stamp_ms
                    && stamp <= last
                {
                    stamp = last + period;
                }
                self.last_get_stamp_ms = Some(stamp);
                self.scan_reply(line, &req, Status::OK, stamp);
            }
            Command::Stream(req) => {
                if let Some(s) = self.check_request(&req.scan) {
                    return self.reply(line, s);
                }
                self.laser_on = true;
                self.reply(line, Status::OK);
                let period = p.scan_period().as_millis().max(1) as u64;
                self.stream = Some(StreamJob {
                    req,
                    echo: line.to_vec(),
                    remaining: (req.count > 0).then_some(u32::from(req.count)),
                    next_due_ms: now_ms - now_ms % period + period,
                    interval_ms: period * (u64::from(req.skip) + 1),
                });
            }
        }
    }

    fn reply_no_blank(&mut self, echo: &[u8], status: Status) {
        self.begin_reply();
        self.out.extend(echo);
        self.out.push_back(LF);
        let mut v = Vec::with_capacity(4);
        encode_status_line(status, &mut v);
        self.out.extend(v);
    }

    fn check_request(&self, req: &ScanRequest) -> Option<Status> {
        let p = &self.profile.params;
        if req.kind == DataKind::RangeIntensity && !self.profile.intensity {
            return Some(Status::UNDEFINED);
        }
        if req.start_step < p.amin || req.start_step > p.amax {
            return Some(Status(*b"04"));
        }
        if req.end_step > p.amax {
            return Some(Status(*b"04"));
        }
        if req.end_step < req.start_step {
            return Some(Status(*b"05"));
        }
        None
    }

    /// Builds one scan reply from the source; returns false when a fault or source error
    /// ended the stream.
    fn scan_reply(
        &mut self,
        echo: &[u8],
        req: &ScanRequest,
        status: Status,
        stamp_ms: u64,
    ) -> bool {
        let fault = {
            let mut c = self.control.lock();
            let pos = c
                .faults
                .iter()
                .position(|f| !matches!(f, Fault::Garbage(_)));
            pos.and_then(|i| c.faults.remove(i))
        };
        if let Some(Fault::HardwareStatus(s)) = fault {
            self.reply(echo, Status(s));
            return false;
        }
        let scan = match self.source.next_scan() {
            Ok(s) => s,
            Err(e) => {
                tracing::warn!("emulator source failed: {e}; answering with a hardware fault");
                self.reply(echo, Status(*b"50"));
                return false;
            }
        };
        let (ranges, intens) = self.values(&scan, req);
        let mut v = Vec::with_capacity(ranges.len() * 4 + 64);
        v.extend_from_slice(echo);
        v.push(LF);
        encode_status_line(status, &mut v);
        encode_scan_body(self.timer(stamp_ms), &ranges, &intens, req.kind, &mut v);
        v.push(LF);
        match fault {
            Some(Fault::CorruptChecksum) => {
                // The last data line's checksum character, changed.
                let at = v.len() - 3;
                v[at] = if v[at] == b'0' { b'1' } else { b'0' };
            }
            Some(Fault::TruncateReply) => v.truncate(v.len() / 2),
            _ => {}
        }
        self.begin_reply();
        self.out.extend(v);
        self.control.lock().scans_served += 1;
        true
    }

    /// Sensor values (mm or error codes) and intensities for a request.
    fn values(&self, scan: &Scan, req: &ScanRequest) -> (Vec<u32>, Vec<u32>) {
        let p = &self.profile.params;
        let value_of = |step: usize| -> (u32, u32) {
            let Some(i) = self.step_map.get(step).copied().flatten() else {
                return (19, 0);
            };
            let intensity = scan
                .intensities
                .as_ref()
                .and_then(|v| v.get(i))
                .map(|&x| x.max(0.0) as u32);
            match (scan.status.get(i), scan.ranges_m.get(i)) {
                (Some(RayStatus::Hit), Some(&r)) if r.is_finite() => {
                    let mm = (r * 1000.0)
                        .round()
                        .clamp(f64::from(p.dmin_mm), f64::from(p.dmax_mm - 1));
                    (mm as u32, intensity.unwrap_or(1000))
                }
                (Some(RayStatus::Error(c)), _) => (u32::from(*c).min(p.dmin_mm - 1), 0),
                // No return: code 0.
                _ => (0, intensity.unwrap_or(0)),
            }
        };
        let cluster = usize::from(req.cluster.max(1));
        let mut ranges = Vec::with_capacity(req.value_count());
        let mut intens = Vec::new();
        let mut s = usize::from(req.start_step);
        let end = usize::from(req.end_step);
        while s <= end {
            let group_end = (s + cluster - 1).min(end);
            let (first, first_i) = value_of(s);
            // A cluster reports its smallest valid distance, else the first step's code.
            let best = (s..=group_end)
                .map(value_of)
                .filter(|(v, _)| *v >= p.dmin_mm)
                .min_by_key(|(v, _)| *v)
                .unwrap_or((first, first_i));
            ranges.push(best.0);
            if req.kind == DataKind::RangeIntensity {
                intens.push(best.1);
            }
            s = group_end + 1;
        }
        (ranges, intens)
    }
}

#[derive(Debug, Clone, Copy)]
enum Clock {
    Virtual(u64),
    Real(Instant),
}

/// An emulated sensor that is itself a `Read + Write` transport for the driver.
///
/// With the virtual clock (default) streamed scans come out as fast as they are read, each
/// stamped one sensor period after the last; with the real clock they come at the sensor's
/// period. A read with nothing to send fails with `TimedOut` after the read timeout, like a
/// serial port.
pub struct Emulator<S> {
    core: SensorCore<S>,
    clock: Clock,
    read_timeout: Duration,
    max_chunk: usize,
}

impl<S> std::fmt::Debug for Emulator<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Emulator")
            .field("model", &self.core.profile.params.model)
            .field("clock", &self.clock)
            .field("pending", &self.core.out.len())
            .finish_non_exhaustive()
    }
}

impl<S> std::fmt::Debug for SensorCore<S> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SensorCore")
            .field("model", &self.profile.params.model)
            .field("laser_on", &self.laser_on)
            .field("streaming", &self.stream.is_some())
            .finish_non_exhaustive()
    }
}

impl Emulator<FixedSource> {
    /// A `model` sensor that always sees the [`FixedSource::room`] scan.
    pub fn fixed(model: Model) -> Self {
        let profile = Profile::of(model);
        let g = profile.params.geometry();
        Emulator::new(profile, FixedSource::room(g))
    }
}

impl<S: LaserSource> Emulator<S> {
    /// A sensor of `profile` fed by `source`, on a virtual clock.
    pub fn new(profile: Profile, source: S) -> Self {
        Self::with_control(profile, source, EmulatorControl::default())
    }

    /// As [`Emulator::new`], steered by an existing control handle.
    pub fn with_control(profile: Profile, source: S, control: EmulatorControl) -> Self {
        Emulator {
            core: SensorCore::new(profile, source, control),
            clock: Clock::Virtual(1_000),
            read_timeout: Duration::from_millis(2),
            max_chunk: usize::MAX,
        }
    }

    /// Runs on the host's real clock: streamed scans come at the sensor's period.
    pub fn real_time(mut self) -> Self {
        self.clock = Clock::Real(Instant::now());
        self
    }

    /// Returns at most `n` bytes per read (to exercise reassembly).
    pub fn max_read_chunk(mut self, n: usize) -> Self {
        self.max_chunk = n.max(1);
        self
    }

    /// How long a read waits before `TimedOut` when there is nothing to send.
    pub fn read_timeout(mut self, t: Duration) -> Self {
        self.read_timeout = t;
        self
    }

    /// Makes the sensor start in SCIP 1.1 (as a factory URG-04LX does).
    pub fn scip1_at_power_up(mut self) -> Self {
        self.core.scip1 = true;
        self
    }

    /// Sets the sensor timer to read `value` now (to test the 24-bit wrap).
    pub fn timer_at(mut self, value: u32) -> Self {
        let now = self.now_ms();
        self.core.set_timer(now, value);
        self
    }

    /// The control handle (faults, stalls, unplugging, received commands).
    pub fn control(&self) -> EmulatorControl {
        self.core.control.clone()
    }

    /// The state machine.
    pub fn core_mut(&mut self) -> &mut SensorCore<S> {
        &mut self.core
    }

    fn now_ms(&self) -> u64 {
        match self.clock {
            Clock::Virtual(t) => t,
            Clock::Real(start) => start.elapsed().as_millis() as u64 + 1_000,
        }
    }

    fn unplugged(&self) -> bool {
        self.core.control.lock().unplugged
    }
}

fn broken_pipe() -> io::Error {
    io::Error::new(io::ErrorKind::BrokenPipe, "emulated sensor unplugged")
}

impl<S: LaserSource> Write for Emulator<S> {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        if self.unplugged() {
            return Err(broken_pipe());
        }
        if let Clock::Virtual(t) = &mut self.clock {
            // Each write takes a millisecond of sensor time.
            *t += 1;
        }
        let now = self.now_ms();
        self.core.feed(buf, now);
        if let (Clock::Virtual(t), Some(s)) = (&mut self.clock, self.core.last_get_stamp_ms) {
            // A single scan finishes before its reply: the virtual clock follows it.
            *t = (*t).max(s);
        }
        Ok(buf.len())
    }

    fn flush(&mut self) -> io::Result<()> {
        if self.unplugged() {
            return Err(broken_pipe());
        }
        Ok(())
    }
}

impl<S: LaserSource> Read for Emulator<S> {
    fn read(&mut self, buf: &mut [u8]) -> io::Result<usize> {
        loop {
            if self.unplugged() {
                return Err(broken_pipe());
            }
            let stalled = self.core.control.lock().stalled;
            if !stalled && self.core.pending() > 0 {
                let n = buf.len().min(self.max_chunk);
                return Ok(self.core.take_output(&mut buf[..n]));
            }
            let due = (!stalled).then(|| self.core.next_due_ms()).flatten();
            match (due, self.clock) {
                (Some(due), Clock::Virtual(t)) => {
                    self.clock = Clock::Virtual(t.max(due));
                    let now = self.now_ms();
                    self.core.poll(now);
                }
                (Some(due), Clock::Real(_)) => {
                    let now = self.now_ms();
                    let wait = Duration::from_millis(due.saturating_sub(now));
                    if wait > self.read_timeout {
                        std::thread::sleep(self.read_timeout);
                        return Err(io::ErrorKind::TimedOut.into());
                    }
                    std::thread::sleep(wait);
                    let now = self.now_ms();
                    self.core.poll(now);
                }
                (None, _) => {
                    std::thread::sleep(self.read_timeout);
                    return Err(io::ErrorKind::TimedOut.into());
                }
            }
        }
    }
}

/// An emulator served on a pseudo-terminal by a background thread.
pub struct PtyServer {
    path: String,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    control: EmulatorControl,
}

impl PtyServer {
    /// The device path a client opens (for example `/dev/pts/3`).
    pub fn path(&self) -> &str {
        &self.path
    }

    /// The emulator's control handle.
    pub fn control(&self) -> &EmulatorControl {
        &self.control
    }

    /// Stops serving and waits for the thread.
    pub fn stop(mut self) {
        self.shutdown();
    }

    fn shutdown(&mut self) {
        self.stop.store(true, Ordering::SeqCst);
        if let Some(h) = self.handle.take() {
            let _ = h.join();
        }
    }
}

impl Drop for PtyServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Serves a sensor on a new pseudo-terminal (real clock), until the server is stopped or dropped.
pub fn serve_pty<S: LaserSource + Send + 'static>(
    profile: Profile,
    source: S,
) -> io::Result<PtyServer> {
    serve_pty_with(SensorCore::new(profile, source, EmulatorControl::default()))
}

/// Serves a prepared sensor state machine on a new pseudo-terminal.
pub fn serve_pty_with<S: LaserSource + Send + 'static>(
    mut core: SensorCore<S>,
) -> io::Result<PtyServer> {
    use serialport::SerialPort;
    let (mut master, slave) = serialport::TTYPort::pair().map_err(io::Error::from)?;
    let path = slave
        .name()
        .ok_or_else(|| io::Error::other("pseudo-terminal has no name"))?;
    master
        .set_timeout(Duration::from_millis(2))
        .map_err(io::Error::from)?;
    let stop = Arc::new(AtomicBool::new(false));
    let control = core.control.clone();
    let stop2 = stop.clone();
    let handle = std::thread::Builder::new()
        .name("urg-emulator".into())
        .spawn(move || {
            // Keep the slave open so the master never sees a hang-up between clients.
            let _slave = slave;
            let start = Instant::now();
            let now = || start.elapsed().as_millis() as u64 + 1_000;
            let mut buf = [0u8; 1024];
            let mut out = vec![0u8; 4096];
            while !stop2.load(Ordering::SeqCst) {
                match master.read(&mut buf) {
                    Ok(n) if n > 0 => {
                        if !core.control.lock().unplugged {
                            core.feed(&buf[..n], now());
                        }
                    }
                    Ok(_) => {}
                    Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
                    Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                    Err(_) => std::thread::sleep(Duration::from_millis(5)),
                }
                core.poll(now());
                if core.control.lock().unplugged {
                    let mut sink = [0u8; 4096];
                    while core.take_output(&mut sink) > 0 {}
                    continue;
                }
                while core.pending() > 0 {
                    let n = core.take_output(&mut out);
                    if let Err(e) = master.write_all(&out[..n]) {
                        // Nobody reads the terminal: drop the output, like a sensor whose
                        // host is gone.
                        tracing::debug!("emulator output dropped: {e}");
                        break;
                    }
                }
            }
        })?;
    Ok(PtyServer {
        path,
        stop,
        handle: Some(handle),
        control,
    })
}

/// A `SensorCore` for `model` fed by `source`, for [`serve_pty_with`].
pub fn sensor<S: LaserSource>(model: Model, source: S) -> SensorCore<S> {
    SensorCore::new(Profile::of(model), source, EmulatorControl::default())
}

/// The bearing of `step` of `model` (radians), handy for building sources.
pub fn step_bearing_rad(model: Model, step: u16) -> f64 {
    Profile::of(model).params.step_bearing_rad(f64::from(step))
}
