//! Transport failures an emulator cannot make, with mockall: write errors, zero-byte reads,
//! interrupted reads.

use std::io;
use std::time::Duration;

use mockall::{Sequence, mock};
use urg_driver::{PortConfig, ScipPort, UrgError};

mock! {
    pub Io {}
    impl io::Read for Io {
        fn read(&mut self, buf: &mut [u8]) -> io::Result<usize>;
    }
    impl io::Write for Io {
        fn write(&mut self, buf: &[u8]) -> io::Result<usize>;
        fn flush(&mut self) -> io::Result<()>;
    }
}

fn port(io: MockIo) -> ScipPort<MockIo> {
    ScipPort::new(
        io,
        PortConfig {
            command_timeout: Duration::from_millis(100),
            scan_timeout: Duration::from_millis(100),
        },
    )
}

fn serve(bytes: &'static [u8]) -> impl FnMut(&mut [u8]) -> io::Result<usize> {
    let mut pos = 0;
    move |buf: &mut [u8]| {
        let n = buf.len().min(bytes.len() - pos).min(3);
        buf[..n].copy_from_slice(&bytes[pos..pos + n]);
        pos += n;
        if n == 0 {
            Err(io::ErrorKind::TimedOut.into())
        } else {
            Ok(n)
        }
    }
}

#[test]
fn write_errors_are_reported() {
    let mut io = MockIo::new();
    io.expect_write()
        .returning(|_| Err(io::Error::new(io::ErrorKind::PermissionDenied, "denied")));
    let mut p = port(io);
    let e = p.version().unwrap_err();
    assert!(
        matches!(e, UrgError::Io(ref x) if x.kind() == io::ErrorKind::PermissionDenied),
        "{e}"
    );

    let mut io = MockIo::new();
    io.expect_write()
        .returning(|_| Err(io::Error::from(io::ErrorKind::BrokenPipe)));
    let e = port(io).version().unwrap_err();
    assert!(matches!(e, UrgError::Disconnected(_)), "{e}");

    // EIO from a vanished USB device is a disconnect too.
    let mut io = MockIo::new();
    io.expect_write()
        .returning(|_| Err(io::Error::from_raw_os_error(5)));
    assert!(matches!(port(io).version(), Err(UrgError::Disconnected(_))));

    // A write that accepts nothing is an error (write_all's WriteZero), not a loop.
    let mut io = MockIo::new();
    io.expect_write().returning(|_| Ok(0));
    assert!(matches!(port(io).version(), Err(UrgError::Io(_))));
}

#[test]
fn a_zero_byte_read_is_end_of_stream() {
    let mut io = MockIo::new();
    io.expect_write().returning(|b| Ok(b.len()));
    io.expect_flush().returning(|| Ok(()));
    io.expect_read().returning(|_| Ok(0));
    let e = port(io).version().unwrap_err();
    assert!(matches!(e, UrgError::Disconnected(_)), "{e}");
}

#[test]
fn interrupted_and_timed_out_reads_are_retried() {
    let mut io = MockIo::new();
    io.expect_write().returning(|b| Ok(b.len()));
    io.expect_flush().returning(|| Ok(()));
    let mut seq = Sequence::new();
    io.expect_read()
        .times(1)
        .in_sequence(&mut seq)
        .returning(|_| Err(io::ErrorKind::Interrupted.into()));
    io.expect_read()
        .times(1)
        .in_sequence(&mut seq)
        .returning(|_| Err(io::ErrorKind::WouldBlock.into()));
    io.expect_read()
        .times(1)
        .in_sequence(&mut seq)
        .returning(|_| Err(io::ErrorKind::Interrupted.into()));
    io.expect_read()
        .in_sequence(&mut seq)
        .returning(serve(b"QT\n00P\n\n"));
    let mut p = port(io);
    p.laser_off().unwrap();
}

#[test]
fn silence_is_a_timeout() {
    let mut io = MockIo::new();
    io.expect_write().returning(|b| Ok(b.len()));
    io.expect_flush().returning(|| Ok(()));
    io.expect_read().returning(|_| {
        std::thread::sleep(Duration::from_millis(5));
        Err(io::ErrorKind::TimedOut.into())
    });
    let t = std::time::Instant::now();
    let e = port(io).version().unwrap_err();
    assert!(
        matches!(e, UrgError::Timeout { ref command, .. } if command == "VV"),
        "{e}"
    );
    assert!(t.elapsed() < Duration::from_secs(1));
}

#[test]
fn other_read_errors_are_io_errors() {
    let mut io = MockIo::new();
    io.expect_write().returning(|b| Ok(b.len()));
    io.expect_flush().returning(|| Ok(()));
    io.expect_read()
        .returning(|_| Err(io::Error::new(io::ErrorKind::InvalidData, "framing")));
    assert!(matches!(port(io).version(), Err(UrgError::Io(_))));
}
