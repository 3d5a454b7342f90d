//! Serving an emulated sensor over TCP, as an Ethernet Hokuyo does (port 10940), from a
//! background thread: one client at a time.

use std::io::{self, Read, Write};
use std::net::{Shutdown, SocketAddr, TcpListener, TcpStream};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use scan_types::LaserSource;

use super::control::EmulatorControl;
use super::machine::SensorCore;
use super::profile::Profile;

/// Longest wait for a client's bytes or a connection, so that stopping and unplugging are
/// seen within this time.
const IDLE_WAIT: Duration = Duration::from_millis(50);

/// An emulator served on a TCP address by a background thread.
///
/// One client is served at a time; a second one waits in the listen queue until the first
/// closes its connection. A client that disconnects ends its stream and pending requests,
/// and the server waits for the next one. Unplugging (through [`EmulatorControl::unplug`])
/// closes the connection and the listening socket (connections are refused); plugging in
/// again listens on the same address, with the sensor powered up afresh.
pub struct TcpServer {
    addr: SocketAddr,
    stop: Arc<AtomicBool>,
    handle: Option<JoinHandle<()>>,
    control: EmulatorControl,
}

impl TcpServer {
    /// The address the server listens on (with the actual port when bound to port 0).
    pub fn local_addr(&self) -> SocketAddr {
        self.addr
    }

    /// The emulator's control handle.
    pub fn control(&self) -> &EmulatorControl {
        &self.control
    }

    /// Stops serving (closing any connection) and waits for the thread.
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

impl Drop for TcpServer {
    fn drop(&mut self) {
        self.shutdown();
    }
}

/// Serves a sensor on the TCP address `addr` (real clock), until the server is stopped or
/// dropped.
pub fn serve_tcp<S: LaserSource + Send + 'static>(
    addr: SocketAddr,
    profile: Profile,
    source: S,
) -> io::Result<TcpServer> {
    serve_tcp_with(
        addr,
        SensorCore::new(profile, source, EmulatorControl::default()),
    )
}

/// Binds `addr` and makes the listener non-blocking (accepts are polled at [`IDLE_WAIT`]).
fn listen(addr: SocketAddr) -> io::Result<TcpListener> {
    let listener = TcpListener::bind(addr)?;
    listener.set_nonblocking(true)?;
    Ok(listener)
}

/// Serves a prepared sensor state machine on the TCP address `addr`; binding errors (address
/// in use, not local) are returned at once.
pub fn serve_tcp_with<S: LaserSource + Send + 'static>(
    addr: SocketAddr,
    mut core: SensorCore<S>,
) -> io::Result<TcpServer> {
    let first = listen(addr)?;
    let addr = first.local_addr()?;
    let stop = Arc::new(AtomicBool::new(false));
    let control = core.control().clone();
    let stop2 = stop.clone();
    let handle = std::thread::Builder::new()
        .name("urg-emulator-tcp".into())
        .spawn(move || {
            let start = Instant::now();
            let now = || start.elapsed().as_millis() as u64 + 1_000;
            let mut listener = Some(first);
            let mut client: Option<TcpStream> = None;
            let mut buf = [0u8; 1024];
            let mut out = vec![0u8; 4096];
            while !stop2.load(Ordering::SeqCst) {
                if core.control().is_plugged() {
                    if listener.is_none() {
                        core.power_up(now());
                        match listen(addr) {
                            Ok(l) => listener = Some(l),
                            Err(e) => {
                                tracing::warn!("emulator cannot listen on {addr} again: {e}");
                                std::thread::sleep(IDLE_WAIT);
                            }
                        }
                        continue;
                    }
                } else {
                    if let Some(c) = client.take() {
                        let _ = c.shutdown(Shutdown::Both);
                    }
                    if listener.take().is_some() {
                        tracing::debug!("emulated sensor unplugged from {addr}");
                    }
                    std::thread::sleep(IDLE_WAIT);
                    continue;
                }
                match (&mut client, &listener) {
                    (Some(c), _) => {
                        if !serve_once(&mut core, c, &mut buf, &mut out, now) {
                            tracing::debug!("emulator client left");
                            core.end_session();
                            client = None;
                        }
                    }
                    (None, Some(l)) => match l.accept() {
                        Ok((c, peer)) => match prepare(&c) {
                            Ok(()) => {
                                tracing::debug!("emulator client {peer} connected");
                                client = Some(c);
                            }
                            Err(e) => tracing::warn!("emulator client {peer} dropped: {e}"),
                        },
                        Err(e) if e.kind() == io::ErrorKind::WouldBlock => {
                            std::thread::sleep(IDLE_WAIT)
                        }
                        Err(e) => {
                            tracing::warn!("emulator accept failed: {e}");
                            std::thread::sleep(IDLE_WAIT);
                        }
                    },
                    (None, None) => std::thread::sleep(IDLE_WAIT),
                }
            }
        })?;
    Ok(TcpServer {
        addr,
        stop,
        handle: Some(handle),
        control,
    })
}

/// Sets up an accepted connection: blocking reads with a timeout, no Nagle delay.
fn prepare(c: &TcpStream) -> io::Result<()> {
    c.set_nonblocking(false)?;
    c.set_nodelay(true)?;
    c.set_write_timeout(Some(Duration::from_secs(1)))
}

/// One round with a client: wait for its bytes until the next scan is due (at most
/// [`IDLE_WAIT`]), emit what is due, write it out. False when the client is gone.
fn serve_once<S: LaserSource>(
    core: &mut SensorCore<S>,
    c: &mut TcpStream,
    buf: &mut [u8],
    out: &mut [u8],
    now: impl Fn() -> u64,
) -> bool {
    let t = now();
    let wait = core
        .next_due_ms()
        .map_or(IDLE_WAIT, |due| {
            Duration::from_millis(due.saturating_sub(t))
        })
        .clamp(Duration::from_millis(1), IDLE_WAIT);
    if c.set_read_timeout(Some(wait)).is_err() {
        return false;
    }
    match c.read(buf) {
        Ok(0) => return false,
        Ok(n) => core.feed(&buf[..n], now()),
        Err(e)
            if matches!(
                e.kind(),
                io::ErrorKind::WouldBlock | io::ErrorKind::TimedOut | io::ErrorKind::Interrupted
            ) => {}
        Err(_) => return false,
    }
    core.poll(now());
    while core.pending() > 0 {
        let n = core.take_output(out);
        if let Err(e) = c.write_all(&out[..n]) {
            tracing::debug!("emulator output to a client failed: {e}");
            return false;
        }
    }
    true
}
