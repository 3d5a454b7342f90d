//! `ScipPort`: SCIP 2.0 commands over any byte transport, with reply framing, echo matching,
//! resynchronisation and timeouts.

use std::io::{self, Read, Write};
use std::ops::Range;
use std::time::{Duration, Instant};

use crate::UrgError;
use crate::codec::{
    self, Command, RawScan, Reply, ScanRequest, Status, StatusLine, StreamRequest, TimeCode,
};
use crate::info::{SensorParams, StateInfo, VersionInfo};

/// Receive buffer size; a reply longer than this without an end is discarded.
pub const RX_CAPACITY: usize = 64 * 1024;

/// Counters of what the port saw.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PortStats {
    /// Scans decoded successfully.
    pub scans: u64,
    /// Scan replies dropped for a checksum error.
    pub checksum_errors: u64,
    /// Replies dropped as malformed (garbage, truncation, bad characters).
    pub malformed_replies: u64,
    /// Well-formed replies that answered nothing pending (stale stream data, old replies).
    pub stale_replies: u64,
    /// Waits that ended in a timeout.
    pub timeouts: u64,
}

/// Timeouts of a [`ScipPort`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PortConfig {
    /// Longest wait for the reply to a command.
    pub command_timeout: Duration,
    /// Longest wait for a streamed scan.
    pub scan_timeout: Duration,
}

impl Default for PortConfig {
    fn default() -> Self {
        PortConfig {
            command_timeout: Duration::from_millis(1000),
            scan_timeout: Duration::from_millis(2000),
        }
    }
}

/// True when an I/O error means the device is gone.
pub fn is_disconnect(e: &io::Error) -> bool {
    use io::ErrorKind::*;
    matches!(
        e.kind(),
        BrokenPipe | NotConnected | ConnectionReset | ConnectionAborted | UnexpectedEof | NotFound
    ) || matches!(e.raw_os_error(), Some(5 | 6 | 19 | 32))
}

fn map_io(e: io::Error, what: &str) -> UrgError {
    if is_disconnect(&e) {
        UrgError::Disconnected(format!("{what}: {e}"))
    } else {
        UrgError::Io(e)
    }
}

/// SCIP 2.0 over a transport `T` it owns; hand the transport back with [`ScipPort::into_inner`].
#[derive(Debug)]
pub struct ScipPort<T> {
    io: T,
    rx: Vec<u8>,
    start: usize,
    end: usize,
    searched: usize,
    tx: Vec<u8>,
    config: PortConfig,
    stats: PortStats,
    stream_echo: Option<Vec<u8>>,
}

/// A reply copied out of the receive buffer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct OwnedReply {
    /// The whole reply, blank line included.
    pub bytes: Vec<u8>,
}

impl OwnedReply {
    /// The parsed parts (the reply was checked when received).
    pub fn parts(&self) -> Reply<'_> {
        codec::parse_reply(&self.bytes).expect("checked on receipt")
    }

    /// The status line.
    pub fn status(&self) -> StatusLine {
        self.parts().status
    }
}

impl<T: Read + Write> ScipPort<T> {
    /// Wraps a transport; no I/O happens.
    pub fn new(io: T, config: PortConfig) -> Self {
        ScipPort {
            io,
            rx: vec![0; RX_CAPACITY],
            start: 0,
            end: 0,
            searched: 0,
            tx: Vec::with_capacity(64),
            config,
            stats: PortStats::default(),
            stream_echo: None,
        }
    }

    /// Gives the transport back.
    pub fn into_inner(self) -> T {
        self.io
    }

    /// The transport.
    pub fn get_ref(&self) -> &T {
        &self.io
    }

    /// The transport, mutably (for tests: fault injection).
    pub fn get_mut(&mut self) -> &mut T {
        &mut self.io
    }

    /// What the port has counted so far.
    pub fn stats(&self) -> PortStats {
        self.stats
    }

    /// The timeouts in use.
    pub fn config(&self) -> PortConfig {
        self.config
    }

    /// Changes the timeouts.
    pub fn set_config(&mut self, config: PortConfig) {
        self.config = config;
    }

    /// True while an `M?` stream is active.
    pub fn is_streaming(&self) -> bool {
        self.stream_echo.is_some()
    }

    /// Writes raw bytes to the sensor.
    pub fn write_raw(&mut self, bytes: &[u8]) -> Result<(), UrgError> {
        let timeout = || UrgError::Timeout {
            command: "write".into(),
            waited_ms: 0,
        };
        self.io.write_all(bytes).map_err(|e| {
            if e.kind() == io::ErrorKind::TimedOut {
                timeout()
            } else {
                map_io(e, "write")
            }
        })?;
        // serialport reports a failed drain as a bare "flush failed", its errno dropped; a
        // terminal fails to drain only when its device is gone (unplugged mid-write).
        self.io.flush().map_err(|e| {
            if e.kind() == io::ErrorKind::TimedOut {
                timeout()
            } else {
                UrgError::Disconnected(format!("flush: {e}"))
            }
        })
    }

    /// Sends a command (with an optional tag) without waiting for its reply.
    pub fn send(&mut self, cmd: &Command, tag: Option<&str>) -> Result<(), UrgError> {
        let mut tx = std::mem::take(&mut self.tx);
        tx.clear();
        let r = cmd.encode(tag, &mut tx).and_then(|()| self.write_raw(&tx));
        self.tx = tx;
        r
    }

    /// Reads and discards everything until the line is quiet for `quiet`; returns the byte count.
    pub fn drain(&mut self, quiet: Duration) -> Result<usize, UrgError> {
        let mut n = self.end - self.start;
        self.start = 0;
        self.end = 0;
        self.searched = 0;
        let mut last = Instant::now();
        let mut buf = [0u8; 512];
        while last.elapsed() < quiet {
            match self.io.read(&mut buf) {
                Ok(0) => {
                    return Err(UrgError::Disconnected(
                        "end of stream while draining".into(),
                    ));
                }
                Ok(k) => {
                    n += k;
                    last = Instant::now();
                }
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e)
                    if matches!(
                        e.kind(),
                        io::ErrorKind::TimedOut | io::ErrorKind::WouldBlock
                    ) =>
                {
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => return Err(map_io(e, "read")),
            }
        }
        Ok(n)
    }

    /// Waits for the next complete reply; returns its range in the receive buffer.
    fn next_frame(&mut self, deadline: Instant, what: &str) -> Result<Range<usize>, UrgError> {
        let started = Instant::now();
        loop {
            let win = &self.rx[self.start..self.end];
            if let Some(n) = codec::find_reply_end_from(win, self.searched) {
                let r = self.start..self.start + n;
                self.start += n;
                self.searched = 0;
                return Ok(r);
            }
            self.searched = win.len();
            if Instant::now() >= deadline {
                self.stats.timeouts += 1;
                return Err(UrgError::Timeout {
                    command: what.to_string(),
                    waited_ms: started.elapsed().as_millis() as u64,
                });
            }
            if self.end == self.rx.len() {
                if self.start == 0 {
                    self.start = 0;
                    self.end = 0;
                    self.searched = 0;
                    self.stats.malformed_replies += 1;
                    return Err(UrgError::Overflow(RX_CAPACITY));
                }
                self.rx.copy_within(self.start..self.end, 0);
                self.end -= self.start;
                self.start = 0;
            }
            match self.io.read(&mut self.rx[self.end..]) {
                Ok(0) => {
                    return Err(UrgError::Disconnected(format!(
                        "end of stream while waiting for {what}"
                    )));
                }
                Ok(k) => self.end += k,
                Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
                Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
                Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                    std::thread::sleep(Duration::from_millis(1));
                }
                Err(e) => return Err(map_io(e, "read")),
            }
        }
    }

    fn compact(&mut self) {
        if self.start == self.end {
            self.start = 0;
            self.end = 0;
        }
    }

    /// Sends `cmd` and waits for the reply that echoes it, skipping stale or malformed replies.
    pub fn transact(&mut self, cmd: &Command, tag: Option<&str>) -> Result<OwnedReply, UrgError> {
        self.send(cmd, tag)?;
        let sent = self.tx[..self.tx.len() - 1].to_vec();
        let deadline = Instant::now() + self.config.command_timeout;
        loop {
            let r = self.next_frame(deadline, cmd.name())?;
            if r.len() == 1 {
                continue;
            }
            let frame = &self.rx[r.clone()];
            match codec::parse_reply(frame) {
                Ok(rep) if rep.echo == sent.as_slice() => {
                    let bytes = frame.to_vec();
                    self.compact();
                    return Ok(OwnedReply { bytes });
                }
                Ok(_) => self.stats.stale_replies += 1,
                Err(e) => {
                    tracing::debug!(
                        "dropping malformed reply while waiting for {}: {e}",
                        cmd.name()
                    );
                    self.stats.malformed_replies += 1;
                }
            }
        }
    }

    /// Sends `cmd` and checks its status: `00` (or one of `benign`) is Ok and returned.
    pub fn command(
        &mut self,
        cmd: &Command,
        benign: &[&[u8; 2]],
    ) -> Result<(OwnedReply, Status), UrgError> {
        let reply = self.transact(cmd, None)?;
        let status = match reply.status() {
            StatusLine::Scip2(s) => s,
            StatusLine::Scip1(c) => {
                return Err(UrgError::Framing {
                    what: format!(
                        "{} answered with the SCIP 1.1 status {:?}: the sensor is not in SCIP 2.0 mode",
                        cmd.name(),
                        c as char
                    ),
                    offset: 0,
                });
            }
        };
        if status == Status::OK || benign.iter().any(|b| **b == status.0) {
            return Ok((reply, status));
        }
        Err(UrgError::from_status(cmd.name(), status))
    }

    /// `SCIP2.0`: switches a SCIP 1.1 sensor to SCIP 2.0. Ok if it switched or already was.
    pub fn switch_to_scip2(&mut self) -> Result<(), UrgError> {
        let reply = self.transact(&Command::Scip2, None)?;
        match reply.status() {
            StatusLine::Scip1(b'0') => Ok(()),
            StatusLine::Scip2(s) if s == Status::OK || s == Status::UNDEFINED => Ok(()),
            StatusLine::Scip2(s) => Err(UrgError::from_status("SCIP2.0", s)),
            StatusLine::Scip1(c) => Err(UrgError::Framing {
                what: format!("SCIP2.0 refused with status {:?}", c as char),
                offset: 0,
            }),
        }
    }

    /// `VV`: version information.
    pub fn version(&mut self) -> Result<VersionInfo, UrgError> {
        let (r, _) = self.command(&Command::Version, &[])?;
        VersionInfo::from_reply(&r.parts())
    }

    /// `PP`: sensor parameters.
    pub fn parameters(&mut self) -> Result<SensorParams, UrgError> {
        let (r, _) = self.command(&Command::Parameters, &[])?;
        SensorParams::from_reply(&r.parts())
    }

    /// `II`: sensor state.
    pub fn state(&mut self) -> Result<StateInfo, UrgError> {
        let (r, _) = self.command(&Command::State, &[])?;
        StateInfo::from_reply(&r.parts())
    }

    /// `BM`: laser on. Returns false when it was already on.
    pub fn laser_on(&mut self) -> Result<bool, UrgError> {
        let (_, s) = self.command(&Command::LaserOn, &[b"02"])?;
        Ok(s == Status::OK)
    }

    /// `QT`: laser off; stops any stream (stream replies still in flight are skipped).
    pub fn laser_off(&mut self) -> Result<(), UrgError> {
        self.stream_echo = None;
        self.command(&Command::LaserOff, &[]).map(|_| ())
    }

    /// `RS`: resets laser, motor speed, bit rate and the sensor's timer.
    pub fn reset(&mut self) -> Result<(), UrgError> {
        self.stream_echo = None;
        self.command(&Command::Reset, &[]).map(|_| ())
    }

    /// `TM0` / `TM2`: enters or leaves time-adjust mode ("already" answers are Ok).
    pub fn time_adjust(&mut self, enter: bool) -> Result<(), UrgError> {
        if enter {
            self.command(&Command::Time(TimeCode::Enter), &[b"02"])
        } else {
            self.command(&Command::Time(TimeCode::Leave), &[b"03"])
        }
        .map(|_| ())
    }

    /// `TM1`: the sensor's 24-bit millisecond timer (time-adjust mode only).
    pub fn read_time(&mut self) -> Result<u32, UrgError> {
        let (r, _) = self.command(&Command::Time(TimeCode::Read), &[])?;
        let p = r.parts();
        let line = p.body.strip_suffix(b"\n").unwrap_or(p.body);
        if line.len() != 5 {
            return Err(UrgError::Framing {
                what: format!("TM1 time line has {} characters, expected 5", line.len()),
                offset: p.body_offset,
            });
        }
        let sum = codec::checksum(&line[..4]);
        if sum != line[4] {
            return Err(UrgError::Checksum {
                line: 3,
                offset: p.body_offset,
                expected: sum as char,
                found: line[4] as char,
            });
        }
        codec::decode_value(&line[..4])
    }

    /// `SS`: bit rate (serial only; "already" is Ok).
    pub fn set_bit_rate(&mut self, bit_rate: u32) -> Result<(), UrgError> {
        self.command(&Command::BitRate(bit_rate), &[b"03"])
            .map(|_| ())
    }

    /// `CR`: motor speed code (00 default, 01..=10, 99 reset; "already" is Ok).
    pub fn set_motor_speed(&mut self, code: u8) -> Result<(), UrgError> {
        self.command(&Command::MotorSpeed(code), &[b"03"])
            .map(|_| ())
    }

    /// `HS`: high-sensitivity mode ("already" is Ok).
    pub fn set_high_sensitivity(&mut self, on: bool) -> Result<(), UrgError> {
        self.command(&Command::HighSensitivity(on), &[b"02"])
            .map(|_| ())
    }

    /// `GD`/`GS`/`GE`: one scan into `out`.
    pub fn get_scan(&mut self, req: &ScanRequest, out: &mut RawScan) -> Result<(), UrgError> {
        let cmd = Command::Get(*req);
        self.send(&cmd, None)?;
        let sent_len = self.tx.len() - 1;
        let deadline = Instant::now() + self.config.command_timeout.max(self.config.scan_timeout);
        loop {
            let r = self.next_frame(deadline, cmd.name())?;
            if r.len() == 1 {
                continue;
            }
            let frame = &self.rx[r.clone()];
            let echo_ok = frame.len() > sent_len
                && frame[..sent_len] == self.tx[..sent_len]
                && frame[sent_len] == b'\n';
            if !echo_ok {
                self.stats.stale_replies += 1;
                continue;
            }
            let res = codec::decode_scan_reply(frame, req.kind, out).map(|_| ());
            self.compact();
            return self.count(res);
        }
    }

    fn count(&mut self, res: Result<(), UrgError>) -> Result<(), UrgError> {
        match &res {
            Ok(()) => self.stats.scans += 1,
            Err(UrgError::Checksum { .. }) => self.stats.checksum_errors += 1,
            Err(e) if e.is_reply_error() => self.stats.malformed_replies += 1,
            Err(_) => {}
        }
        res
    }

    /// `MD`/`MS`/`ME`: starts streaming; waits for the `00` acknowledgement.
    pub fn start_stream(&mut self, req: &StreamRequest) -> Result<(), UrgError> {
        let cmd = Command::Stream(*req);
        self.command(&cmd, &[])?;
        let mut echo = Vec::new();
        cmd.encode_line(None, &mut echo)?;
        self.stream_echo = Some(echo);
        Ok(())
    }

    /// The next streamed scan into `out`. Replies that are not scans of the stream are skipped;
    /// a scan with a bad checksum is dropped, counted and reported (the stream goes on).
    pub fn read_stream_scan(
        &mut self,
        kind: codec::DataKind,
        out: &mut RawScan,
    ) -> Result<(), UrgError> {
        let Some(echo) = self.stream_echo.take() else {
            return Err(UrgError::InvalidValue("no stream is active".into()));
        };
        let res = self.read_stream_scan_inner(&echo, kind, out);
        self.stream_echo = Some(echo);
        if let Err(UrgError::HardwareFault { .. } | UrgError::Status { .. }) = &res {
            // The sensor stops streaming on an error status.
            self.stream_echo = None;
        }
        res
    }

    fn read_stream_scan_inner(
        &mut self,
        echo: &[u8],
        kind: codec::DataKind,
        out: &mut RawScan,
    ) -> Result<(), UrgError> {
        let deadline = Instant::now() + self.config.scan_timeout;
        loop {
            let r = self.next_frame(deadline, "streamed scan")?;
            if r.len() == 1 {
                continue;
            }
            let frame = &self.rx[r.clone()];
            let n = echo.len();
            // Scan echoes differ from the request in the count field (bytes 13..15).
            let matches = frame.len() > n
                && frame[n] == b'\n'
                && frame[..13] == echo[..13]
                && frame[15..n] == echo[15..];
            if !matches {
                self.stats.stale_replies += 1;
                continue;
            }
            // Skip the acknowledgement (status 00 and nothing else).
            if frame[n + 1..].starts_with(b"00P\n\n") {
                continue;
            }
            let res = codec::decode_scan_reply(frame, kind, out).map(|_| ());
            self.compact();
            return self.count(res);
        }
    }

    /// Stops a stream with `QT`, skipping the scans still in flight.
    pub fn stop_stream(&mut self) -> Result<(), UrgError> {
        self.laser_off()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Takes every write; its flush fails as serialport's does when the device is gone.
    struct Vanished;

    impl Read for Vanished {
        fn read(&mut self, _: &mut [u8]) -> io::Result<usize> {
            Ok(0)
        }
    }

    impl Write for Vanished {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
            Ok(buf.len())
        }
        fn flush(&mut self) -> io::Result<()> {
            Err(io::Error::other("flush failed"))
        }
    }

    #[test]
    fn a_failed_flush_is_a_disconnect() {
        let mut port = ScipPort::new(Vanished, PortConfig::default());
        let e = port.write_raw(b"QT\n").unwrap_err();
        assert!(matches!(e, UrgError::Disconnected(_)), "{e}");
        assert!(e.to_string().contains("flush failed"), "{e}");
    }
}
