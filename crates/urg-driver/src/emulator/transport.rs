//! The emulator as an in-memory `Read + Write` transport, on a virtual or real clock.

use std::io::{self, Read, Write};
use std::time::{Duration, Instant};

use scan_types::LaserSource;

use super::control::EmulatorControl;
use super::machine::SensorCore;
use super::profile::{Model, Profile};
use super::source::FixedSource;

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
