//! The line protocol: one ASCII command a line, one answer a line.
//!
//! The host sends `rotate RAD` (turn in place, counter-clockwise positive), `forward M` (drive
//! straight, metres, negative backwards) or `stop`; the base answers each with one line, `done`
//! when the move is finished or `error <text>` when it could not be made. Blank lines and lines
//! starting with `#` from the base are ignored (free for its own logging).

use std::io::{BufRead, Write};

use scan_types::MotionBase;

use crate::BaseError;
use crate::answers::Answers;

/// The line to send for a rotation.
pub fn rotate_line(angle_rad: f64) -> String {
    format!("rotate {angle_rad:.6}")
}

/// The line to send for a straight drive.
pub fn forward_line(distance_m: f64) -> String {
    format!("forward {distance_m:.4}")
}

/// A base spoken to over the line protocol on any reader/writer pair.
pub struct LineBase<W> {
    answers: Answers,
    writer: W,
    cancel: Option<fn() -> bool>,
}

impl<W: Write> LineBase<W> {
    /// A base that reads answers from `reader` (on a thread of its own) and writes commands
    /// to `writer`.
    pub fn new<R: BufRead + Send + 'static>(reader: R, writer: W) -> Self {
        Self {
            answers: Answers::new(reader),
            writer,
            cancel: None,
        }
    }

    /// Gives up waiting for a move's answer once `cancel` returns true (checked every 50 ms);
    /// the move then fails with [`BaseError::Cancelled`]. `stop` is always waited for.
    pub fn with_cancel(mut self, cancel: fn() -> bool) -> Self {
        self.cancel = Some(cancel);
        self
    }

    /// Gives the writer back.
    pub fn into_writer(self) -> W {
        self.writer
    }

    /// Sends one command and waits for its answer.
    pub fn command(&mut self, command: &str) -> Result<(), BaseError> {
        tracing::debug!(command, "base <-");
        self.writer.write_all(command.as_bytes())?;
        self.writer.write_all(b"\n")?;
        self.writer.flush()?;
        let cancel = if command == "stop" { None } else { self.cancel };
        loop {
            let Some(line) = self.answers.next(command, cancel)? else {
                return Err(BaseError::Closed {
                    command: command.to_string(),
                });
            };
            let t = line.trim();
            tracing::debug!(answer = t, "base ->");
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            if t == "done" {
                return Ok(());
            }
            if let Some(rest) = t.strip_prefix("error")
                && (rest.is_empty() || rest.starts_with(char::is_whitespace))
            {
                return Err(BaseError::Refused {
                    command: command.to_string(),
                    message: rest.trim().to_string(),
                });
            }
            return Err(BaseError::Protocol {
                command: command.to_string(),
                line: t.to_string(),
            });
        }
    }
}

impl<W: Write> MotionBase for LineBase<W> {
    type Error = BaseError;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), BaseError> {
        self.command(&rotate_line(angle_rad))
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), BaseError> {
        self.command(&forward_line(distance_m))
    }
    fn stop(&mut self) -> Result<(), BaseError> {
        self.command("stop")
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn base(answers: &str) -> LineBase<Vec<u8>> {
        LineBase::new(Cursor::new(answers.as_bytes().to_vec()), Vec::new())
    }

    #[test]
    fn sends_one_line_per_command_and_reads_done() {
        let mut b = base("done\n# turning\n\ndone\ndone\n");
        b.rotate(0.5).unwrap();
        b.forward(-0.25).unwrap();
        b.stop().unwrap();
        let sent = b.into_writer();
        assert_eq!(
            String::from_utf8(sent).unwrap(),
            "rotate 0.500000\nforward -0.2500\nstop\n"
        );
    }

    #[test]
    fn error_answer_carries_its_text() {
        let mut b = base("error bumper pressed\n");
        let e = b.forward(1.0).unwrap_err();
        assert!(
            matches!(&e, BaseError::Refused { command, message } if command == "forward 1.0000" && message == "bumper pressed"),
            "{e}"
        );
    }

    #[test]
    fn garbage_and_eof_are_errors() {
        let mut b = base("ok\n");
        assert!(matches!(b.stop(), Err(BaseError::Protocol { line, .. }) if line == "ok"));
        let mut b = base("errors\n");
        assert!(matches!(b.stop(), Err(BaseError::Protocol { .. })));
        let mut b = base("");
        assert!(matches!(b.rotate(1.0), Err(BaseError::Closed { .. })));
    }

    #[test]
    fn crlf_answers_are_accepted() {
        let mut b = base("done\r\nerror\r\n");
        b.stop().unwrap();
        assert!(matches!(b.stop(), Err(BaseError::Refused { message, .. }) if message.is_empty()));
    }

    #[test]
    fn an_endless_answer_is_cut_and_named() {
        let long = format!("{}\ndone\n", "x".repeat(3 * crate::MAX_LINE_BYTES));
        let mut b = base(&long);
        let e = b.forward(1.0).unwrap_err();
        let BaseError::Protocol { line, .. } = &e else {
            panic!("{e}");
        };
        assert!(line.len() < 200, "{line}");
        assert!(
            line.contains(&format!("{} bytes", 3 * crate::MAX_LINE_BYTES)),
            "{line}"
        );
        // The rest of the long line was dropped: the next answer is read whole.
        b.stop().unwrap();
    }

    static GIVE_UP: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

    fn give_up() -> bool {
        GIVE_UP.load(std::sync::atomic::Ordering::SeqCst)
    }

    #[test]
    fn a_move_never_answered_is_given_up_but_stop_is_waited_for() {
        use std::io::{BufReader, Write};
        use std::os::unix::net::UnixStream;
        let (host, mut peer) = UnixStream::pair().unwrap();
        let mut b =
            LineBase::new(BufReader::new(host.try_clone().unwrap()), host).with_cancel(give_up);
        GIVE_UP.store(true, std::sync::atomic::Ordering::SeqCst);
        let t = std::time::Instant::now();
        let e = b.forward(1.0).unwrap_err();
        assert!(
            matches!(&e, BaseError::Cancelled { command } if command == "forward 1.0000"),
            "{e}"
        );
        assert!(t.elapsed() < std::time::Duration::from_secs(1));
        // `stop` is not given up: it waits for the base's answer.
        let answer = std::thread::spawn(move || {
            std::thread::sleep(std::time::Duration::from_millis(200));
            writeln!(peer, "done").unwrap();
            peer
        });
        b.stop().unwrap();
        assert!(t.elapsed() >= std::time::Duration::from_millis(200));
        drop(answer.join().unwrap());
    }

    /// A peer on the other end of a pipe pair that executes moves and answers.
    #[test]
    fn talks_to_a_peer_thread() {
        use std::io::{BufRead, BufReader, Write};
        use std::os::unix::net::UnixStream;
        let (host, peer) = UnixStream::pair().unwrap();
        let handle = std::thread::spawn(move || {
            let mut r = BufReader::new(peer.try_clone().unwrap());
            let mut w = peer;
            let mut heading = 0.0f64;
            let mut x = 0.0f64;
            let mut line = String::new();
            while r.read_line(&mut line).unwrap() > 0 {
                let mut it = line.split_whitespace();
                let answer = match (it.next(), it.next().map(str::parse::<f64>)) {
                    (Some("rotate"), Some(Ok(a))) => {
                        heading += a;
                        "done".to_string()
                    }
                    (Some("forward"), Some(Ok(d))) if d <= 2.0 => {
                        x += d * heading.cos();
                        "done".to_string()
                    }
                    (Some("forward"), _) => "error too far".to_string(),
                    (Some("stop"), None) => "done".to_string(),
                    _ => format!("error bad command {line:?}"),
                };
                writeln!(w, "{answer}").unwrap();
                line.clear();
            }
            (heading, x)
        });
        let mut b = LineBase::new(BufReader::new(host.try_clone().unwrap()), host);
        b.rotate(std::f64::consts::PI).unwrap();
        b.forward(1.5).unwrap();
        assert!(matches!(b.forward(3.0), Err(BaseError::Refused { .. })));
        b.stop().unwrap();
        let w = b.into_writer();
        w.shutdown(std::net::Shutdown::Both).unwrap();
        let (heading, x) = handle.join().unwrap();
        assert!((heading - std::f64::consts::PI).abs() < 1e-6);
        assert!((x + 1.5).abs() < 1e-4);
    }
}
