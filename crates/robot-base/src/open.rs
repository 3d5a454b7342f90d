//! A base named by a spec: `stdio`, `serial:PATH[@BAUD]` or `manual`.

use std::io::BufReader;

use scan_types::MotionBase;

use crate::{BaseError, LineBase, ManualBase};

/// A base opened from a spec, behind one type whatever its link.
pub type DynBase = Box<dyn MotionBase<Error = BaseError> + Send>;

/// Baud rate of a `serial:PATH` spec without `@BAUD`.
pub const DEFAULT_BAUD: u32 = 115_200;

/// A parsed base spec.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum BaseSpec {
    /// The line protocol on standard input (answers) and standard output (commands).
    Stdio,
    /// The line protocol on a serial port.
    Serial {
        /// The port's path.
        path: String,
        /// Its baud rate.
        baud: u32,
    },
    /// Prompts on standard error, confirmations on standard input.
    Manual,
}

impl BaseSpec {
    /// Parses `stdio`, `serial:PATH[@BAUD]` (default [`DEFAULT_BAUD`]) or `manual`.
    pub fn parse(spec: &str) -> Result<Self, BaseError> {
        match spec {
            "stdio" => return Ok(Self::Stdio),
            "manual" => return Ok(Self::Manual),
            _ => {}
        }
        let Some(rest) = spec.strip_prefix("serial:") else {
            return Err(BaseError::UnknownSpec { spec: spec.into() });
        };
        let (path, baud) = match rest.rsplit_once('@') {
            Some((p, b)) => {
                let baud = b.parse::<u32>().map_err(|source| BaseError::BadBaud {
                    spec: spec.into(),
                    baud: b.into(),
                    source,
                })?;
                (p, baud)
            }
            None => (rest, DEFAULT_BAUD),
        };
        if path.is_empty() {
            return Err(BaseError::NoSerialPath { spec: spec.into() });
        }
        Ok(Self::Serial {
            path: path.into(),
            baud,
        })
    }

    /// Opens the base (a serial port with a 5 s read timeout, re-armed while a move lasts);
    /// with `cancel`, waiting for a move's answer is given up once it returns true.
    pub fn open(&self, cancel: Option<fn() -> bool>) -> Result<DynBase, BaseError> {
        fn line<W: std::io::Write>(b: LineBase<W>, cancel: Option<fn() -> bool>) -> LineBase<W> {
            match cancel {
                Some(c) => b.with_cancel(c),
                None => b,
            }
        }
        match self {
            Self::Stdio => Ok(Box::new(line(
                LineBase::new(BufReader::new(std::io::stdin()), std::io::stdout()),
                cancel,
            ))),
            Self::Manual => {
                let b = ManualBase::new(BufReader::new(std::io::stdin()), std::io::stderr());
                Ok(Box::new(match cancel {
                    Some(c) => b.with_cancel(c),
                    None => b,
                }))
            }
            Self::Serial { path, baud } => {
                let serial = |action| {
                    move |source| BaseError::Serial {
                        action,
                        path: path.clone(),
                        source,
                    }
                };
                let port = serialport::new(path, *baud)
                    .timeout(std::time::Duration::from_secs(5))
                    .open()
                    .map_err(serial("open"))?;
                let reader = port.try_clone().map_err(serial("share"))?;
                Ok(Box::new(line(
                    LineBase::new(BufReader::new(reader), port),
                    cancel,
                )))
            }
        }
    }
}

/// Opens the base named by `spec` (see [`BaseSpec::parse`] and [`BaseSpec::open`]).
pub fn open_base(spec: &str, cancel: Option<fn() -> bool>) -> Result<DynBase, BaseError> {
    BaseSpec::parse(spec)?.open(cancel)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn specs_parse() {
        assert_eq!(BaseSpec::parse("stdio").unwrap(), BaseSpec::Stdio);
        assert_eq!(BaseSpec::parse("manual").unwrap(), BaseSpec::Manual);
        assert_eq!(
            BaseSpec::parse("serial:/dev/ttyUSB0").unwrap(),
            BaseSpec::Serial {
                path: "/dev/ttyUSB0".into(),
                baud: DEFAULT_BAUD
            }
        );
        // The baud rate follows the last '@'.
        assert_eq!(
            BaseSpec::parse("serial:/dev/a@b@9600").unwrap(),
            BaseSpec::Serial {
                path: "/dev/a@b".into(),
                baud: 9600
            }
        );
    }

    #[test]
    fn bad_base_specs_are_named() {
        let e = open_base("tcp:1234", None).err().unwrap();
        assert!(e.is_spec_error());
        assert_eq!(
            e.to_string(),
            "'tcp:1234': expected stdio, serial:PATH[@BAUD] or manual"
        );
        let e = open_base("serial:/dev/x@fast", None).err().unwrap();
        assert!(e.is_spec_error() && e.to_string().contains("'fast'"), "{e}");
        let e = open_base("serial:@9600", None).err().unwrap();
        assert!(matches!(e, BaseError::NoSerialPath { .. }), "{e}");
        let e = open_base("serial:/no/such/port", None).err().unwrap();
        assert!(!e.is_spec_error());
        assert!(e.to_string().contains("/no/such/port"), "{e}");
    }
}
