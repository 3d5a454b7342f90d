//! The emulated sensor's state machine: its state, the byte feed that cuts command lines,
//! streamed-scan timing and reply framing.

use std::collections::VecDeque;

use scan_types::LaserSource;

use super::control::EmulatorControl;
use super::control::Fault;
use super::profile::Profile;
use crate::codec::{LF, Status, StreamRequest, encode_info_line, encode_status_line};

/// A single-scan request waiting for the scan it will be answered with.
#[derive(Debug, Clone)]
pub(super) struct GetJob {
    pub(super) echo: Vec<u8>,
    pub(super) req: crate::codec::ScanRequest,
    pub(super) due_ms: u64,
}

#[derive(Debug, Clone)]
pub(super) struct StreamJob {
    pub(super) req: StreamRequest,
    pub(super) echo: Vec<u8>,
    pub(super) remaining: Option<u32>,
    pub(super) next_due_ms: u64,
    pub(super) interval_ms: u64,
}

/// The emulated sensor's state machine, driven by command bytes and a millisecond clock.
pub struct SensorCore<S> {
    pub(super) profile: Profile,
    pub(super) source: S,
    pub(super) control: EmulatorControl,
    pub(super) step_map: Vec<Option<usize>>,
    pub(super) scip1: bool,
    pub(super) laser_on: bool,
    pub(super) time_adjust: bool,
    pub(super) motor_code: u8,
    pub(super) bit_rate: u32,
    pub(super) timer_origin_ms: u64,
    pub(super) last_get_stamp_ms: Option<u64>,
    pub(super) stream: Option<StreamJob>,
    pub(super) get: Option<GetJob>,
    /// Bytes received while a single-scan request waits: read after its reply.
    pub(super) held: Vec<u8>,
    pub(super) inbuf: Vec<u8>,
    pub(super) out: VecDeque<u8>,
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
            get: None,
            held: Vec::new(),
            inbuf: Vec::new(),
            out: VecDeque::new(),
        }
    }

    /// Powers the sensor up afresh at `now_ms` (after it was unplugged): no stream, no pending
    /// request, the timer from zero, the protocol of its power-up.
    pub fn power_up(&mut self, now_ms: u64) {
        self.scip1 = self.profile.scip1_at_power_up;
        self.laser_on = true;
        self.time_adjust = false;
        self.motor_code = 0;
        self.bit_rate = 19_200;
        self.timer_origin_ms = now_ms;
        self.last_get_stamp_ms = None;
        self.stream = None;
        self.get = None;
        self.held.clear();
        self.inbuf.clear();
        self.out.clear();
    }

    /// Forgets a client that went away (its TCP connection closed): no stream, no pending
    /// request, no queued bytes; the timer and the laser state stay as they are.
    pub(super) fn end_session(&mut self) {
        self.stream = None;
        self.get = None;
        self.held.clear();
        self.inbuf.clear();
        self.out.clear();
    }

    /// The sensor's 24-bit timer at `now_ms`.
    pub(super) fn timer(&self, now_ms: u64) -> u32 {
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

    /// When the next scan reply is due: a waiting single-scan request or the next streamed
    /// scan.
    pub fn next_due_ms(&self) -> Option<u64> {
        let get = self.get.as_ref().map(|g| g.due_ms);
        let stream = self.stream.as_ref().map(|s| s.next_due_ms);
        get.into_iter().chain(stream).min()
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
        for (k, &b) in bytes.iter().enumerate() {
            if self.get.is_some() {
                // A sensor reads its next command after answering the one it is busy with.
                self.held.extend_from_slice(&bytes[k..]);
                self.held.truncate(4096);
                return;
            }
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

    /// Emits the scan reply due at or before `now_ms`, if any; returns whether it did.
    pub fn poll(&mut self, now_ms: u64) -> bool {
        if let Some(job) = &self.get
            && job.due_ms <= now_ms
            && !self.control.lock().stalled
        {
            let job = self.get.take().expect("checked above");
            self.scan_reply(&job.echo, &job.req, Status::OK, job.due_ms);
            let held = std::mem::take(&mut self.held);
            self.feed(&held, now_ms);
            return true;
        }
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

    pub(super) fn reply(&mut self, echo: &[u8], status: Status) {
        self.reply_no_blank(echo, status);
        self.out.push_back(LF);
    }

    pub(super) fn begin_reply(&mut self) {
        let mut c = self.control.lock();
        if let Some(pos) = c.faults.iter().position(|f| matches!(f, Fault::Garbage(_)))
            && let Some(Fault::Garbage(g)) = c.faults.remove(pos)
        {
            self.out.extend(g);
        }
    }

    pub(super) fn info_reply(&mut self, echo: &[u8], lines: &[(String, String)]) {
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

    pub(super) fn reply_no_blank(&mut self, echo: &[u8], status: Status) {
        self.begin_reply();
        self.out.extend(echo);
        self.out.push_back(LF);
        let mut v = Vec::with_capacity(4);
        encode_status_line(status, &mut v);
        self.out.extend(v);
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
