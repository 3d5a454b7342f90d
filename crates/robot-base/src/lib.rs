//! Robot bases: the drivers that make a robot's moves, behind [`scan_types::MotionBase`].
//!
//! - [`LineBase`]: the one-line-per-command base protocol (`rotate RAD`, `forward M`, `stop`;
//!   answers `done` or `error <text>`) over any reader/writer pair, standard input and output
//!   or a serial port; see `docs/base-protocol.md`.
//! - [`ManualBase`]: a person makes each move and confirms it with Enter.
//! - [`open_base`]: the base named by a spec, `stdio`, `serial:PATH[@BAUD]` or `manual`.
//! - [`LoggingBase`], [`NoMotion`]: adaptors that record every command, or execute none.
//!
//! ```
//! use scan_types::MotionBase;
//! let answers = std::io::Cursor::new(b"done\n# turning\ndone\n".to_vec());
//! let mut base = robot_base::LineBase::new(answers, Vec::new());
//! base.rotate(0.5).unwrap();
//! base.stop().unwrap();
//! let sent = base.into_writer();
//! assert_eq!(sent, b"rotate 0.500000\nstop\n");
//! ```

mod adaptors;
mod answers;
mod error;
mod line;
mod manual;
mod open;

pub use adaptors::{Command, LoggingBase, NoMotion, StopOnDrop};
pub use answers::MAX_LINE_BYTES;
pub use error::BaseError;
pub use line::{LineBase, forward_line, rotate_line};
pub use manual::ManualBase;
pub use open::{BaseSpec, DEFAULT_BAUD, DynBase, open_base};
