//! A base moved by a person, prompted move by move.

use std::io::{BufRead, Write};

use scan_types::MotionBase;

use crate::BaseError;

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
