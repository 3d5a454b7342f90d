//! Line-oriented logs (CARMEN, BreezySLAM), plain or gzip-compressed.

use std::io::BufRead;
use std::path::{Path, PathBuf};

use scan_types::ScanGeometry;

use crate::{LogError, LogRecord, breezy, carmen};

/// Which text format a [`TextLog`] parses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TextFormat {
    /// CARMEN `FLASER` / `ROBOTLASER1` lines (other lines are skipped).
    Carmen,
    /// BreezySLAM `.dat`: one URG-04LX scan a line.
    Breezy,
}

/// An iterator over the scans of a text log: one `Result` per scan line, so a bad line
/// gives an error naming the file and line and the lines after it still read.
pub struct TextLog<R> {
    reader: R,
    path: PathBuf,
    format: TextFormat,
    geometry: Option<ScanGeometry>,
    max_range_m: f64,
    line_no: usize,
    offset: u64,
    buf: Vec<u8>,
    failed_io: bool,
}

impl<R: BufRead> TextLog<R> {
    /// Reads `format` from `reader`; `path` names the source in errors. A `geometry` overrides
    /// the one from the log (CARMEN) or the BreezySLAM default; `max_range_m` is the CARMEN
    /// no-return threshold.
    pub fn new(
        reader: R,
        path: &Path,
        format: TextFormat,
        geometry: Option<ScanGeometry>,
        max_range_m: f64,
    ) -> Self {
        let geometry = match format {
            TextFormat::Breezy => Some(geometry.unwrap_or_else(breezy::breezy_geometry)),
            TextFormat::Carmen => geometry,
        };
        Self {
            reader,
            path: path.to_path_buf(),
            format,
            geometry,
            max_range_m,
            line_no: 0,
            offset: 0,
            buf: Vec::with_capacity(8192),
            failed_io: false,
        }
    }
}

impl<R: BufRead> Iterator for TextLog<R> {
    type Item = Result<LogRecord, LogError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.failed_io {
            return None;
        }
        loop {
            self.buf.clear();
            let start = self.offset;
            let n = match self.reader.read_until(b'\n', &mut self.buf) {
                Ok(0) => return None,
                Ok(n) => n,
                Err(e) => {
                    // A broken stream (e.g. a gzip file cut short) ends the log.
                    self.failed_io = true;
                    return Some(Err(LogError::Parse {
                        path: self.path.clone(),
                        line: self.line_no + 1,
                        byte_offset: start,
                        message: format!("read failed: {e}"),
                    }));
                }
            };
            self.offset += n as u64;
            self.line_no += 1;
            let err = |message: String| LogError::Parse {
                path: self.path.clone(),
                line: self.line_no,
                byte_offset: start,
                message,
            };
            let text = match std::str::from_utf8(&self.buf) {
                Ok(t) => t,
                Err(e) => return Some(Err(err(format!("not UTF-8 text: {e}")))),
            };
            let parsed = match self.format {
                TextFormat::Carmen => {
                    carmen::parse_line(text, self.line_no, self.geometry.as_ref(), self.max_range_m)
                }
                TextFormat::Breezy => breezy::parse_line(
                    text,
                    self.line_no,
                    self.geometry.as_ref().expect("set in new"),
                ),
            };
            match parsed {
                Ok(Some(rec)) => return Some(Ok(rec)),
                Ok(None) => continue,
                Err(m) => return Some(Err(err(m))),
            }
        }
    }
}
