//! The crate's error type.

use crate::codec::Status;

/// Everything that can go wrong while talking SCIP 2.0.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum UrgError {
    /// A line's checksum character does not match the sum of its bytes.
    #[error(
        "checksum error on reply line {line} (byte offset {offset}): expected {expected:?}, found {found:?}"
    )]
    Checksum {
        /// Line number inside the reply, 1-based (the echo is line 1).
        line: usize,
        /// Byte offset of the line inside the reply.
        offset: usize,
        /// The checksum character computed from the line.
        expected: char,
        /// The checksum character received.
        found: char,
    },
    /// A data character lies outside the 0x30..=0x6F encoding alphabet.
    #[error("byte 0x{byte:02x} at offset {offset} is not a SCIP data character")]
    BadChar {
        /// The offending byte.
        byte: u8,
        /// Its offset inside the reply (or inside the encoded value).
        offset: usize,
    },
    /// The reply is not laid out as SCIP 2.0 says.
    #[error("malformed reply at byte offset {offset}: {what}")]
    Framing {
        /// What was wrong.
        what: String,
        /// Byte offset inside the reply.
        offset: usize,
    },
    /// A value does not fit its encoding or a parameter is out of range.
    #[error("invalid value: {0}")]
    InvalidValue(String),
    /// A PP/VV/II key is missing or unreadable.
    #[error("sensor information line {key}: {why}")]
    Info {
        /// The key (`DMIN`, `AFRT`, ...).
        key: String,
        /// What was wrong.
        why: String,
    },
    /// The sensor refused a command with a non-OK status.
    #[error("{command} refused by the sensor: status {status} ({meaning})")]
    Status {
        /// The command that was refused (its two-letter name).
        command: String,
        /// The status the sensor sent.
        status: Status,
        /// What the status means for that command.
        meaning: &'static str,
    },
    /// The sensor reported a hardware fault (status 50..=97).
    #[error("{command}: sensor hardware fault, status {status} ({meaning})")]
    HardwareFault {
        /// The command being answered.
        command: String,
        /// The status the sensor sent.
        status: Status,
        /// What the status means.
        meaning: &'static str,
    },
    /// The model does not have this command (it answered `0E`); the device keeps working.
    #[error("{command} is not supported by this sensor (status 0E)")]
    Unsupported {
        /// The command.
        command: String,
    },
    /// No complete reply arrived within the timeout.
    #[error("no reply to {command} within {waited_ms} ms")]
    Timeout {
        /// What the driver was waiting for.
        command: String,
        /// How long it waited, milliseconds.
        waited_ms: u64,
    },
    /// The device went away (USB unplugged, pseudo-terminal closed, end of stream).
    #[error("sensor disconnected: {0}")]
    Disconnected(String),
    /// A `--port` value that names no usable place (e.g. `tcp:` without a port number).
    #[error("bad port {port:?}: {why}")]
    BadPort {
        /// The value given.
        port: String,
        /// What is wrong with it.
        why: String,
    },
    /// Nothing answers at a TCP address (refused, unreachable, unknown host or timed out).
    #[error(
        "cannot connect to the sensor at tcp:{addr} ({why}); is it powered and on this network? An Ethernet Hokuyo answers at 192.168.0.10:10940 unless reconfigured"
    )]
    NoSuchAddress {
        /// The address given, `HOST:PORT`.
        addr: String,
        /// What the system said.
        why: String,
    },
    /// The serial device does not exist (wrong path, or the sensor is not plugged in).
    #[error(
        "no serial device at {path} ({why}); is the sensor plugged in? A USB Hokuyo appears as /dev/ttyACM0 or similar"
    )]
    NoSuchPort {
        /// The path given.
        path: String,
        /// What the system said.
        why: String,
    },
    /// The reply grew beyond the receive buffer without an end.
    #[error("reply longer than {0} bytes without an end; buffer discarded")]
    Overflow(usize),
    /// The sensor's parameters changed across a reconnect.
    #[error("sensor parameters changed after reconnecting: {0}")]
    ParametersChanged(String),
    /// Any other I/O error from the transport.
    #[error("I/O error: {0}")]
    Io(#[from] std::io::Error),
}

impl UrgError {
    /// The error for a refused command: `0E` is "unsupported", 50..=97 a hardware fault.
    pub fn from_status(command: &str, status: Status) -> UrgError {
        let meaning = status.meaning(command);
        if status == Status::UNDEFINED {
            UrgError::Unsupported {
                command: command.to_string(),
            }
        } else if status.is_hardware_fault() {
            UrgError::HardwareFault {
                command: command.to_string(),
                status,
                meaning,
            }
        } else {
            UrgError::Status {
                command: command.to_string(),
                status,
                meaning,
            }
        }
    }

    /// True for errors that concern one reply only (checksum, characters, framing): the
    /// stream can go on with the next reply.
    pub fn is_reply_error(&self) -> bool {
        matches!(
            self,
            UrgError::Checksum { .. } | UrgError::BadChar { .. } | UrgError::Framing { .. }
        )
    }
}
