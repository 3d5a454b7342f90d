//! Robot bases for `robot-app run`: a line protocol over stdin/stdout or a serial port, and a
//! manual base that asks a person to make each move.
//!
//! The line protocol (documented in `docs/base-protocol.md`): the host sends one ASCII command a
//! line, `rotate RAD` (turn in place, counter-clockwise positive), `forward M` (drive straight,
//! metres, negative backwards) or `stop`; the base answers each with one line, `done` when the move
//! is finished or `error <text>` when it could not be made. Blank lines and lines starting with `#`
//! from the base are ignored (free for its own logging).

use std::io::{BufRead, BufReader, Write};

use scan_types::MotionBase;

/// What can go wrong talking to a base.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum BaseError {
    /// Reading or writing the link failed.
    #[error("base link: {0}")]
    Io(#[from] std::io::Error),
    /// The base answered `error ...`.
    #[error("base refused '{command}': {message}")]
    Refused {
        /// The command sent.
        command: String,
        /// The base's text after `error`.
        message: String,
    },
    /// The base answered something that is not `done` or `error ...`.
    #[error("base answered '{line}' to '{command}' (expected 'done' or 'error ...')")]
    Protocol {
        /// The command sent.
        command: String,
        /// The line received.
        line: String,
    },
    /// The link closed before the answer.
    #[error("base link closed while waiting for the answer to '{command}'")]
    Closed {
        /// The command sent.
        command: String,
    },
    /// The operator stopped a manual run.
    #[error("stopped by the operator")]
    Aborted,
}

/// The line to send for a rotation.
pub fn rotate_line(angle_rad: f64) -> String {
    format!("rotate {angle_rad:.6}")
}

/// The line to send for a straight drive.
pub fn forward_line(distance_m: f64) -> String {
    format!("forward {distance_m:.4}")
}

/// A base spoken to over the line protocol on any reader/writer pair.
pub struct LineBase<R, W> {
    reader: R,
    writer: W,
}

impl<R: BufRead, W: Write> LineBase<R, W> {
    /// A base that reads answers from `reader` and writes commands to `writer`.
    pub fn new(reader: R, writer: W) -> Self {
        Self { reader, writer }
    }

    /// Gives the reader and writer back.
    pub fn into_inner(self) -> (R, W) {
        (self.reader, self.writer)
    }

    /// Sends one command and waits for its answer.
    pub fn command(&mut self, command: &str) -> Result<(), BaseError> {
        tracing::debug!(command, "base <-");
        self.writer.write_all(command.as_bytes())?;
        self.writer.write_all(b"\n")?;
        self.writer.flush()?;
        let mut line = String::new();
        loop {
            line.clear();
            let n = match self.reader.read_line(&mut line) {
                Ok(n) => n,
                // A serial port with a read timeout: keep waiting, moves can be slow.
                Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                Err(e) => return Err(e.into()),
            };
            if n == 0 {
                return Err(BaseError::Closed {
                    command: command.to_string(),
                });
            }
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

impl<R: BufRead, W: Write> MotionBase for LineBase<R, W> {
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

/// A base moved by a person: each move is printed, and Enter confirms it was made
/// (`q` then Enter stops the run).
pub struct ManualBase<R, W> {
    reader: R,
    writer: W,
    moves: usize,
}

impl<R: BufRead, W: Write> ManualBase<R, W> {
    /// A manual base prompting on `writer` and reading confirmations from `reader`.
    pub fn new(reader: R, writer: W) -> Self {
        Self {
            reader,
            writer,
            moves: 0,
        }
    }

    fn ask(&mut self, what: &str) -> Result<(), BaseError> {
        self.moves += 1;
        write!(
            self.writer,
            "move {}: {what}; press Enter when done (q to stop) ",
            self.moves
        )?;
        self.writer.flush()?;
        let mut line = String::new();
        if self.reader.read_line(&mut line)? == 0 {
            return Err(BaseError::Closed {
                command: what.to_string(),
            });
        }
        if line.trim().eq_ignore_ascii_case("q") {
            return Err(BaseError::Aborted);
        }
        Ok(())
    }
}

impl<R: BufRead, W: Write> MotionBase for ManualBase<R, W> {
    type Error = BaseError;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), BaseError> {
        let side = if angle_rad >= 0.0 {
            "left (counter-clockwise)"
        } else {
            "right (clockwise)"
        };
        self.ask(&format!(
            "turn in place {:.1} deg {side}",
            angle_rad.to_degrees().abs()
        ))
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), BaseError> {
        let way = if distance_m >= 0.0 {
            "forward"
        } else {
            "backward"
        };
        self.ask(&format!(
            "drive straight {way} {:.1} cm",
            distance_m.abs() * 100.0
        ))
    }
    fn stop(&mut self) -> Result<(), BaseError> {
        writeln!(self.writer, "stop: the run has ended")?;
        self.writer.flush()?;
        Ok(())
    }
}

/// A base chosen on the command line: `stdio`, `serial:PATH[@BAUD]` or `manual`.
pub type DynBase = Box<dyn MotionBase<Error = BaseError> + Send>;

/// Opens the base named by `spec` (see [`DynBase`]).
pub fn open_base(spec: &str) -> anyhow::Result<DynBase> {
    use anyhow::Context;
    if spec == "stdio" {
        return Ok(Box::new(LineBase::new(
            BufReader::new(std::io::stdin()),
            std::io::stdout(),
        )));
    }
    if spec == "manual" {
        return Ok(Box::new(ManualBase::new(
            BufReader::new(std::io::stdin()),
            std::io::stderr(),
        )));
    }
    if let Some(rest) = spec.strip_prefix("serial:") {
        let (path, baud) = match rest.rsplit_once('@') {
            Some((p, b)) => (
                p,
                b.parse::<u32>()
                    .with_context(|| format!("--base {spec}: baud rate '{b}' is not a number"))?,
            ),
            None => (rest, 115_200),
        };
        if path.is_empty() {
            anyhow::bail!("--base {spec}: no serial port path after 'serial:'");
        }
        let port = serialport::new(path, baud)
            .timeout(std::time::Duration::from_secs(5))
            .open()
            .with_context(|| format!("cannot open base serial port {path}"))?;
        let reader = port
            .try_clone()
            .with_context(|| format!("cannot share base serial port {path}"))?;
        return Ok(Box::new(LineBase::new(BufReader::new(reader), port)));
    }
    anyhow::bail!("--base '{spec}': expected stdio, serial:PATH[@BAUD] or manual")
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

    fn base(answers: &str) -> LineBase<Cursor<Vec<u8>>, Vec<u8>> {
        LineBase::new(Cursor::new(answers.as_bytes().to_vec()), Vec::new())
    }

    #[test]
    fn sends_one_line_per_command_and_reads_done() {
        let mut b = base("done\n# turning\n\ndone\ndone\n");
        b.rotate(0.5).unwrap();
        b.forward(-0.25).unwrap();
        b.stop().unwrap();
        let (_, sent) = b.into_inner();
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
        let (_, w) = b.into_inner();
        w.shutdown(std::net::Shutdown::Both).unwrap();
        let (heading, x) = handle.join().unwrap();
        assert!((heading - std::f64::consts::PI).abs() < 1e-6);
        assert!((x + 1.5).abs() < 1e-4);
    }

    #[test]
    fn manual_base_prompts_and_waits() {
        let mut b = ManualBase::new(Cursor::new(b"\n\nq\n".to_vec()), Vec::new());
        b.rotate(-std::f64::consts::FRAC_PI_2).unwrap();
        b.forward(0.25).unwrap();
        assert!(matches!(b.forward(0.1), Err(BaseError::Aborted)));
        let text = String::from_utf8(b.writer).unwrap();
        assert!(text.contains("turn in place 90.0 deg right"), "{text}");
        assert!(text.contains("drive straight forward 25.0 cm"), "{text}");
    }

    #[test]
    fn bad_base_specs_are_named() {
        let e = open_base("tcp:1234").err().unwrap();
        assert!(format!("{e:#}").contains("tcp:1234"));
        let e = open_base("serial:/dev/x@fast").err().unwrap();
        assert!(format!("{e:#}").contains("fast"));
    }
}
