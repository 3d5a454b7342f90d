//! Adaptors over any [`MotionBase`]: one that records every command, one that executes none,
//! one that sends `stop` when dropped unless the last command was one.

use scan_types::MotionBase;

/// A motion command the loop gave.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Rotate in place, radians.
    Rotate(f64),
    /// Drive straight, metres.
    Forward(f64),
    /// Stop.
    Stop,
}

/// A motion base that records every command and passes it on to `inner`.
pub struct LoggingBase<M> {
    /// The base that executes the commands.
    pub inner: M,
    /// Every command, in order.
    pub commands: Vec<Command>,
}

impl<M: MotionBase> LoggingBase<M> {
    /// Wraps `inner`.
    pub fn new(inner: M) -> Self {
        Self {
            inner,
            commands: Vec::new(),
        }
    }
}

impl<M: MotionBase> MotionBase for LoggingBase<M> {
    type Error = M::Error;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), Self::Error> {
        self.commands.push(Command::Rotate(angle_rad));
        self.inner.rotate(angle_rad)
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), Self::Error> {
        self.commands.push(Command::Forward(distance_m));
        self.inner.forward(distance_m)
    }
    fn stop(&mut self) -> Result<(), Self::Error> {
        self.commands.push(Command::Stop);
        self.inner.stop()
    }
}

/// A motion base that sends `stop` when dropped unless `stop` was the last command it passed
/// on: an early error or a panic still stops the robot.
pub struct StopOnDrop<M: MotionBase> {
    inner: M,
    stopped: bool,
}

impl<M: MotionBase> StopOnDrop<M> {
    /// Wraps `inner`, not yet stopped.
    pub fn new(inner: M) -> Self {
        Self {
            inner,
            stopped: false,
        }
    }
}

impl<M: MotionBase> MotionBase for StopOnDrop<M> {
    type Error = M::Error;
    fn rotate(&mut self, angle_rad: f64) -> Result<(), Self::Error> {
        self.stopped = false;
        self.inner.rotate(angle_rad)
    }
    fn forward(&mut self, distance_m: f64) -> Result<(), Self::Error> {
        self.stopped = false;
        self.inner.forward(distance_m)
    }
    fn stop(&mut self) -> Result<(), Self::Error> {
        self.stopped = true;
        self.inner.stop()
    }
}

impl<M: MotionBase> Drop for StopOnDrop<M> {
    fn drop(&mut self) {
        if !self.stopped
            && let Err(e) = self.inner.stop()
        {
            tracing::warn!("the base did not take stop: {e}");
        }
    }
}

/// A motion base that does nothing (a replay: the recorded scans already moved).
#[derive(Debug, Default, Clone, Copy)]
pub struct NoMotion;

impl MotionBase for NoMotion {
    type Error = std::convert::Infallible;
    fn rotate(&mut self, _angle_rad: f64) -> Result<(), Self::Error> {
        Ok(())
    }
    fn forward(&mut self, _distance_m: f64) -> Result<(), Self::Error> {
        Ok(())
    }
    fn stop(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stop_on_drop_stops_once_however_it_ends() {
        let mut log = LoggingBase::new(NoMotion);
        {
            let mut b = StopOnDrop::new(&mut log);
            b.forward(1.0).unwrap();
        }
        assert_eq!(log.commands, [Command::Forward(1.0), Command::Stop]);
        let mut log = LoggingBase::new(NoMotion);
        {
            let mut b = StopOnDrop::new(&mut log);
            b.rotate(0.5).unwrap();
            b.stop().unwrap();
        }
        assert_eq!(log.commands, [Command::Rotate(0.5), Command::Stop]);
        // Never moved: still told to stop.
        let mut log = LoggingBase::new(NoMotion);
        drop(StopOnDrop::new(&mut log));
        assert_eq!(log.commands, [Command::Stop]);
    }

    #[test]
    fn logging_base_records_in_order() {
        let mut b = LoggingBase::new(NoMotion);
        b.rotate(0.5).unwrap();
        b.forward(-1.0).unwrap();
        b.stop().unwrap();
        assert_eq!(
            b.commands,
            [Command::Rotate(0.5), Command::Forward(-1.0), Command::Stop]
        );
    }
}
