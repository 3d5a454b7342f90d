//! Serving an emulated sensor on a pseudo-terminal from a background thread.

use std::io::{self, Read, Write};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use scan_types::LaserSource;

use super::control::EmulatorControl;
use super::machine::SensorCore;
use super::profile::{Model, Profile};

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
