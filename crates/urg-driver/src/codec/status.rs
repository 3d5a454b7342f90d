//! Reply status codes: the two-character SCIP 2.0 status, its meaning, and the status line.

use std::fmt;

use super::{LF, checksum};

/// A two-character SCIP 2.0 status, kept as characters (never parsed as a number).
#[derive(Clone, Copy, PartialEq, Eq, Hash)]
pub struct Status(pub [u8; 2]);

impl Status {
    /// `00`: command accepted.
    pub const OK: Status = Status(*b"00");
    /// `99`: scan data follows (MD/MS/ME scan replies).
    pub const SCAN_DATA: Status = Status(*b"99");
    /// `0E`: undefined command (the model does not have it).
    pub const UNDEFINED: Status = Status(*b"0E");

    /// The two status characters as text.
    pub fn as_str(&self) -> &str {
        std::str::from_utf8(&self.0).unwrap_or("??")
    }

    /// The numeric value when both characters are decimal digits.
    pub fn decimal(&self) -> Option<u8> {
        let [a, b] = self.0;
        (a.is_ascii_digit() && b.is_ascii_digit()).then(|| (a - b'0') * 10 + (b - b'0'))
    }

    /// True for a hardware-fault status (50..=97 for scan commands).
    pub fn is_hardware_fault(&self) -> bool {
        matches!(self.decimal(), Some(50..=97))
    }

    /// What this status means in answer to `command` (its two-letter name).
    pub fn meaning(&self, command: &str) -> &'static str {
        let scan_cmd = matches!(
            command,
            "GD" | "GS" | "GE" | "MD" | "MS" | "ME" | "HD" | "ND" | "HE" | "NE"
        );
        match &self.0 {
            b"00" => "OK",
            b"99" => "OK, scan data follows",
            b"0A" => "cannot create the reply internally",
            b"0B" => "buffer shortage, or a command repeated while still being processed",
            b"0C" => "insufficient parameters",
            b"0D" => "undefined command (1)",
            b"0E" => "undefined command: not supported by this model",
            b"0F" => "insufficient parameters (2)",
            b"0G" => "string longer than 16 characters",
            b"0H" => "invalid characters in the string",
            b"0I" => "sensor in firmware-update mode",
            b"0L" => "abnormal state: only a reboot recovers",
            b"0M" => "unstable state",
            _ => match (command, self.decimal()) {
                (_, Some(1)) if scan_cmd => "starting step has a non-numeric value",
                (_, Some(2)) if scan_cmd => "end step has a non-numeric value",
                (_, Some(3)) if scan_cmd => "cluster count has a non-numeric value",
                (_, Some(4)) if scan_cmd => "end step out of range",
                (_, Some(5)) if scan_cmd => "end step smaller than starting step",
                (_, Some(6)) if scan_cmd => "scan interval has a non-numeric value",
                (_, Some(7)) if scan_cmd => "number of scans has a non-numeric value",
                (_, Some(10)) if scan_cmd => "laser is off",
                (_, Some(21..=49)) if scan_cmd => "measurement stopped to verify an error",
                (_, Some(50..=97)) => "hardware fault",
                (_, Some(98)) if scan_cmd => "resumed after a hardware fault",
                ("BM", Some(1)) => "unable to switch the laser on: laser malfunction",
                ("BM", Some(2)) => "laser already on",
                ("TM", Some(1)) => "invalid control code",
                ("TM", Some(2)) => "already in time-adjust mode",
                ("TM", Some(3)) => "already out of time-adjust mode",
                ("TM", Some(4)) => "time requested while not in time-adjust mode",
                ("SS", Some(1)) => "bit rate has non-numeric characters",
                ("SS", Some(2)) => "invalid bit rate",
                ("SS", Some(3)) => "already at this bit rate",
                ("SS", Some(4)) => "not compatible with this sensor",
                ("CR", Some(1)) => "invalid speed parameter",
                ("CR", Some(2)) => "speed out of range",
                ("CR", Some(3)) => "already at this speed",
                ("CR", Some(4)) => "not compatible with this sensor",
                ("HS", Some(1)) => "invalid parameter",
                ("HS", Some(2)) => "already in this mode",
                ("HS", Some(3)) => "not compatible with this sensor",
                _ => "unknown status",
            },
        }
    }
}

impl fmt::Display for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", String::from_utf8_lossy(&self.0))
    }
}

impl fmt::Debug for Status {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Status({self})")
    }
}

/// The status line of a reply: SCIP 2.0 (two characters and a checksum) or SCIP 1.1 (one character).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StatusLine {
    /// A SCIP 2.0 status.
    Scip2(Status),
    /// A SCIP 1.1 one-character status (`0` is OK): the sensor is not in SCIP 2.0 mode.
    Scip1(u8),
}

/// Appends a status line (two characters, checksum, LF).
pub fn encode_status_line(status: Status, out: &mut Vec<u8>) {
    out.extend_from_slice(&status.0);
    out.push(checksum(&status.0));
    out.push(LF);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn status_is_never_read_as_a_number() {
        let s = Status(*b"0E");
        assert_eq!(s.decimal(), None);
        assert_ne!(s, Status::OK);
        assert!(Status(*b"55").is_hardware_fault());
        assert!(!Status(*b"0F").is_hardware_fault());
        assert_eq!(Status(*b"02").meaning("BM"), "laser already on");
    }
}
