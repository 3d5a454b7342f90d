//! The pure SCIP 2.0 codec: checksums, character encodings, commands, reply framing,
//! information lines and scan data. No I/O happens here.
//!
//! ```
//! use urg_driver::codec::{checksum, decode_value, encode_value};
//! assert_eq!(checksum(b"Hokuyo"), b'o');
//! assert_eq!(decode_value(b"CB").unwrap(), 1234);
//! assert_eq!(decode_value(b"1Dh").unwrap(), 5432);
//! assert_eq!(decode_value(b"m2@0").unwrap(), 16_000_000);
//! let mut out = Vec::new();
//! encode_value(5432, 3, &mut out).unwrap();
//! assert_eq!(out, b"1Dh");
//! ```

mod command;
mod encode_command;
mod encoding;
mod info_line;
mod parse_command;
mod reply;
mod scan;
mod status;

pub use command::{Command, DataKind, ScanRequest, StreamRequest, TimeCode};
pub use encode_command::is_valid_tag;
pub use encoding::{checksum, decode_value, encode_value, is_data_char};
pub use info_line::{encode_info_line, info_lines, parse_info_line};
pub use reply::{Reply, find_reply_end, find_reply_end_from, parse_reply};
pub use scan::{RawScan, decode_scan_body, decode_scan_reply, encode_scan_body};
pub use status::{Status, StatusLine, encode_status_line};

/// Line feed, the SCIP line terminator.
pub const LF: u8 = b'\n';

/// Payload characters per data line before the line's checksum.
pub const DATA_LINE_CHARS: usize = 64;

/// Longest tag string the sensor accepts after `;`.
pub const MAX_TAG_LEN: usize = 16;
