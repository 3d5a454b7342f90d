//! A base moved by a person, prompted move by move.

use std::io::{BufRead, Write};

use scan_types::MotionBase;

use crate::BaseError;
use crate::answers::Answers;

/// A base moved by a person: each move is printed, and Enter confirms it was made
/// (`q` then Enter stops the run).
pub struct ManualBase<W> {
    answers: Answers,
    writer: W,
    moves: usize,
    cancel: Option<fn() -> bool>,
}

impl<W: Write> ManualBase<W> {
    /// A manual base prompting on `writer` and reading confirmations from `reader` (on a
    /// thread of its own).
    pub fn new<R: BufRead + Send + 'static>(reader: R, writer: W) -> Self {
        Self {
            answers: Answers::new(reader),
            writer,
            moves: 0,
            cancel: None,
        }
    }

    /// Gives up waiting for a confirmation once `cancel` returns true (checked every 50 ms).
    pub fn with_cancel(mut self, cancel: fn() -> bool) -> Self {
        self.cancel = Some(cancel);
        self
    }

    fn ask(&mut self, what: &str) -> Result<(), BaseError> {
        self.moves += 1;
        write!(
            self.writer,
            "move {}: {what}; press Enter when done (q to stop) ",
            self.moves
        )?;
        self.writer.flush()?;
        let Some(line) = self.answers.next(what, self.cancel)? else {
            return Err(BaseError::Closed {
                command: what.to_string(),
            });
        };
        if line.trim().eq_ignore_ascii_case("q") {
            return Err(BaseError::Aborted);
        }
        Ok(())
    }
}

impl<W: Write> MotionBase for ManualBase<W> {
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

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Cursor;

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
}
