//! The crate's error type.

/// What can go wrong naming, opening or talking to a base.
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
    /// Waiting for the answer was given up (Ctrl-C or SIGTERM during a move).
    #[error("stopped waiting for the answer to '{command}'")]
    Cancelled {
        /// The command sent.
        command: String,
    },
    /// The operator stopped a manual run.
    #[error("stopped by the operator")]
    Aborted,
    /// A base spec that is none of `stdio`, `serial:PATH[@BAUD]`, `manual`.
    #[error("'{spec}': expected stdio, serial:PATH[@BAUD] or manual")]
    UnknownSpec {
        /// The spec given.
        spec: String,
    },
    /// A `serial:PATH@BAUD` spec whose baud rate is not a number.
    #[error("{spec}: baud rate '{baud}' is not a number")]
    BadBaud {
        /// The spec given.
        spec: String,
        /// The text after `@`.
        baud: String,
        /// Why it does not parse.
        source: std::num::ParseIntError,
    },
    /// A `serial:` spec without a path.
    #[error("{spec}: no serial port path after 'serial:'")]
    NoSerialPath {
        /// The spec given.
        spec: String,
    },
    /// The base's serial port could not be opened or shared between reader and writer.
    #[error("cannot {action} base serial port {path}")]
    Serial {
        /// `open` or `share`.
        action: &'static str,
        /// The port's path.
        path: String,
        /// The serial port's error.
        source: serialport::Error,
    },
}

impl BaseError {
    /// True for the errors of a spec that names no base (not of a link or a move).
    pub fn is_spec_error(&self) -> bool {
        matches!(
            self,
            Self::UnknownSpec { .. } | Self::BadBaud { .. } | Self::NoSerialPath { .. }
        )
    }
}
