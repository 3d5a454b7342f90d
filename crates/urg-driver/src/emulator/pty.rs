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
///
/// Like a USB sensor under udev, it is reached through a stable link (`path()`) to the
/// current pseudo-terminal. Unplugging (through [`EmulatorControl::unplug`]) closes the
/// terminal, so that a client's reads and writes fail as on a real unplug, and removes the
/// link; plugging in again opens a new terminal behind the same link, with the sensor powered
/// up afresh.
pub struct PtyServer {
    path: String,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    control: EmulatorControl,
}

impl PtyServer {
    /// The stable device path a client opens (a link to the current pseudo-terminal).
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
        let _ = std::fs::remove_file(&self.path);
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

/// One plugged-in pseudo-terminal: the master the emulator serves and the slave it keeps
/// open, so that the master never sees a hang-up between clients.
struct Plugged {
    master: serialport::TTYPort,
    _slave: serialport::TTYPort,
}

/// Opens a new pseudo-terminal and points `link` at it.
fn plug_in(link: &std::path::Path) -> io::Result<Plugged> {
    use serialport::SerialPort;
    let (master0, slave0) = serialport::TTYPort::pair().map_err(io::Error::from)?;
    // Close-on-exec copies: a child process started by this one must not keep the master
    // open, or closing it would not hang up the terminal (no unplug seen).
    let mut master = master0.try_clone_native().map_err(io::Error::from)?;
    let slave = slave0.try_clone_native().map_err(io::Error::from)?;
    drop((master0, slave0));
    let device = slave
        .name()
        .ok_or_else(|| io::Error::other("pseudo-terminal has no name"))?;
    master
        .set_timeout(Duration::from_millis(2))
        .map_err(io::Error::from)?;
    // Replaced in one step, as udev does.
    let tmp = link.with_extension("new");
    let _ = std::fs::remove_file(&tmp);
    std::os::unix::fs::symlink(&device, &tmp)?;
    std::fs::rename(&tmp, link)?;
    Ok(Plugged {
        master,
        _slave: slave,
    })
}

/// A link path of this process's own, in the temporary folder.
fn new_link_path() -> std::path::PathBuf {
    use std::sync::atomic::AtomicU32;
    static NEXT: AtomicU32 = AtomicU32::new(0);
    let n = NEXT.fetch_add(1, Ordering::SeqCst);
    std::env::temp_dir().join(format!("goalseek-urg-{}-{n}", std::process::id()))
}

/// Serves a prepared sensor state machine on a new pseudo-terminal.
pub fn serve_pty_with<S: LaserSource + Send + 'static>(
    mut core: SensorCore<S>,
) -> io::Result<PtyServer> {
    let link = new_link_path();
    let mut plugged = Some(plug_in(&link)?);
    let path = link.to_string_lossy().into_owned();
    let stop = Arc::new(AtomicBool::new(false));
    let control = core.control.clone();
    let stop2 = stop.clone();
    let handle = std::thread::Builder::new()
        .name("urg-emulator".into())
        .spawn(move || {
            let start = Instant::now();
            let now = || start.elapsed().as_millis() as u64 + 1_000;
            let mut buf = [0u8; 1024];
            let mut out = vec![0u8; 4096];
            while !stop2.load(Ordering::SeqCst) {
                let unplugged = core.control.lock().unplugged;
                match (&mut plugged, unplugged) {
                    (Some(_), true) => {
                        // Closing the terminal is what the client sees of an unplug.
                        plugged = None;
                        let _ = std::fs::remove_file(&link);
                        tracing::debug!("emulated sensor unplugged");
                        continue;
                    }
                    (None, false) => {
                        core.power_up(now());
                        match plug_in(&link) {
                            Ok(p) => plugged = Some(p),
                            Err(e) => {
                                tracing::warn!("emulator cannot plug in again: {e}");
                                std::thread::sleep(Duration::from_millis(50));
                            }
                        }
                        continue;
                    }
                    (None, true) => {
                        std::thread::sleep(Duration::from_millis(5));
                        continue;
                    }
                    (Some(p), false) => {
                        serve_once(&mut core, &mut p.master, &mut buf, &mut out, now())
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

/// One round of the server: read what the client wrote, emit what is due, write it out.
fn serve_once<S: LaserSource>(
    core: &mut SensorCore<S>,
    master: &mut serialport::TTYPort,
    buf: &mut [u8],
    out: &mut [u8],
    now_ms: u64,
) {
    match master.read(buf) {
        Ok(n) if n > 0 => core.feed(&buf[..n], now_ms),
        Ok(_) => {}
        Err(e) if e.kind() == io::ErrorKind::TimedOut => {}
        Err(e) if e.kind() == io::ErrorKind::Interrupted => {}
        Err(_) => std::thread::sleep(Duration::from_millis(5)),
    }
    core.poll(now_ms);
    while core.pending() > 0 {
        let n = core.take_output(out);
        if let Err(e) = master.write_all(&out[..n]) {
            // Nobody reads the terminal: drop the output, like a sensor whose host is gone.
            tracing::debug!("emulator output dropped: {e}");
            break;
        }
    }
}

/// A `SensorCore` for `model` fed by `source`, for [`serve_pty_with`].
pub fn sensor<S: LaserSource>(model: Model, source: S) -> SensorCore<S> {
    SensorCore::new(Profile::of(model), source, EmulatorControl::default())
}
