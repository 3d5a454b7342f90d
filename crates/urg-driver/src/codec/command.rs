//! The commands a host sends and the scan requests they carry.

/// The data a scan command asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DataKind {
    /// Ranges, 3-character encoding (`GD`/`MD`).
    Range3,
    /// Ranges, 2-character encoding (`GS`/`MS`), saturating at 4095 mm.
    Range2,
    /// Range and intensity pairs, 3+3 characters (`GE`/`ME`).
    RangeIntensity,
}

impl DataKind {
    /// Characters per measurement step.
    pub fn chars_per_step(self) -> usize {
        match self {
            DataKind::Range3 => 3,
            DataKind::Range2 => 2,
            DataKind::RangeIntensity => 6,
        }
    }

    /// The two-letter single-scan (`G?`) command name.
    pub fn get_name(self) -> &'static str {
        match self {
            DataKind::Range3 => "GD",
            DataKind::Range2 => "GS",
            DataKind::RangeIntensity => "GE",
        }
    }

    /// The two-letter streaming (`M?`) command name.
    pub fn stream_name(self) -> &'static str {
        match self {
            DataKind::Range3 => "MD",
            DataKind::Range2 => "MS",
            DataKind::RangeIntensity => "ME",
        }
    }

    pub(super) fn from_letter(c: u8) -> Option<DataKind> {
        match c {
            b'D' => Some(DataKind::Range3),
            b'S' => Some(DataKind::Range2),
            b'E' => Some(DataKind::RangeIntensity),
            _ => None,
        }
    }
}

/// Which steps a scan command asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct ScanRequest {
    /// Encoding of the reply.
    pub kind: DataKind,
    /// First step (0..=9999).
    pub start_step: u16,
    /// Last step, inclusive (0..=9999).
    pub end_step: u16,
    /// Steps merged into one value (0 and 1 both mean one).
    pub cluster: u8,
}

impl ScanRequest {
    /// Number of values one reply carries.
    pub fn value_count(&self) -> usize {
        if self.end_step < self.start_step {
            return 0;
        }
        let steps = usize::from(self.end_step - self.start_step) + 1;
        steps.div_ceil(usize::from(self.cluster.max(1)))
    }
}

/// A streaming request: steps, scans skipped between sends, and how many scans (0 = until `QT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct StreamRequest {
    /// Which steps and encoding.
    pub scan: ScanRequest,
    /// Scans skipped after each sent scan (0..=9).
    pub skip: u8,
    /// Number of scans (1..=99), or 0 to stream until `QT`.
    pub count: u8,
}

/// The `TM` control code.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TimeCode {
    /// `TM0`: enter time-adjust mode (laser off).
    Enter,
    /// `TM1`: read the sensor's 24-bit millisecond timer.
    Read,
    /// `TM2`: leave time-adjust mode.
    Leave,
}

/// A host-to-sensor command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Command {
    /// `SCIP2.0`: switch a SCIP 1.1 sensor to SCIP 2.0.
    Scip2,
    /// `VV`: version information.
    Version,
    /// `PP`: sensor parameters.
    Parameters,
    /// `II`: sensor state.
    State,
    /// `BM`: laser on.
    LaserOn,
    /// `QT`: laser off, stops streaming.
    LaserOff,
    /// `RS`: reset laser, motor speed, bit rate and timer.
    Reset,
    /// `TM0`/`TM1`/`TM2`: time adjustment.
    Time(TimeCode),
    /// `SS`: bit rate in bit/s (6 digits).
    BitRate(u32),
    /// `CR`: motor speed code (00 default, 01..=10 levels, 99 reset).
    MotorSpeed(u8),
    /// `HS`: high-sensitivity mode on or off.
    HighSensitivity(bool),
    /// `GD`/`GS`/`GE`: one scan.
    Get(ScanRequest),
    /// `MD`/`MS`/`ME`: streamed scans.
    Stream(StreamRequest),
}

impl Command {
    /// The command's name as it appears on the wire (`VV`, `TM`, `GD`, `SCIP2.0`, ...).
    pub fn name(&self) -> &'static str {
        match self {
            Command::Scip2 => "SCIP2.0",
            Command::Version => "VV",
            Command::Parameters => "PP",
            Command::State => "II",
            Command::LaserOn => "BM",
            Command::LaserOff => "QT",
            Command::Reset => "RS",
            Command::Time(_) => "TM",
            Command::BitRate(_) => "SS",
            Command::MotorSpeed(_) => "CR",
            Command::HighSensitivity(_) => "HS",
            Command::Get(r) => r.kind.get_name(),
            Command::Stream(r) => r.scan.kind.stream_name(),
        }
    }
}
