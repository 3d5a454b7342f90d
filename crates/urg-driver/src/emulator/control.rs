//! Steering an emulator from outside: injected faults, stalls, unplugging, and a record of
//! what it received.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex, MutexGuard};

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
pub(super) struct ControlState {
    pub(super) faults: VecDeque<Fault>,
    pub(super) stalled: bool,
    pub(super) unplugged: bool,
    pub(super) commands: Vec<String>,
    pub(super) scans_served: u64,
}

/// A shared handle to steer an emulator from outside (faults, stalls, unplugging) and to see
/// what it received.
#[derive(Debug, Clone, Default)]
pub struct EmulatorControl(Arc<Mutex<ControlState>>);

impl EmulatorControl {
    pub(super) fn lock(&self) -> MutexGuard<'_, ControlState> {
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
