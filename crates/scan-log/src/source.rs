//! Opening logs of any supported format, and the `LaserSource` over a log.

use std::collections::VecDeque;
use std::fs::File;
use std::io::{BufRead, BufReader, Read};
use std::path::{Path, PathBuf};

use scan_types::{LaserSource, Pose2, Scan, ScanGeometry};

use crate::carmen::CARMEN_DEFAULT_MAX_RANGE_M;
use crate::text::{TextFormat, TextLog};
use crate::{LogError, LogRecord, mcap_io};

/// The log formats goalseek reads.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogFormat {
    /// CARMEN text log (`FLASER`, `ROBOTLASER1`), plain or gzip.
    Carmen,
    /// BreezySLAM `.dat` (URG-04LX, millimetres), plain or gzip.
    Breezy,
    /// An MCAP file: a goalseek recording, a ROS 2 bag (`sensor_msgs/msg/LaserScan` in CDR)
    /// or Foxglove `foxglove.LaserScan` (protobuf or JSON); chunks plain, zstd or lz4.
    Mcap,
    /// A rosbag2 bag: a SQLite `.db3` file, or a bag folder (`metadata.yaml` with `.db3` or
    /// `.mcap` files).
    Bag,
}

impl LogFormat {
    /// The format of `path`: a folder is a rosbag2 bag; a file starting with the MCAP or
    /// SQLite magic bytes is MCAP or a rosbag2 `.db3`; else by its name (`.mcap`, `.dat`,
    /// `.log`, `.clf`, also gzipped), else by its first line.
    pub fn detect(path: &Path) -> Result<LogFormat, LogError> {
        if path.is_dir() {
            return Ok(LogFormat::Bag);
        }
        let head = read_head(path)?;
        if head.starts_with(mcap::MAGIC) {
            return Ok(LogFormat::Mcap);
        }
        if &head == crate::bag::SQLITE_MAGIC {
            return Ok(LogFormat::Bag);
        }
        let name = path
            .file_name()
            .map(|n| n.to_string_lossy().to_lowercase())
            .unwrap_or_default();
        let name = name.strip_suffix(".gz").unwrap_or(&name);
        let name = name.strip_suffix(".partial").unwrap_or(name);
        if name.ends_with(".mcap") {
            return Ok(LogFormat::Mcap);
        }
        if name.ends_with(".dat") {
            return Ok(LogFormat::Breezy);
        }
        if name.ends_with(".log") || name.ends_with(".clf") {
            return Ok(LogFormat::Carmen);
        }
        // Sniff: the first word of the first non-comment line.
        let mut head = Vec::new();
        let mut r = open_text(path)?;
        r.by_ref()
            .take(4096)
            .read_to_end(&mut head)
            .map_err(|source| LogError::Io {
                path: path.to_path_buf(),
                source,
            })?;
        let text = String::from_utf8_lossy(&head);
        let first = text
            .lines()
            .map(str::trim)
            .find(|l| !l.is_empty() && !l.starts_with('#'))
            .and_then(|l| l.split_ascii_whitespace().next())
            .unwrap_or("");
        if first.chars().next().is_some_and(|c| c.is_ascii_uppercase()) {
            Ok(LogFormat::Carmen)
        } else if first.parse::<u64>().is_ok() {
            Ok(LogFormat::Breezy)
        } else {
            Err(LogError::UnknownFormat {
                path: path.to_path_buf(),
            })
        }
    }
}

/// How to read a log.
#[derive(Debug, Clone, Default)]
pub struct LogOptions {
    /// The format; `None` detects it (see [`LogFormat::detect`]).
    pub format: Option<LogFormat>,
    /// A geometry (e.g. from a named sensor preset) that overrides the log's own or the default.
    pub geometry: Option<ScanGeometry>,
    /// CARMEN readings at or beyond this are "no return"; `None` is 50 m.
    pub carmen_max_range_m: Option<f64>,
    /// The laser topic to read from a bag or MCAP file holding several (`--topic`).
    pub topic: Option<String>,
}

/// The first 16 bytes of a file (fewer if it is shorter, the rest zero).
pub(crate) fn read_head(path: &Path) -> Result<[u8; 16], LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut head = [0u8; 16];
    let mut file = File::open(path).map_err(io)?;
    let mut n = 0;
    while n < head.len() {
        match file.read(&mut head[n..]).map_err(io)? {
            0 => break,
            k => n += k,
        }
    }
    Ok(head)
}

/// Opens a file for reading text, decompressing gzip (detected by its magic bytes).
pub fn open_text(path: &Path) -> Result<Box<dyn BufRead + Send>, LogError> {
    let io = |source| LogError::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut r = BufReader::with_capacity(1 << 16, File::open(path).map_err(io)?);
    let gz = r.fill_buf().map_err(io)?.starts_with(&[0x1f, 0x8b]);
    if gz {
        Ok(Box::new(BufReader::with_capacity(
            1 << 16,
            flate2::bufread::MultiGzDecoder::new(r),
        )))
    } else {
        Ok(Box::new(r))
    }
}

/// An iterator over the records of a log of any format: one `Result` per scan.
pub struct LogReader {
    path: PathBuf,
    inner: Inner,
}

enum Inner {
    Text(TextLog<Box<dyn BufRead + Send>>),
    Mcap(std::vec::IntoIter<Result<LogRecord, LogError>>),
}

impl LogReader {
    /// Opens `path`.
    pub fn open(path: &Path, options: &LogOptions) -> Result<LogReader, LogError> {
        let format = match options.format {
            Some(f) => f,
            None => LogFormat::detect(path)?,
        };
        let max = options
            .carmen_max_range_m
            .unwrap_or(CARMEN_DEFAULT_MAX_RANGE_M);
        let inner = match format {
            LogFormat::Carmen | LogFormat::Breezy => {
                let tf = if format == LogFormat::Carmen {
                    TextFormat::Carmen
                } else {
                    TextFormat::Breezy
                };
                Inner::Text(TextLog::new(
                    open_text(path)?,
                    path,
                    tf,
                    options.geometry,
                    max,
                ))
            }
            LogFormat::Mcap => {
                Inner::Mcap(mcap_io::read_mcap_topic(path, options.topic.as_deref())?.into_iter())
            }
            LogFormat::Bag => {
                Inner::Mcap(crate::bag::read_bag(path, options.topic.as_deref())?.into_iter())
            }
        };
        Ok(LogReader {
            path: path.to_path_buf(),
            inner,
        })
    }

    /// The file being read.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

impl Iterator for LogReader {
    type Item = Result<LogRecord, LogError>;
    fn next(&mut self) -> Option<Self::Item> {
        match &mut self.inner {
            Inner::Text(t) => t.next(),
            Inner::Mcap(m) => m.next(),
        }
    }
}

/// How many problems a [`LogSource`] keeps for [`LogSource::errors`].
const KEPT_ERRORS: usize = 100;

/// A log as a [`LaserSource`]: scans in order, bad records skipped and counted.
///
/// The geometry comes from the first readable record (or the override in [`LogOptions`]);
/// a later record with another ray count is skipped as an error. After the last scan,
/// `next_scan` returns [`LogError::EndOfLog`].
pub struct LogSource {
    reader: LogReader,
    geometry: ScanGeometry,
    pending: VecDeque<LogRecord>,
    last: Option<LogRecord>,
    scans: usize,
    skipped: usize,
    errors: Vec<LogError>,
}

impl LogSource {
    /// Opens `path` and reads up to its first scan to learn the geometry.
    pub fn open(path: &Path, options: &LogOptions) -> Result<LogSource, LogError> {
        let mut reader = LogReader::open(path, options)?;
        let mut errors = Vec::new();
        let mut skipped = 0;
        let first = loop {
            match reader.next() {
                Some(Ok(r)) => break r,
                Some(Err(e)) => {
                    tracing::warn!("skipping: {e}");
                    skipped += 1;
                    if errors.len() < KEPT_ERRORS {
                        errors.push(e);
                    }
                }
                None => {
                    return Err(LogError::NoScans {
                        path: path.to_path_buf(),
                        skipped,
                    });
                }
            }
        };
        let geometry = options.geometry.unwrap_or(first.geometry);
        Ok(LogSource {
            reader,
            geometry,
            pending: VecDeque::from([first]),
            last: None,
            scans: 0,
            skipped,
            errors,
        })
    }

    /// The next record (scan and poses); bad records are skipped and counted.
    pub fn next_record(&mut self) -> Result<&LogRecord, LogError> {
        loop {
            let next = match self.pending.pop_front() {
                Some(r) => Ok(r),
                None => match self.reader.next() {
                    Some(r) => r,
                    None => {
                        return Err(LogError::EndOfLog {
                            path: self.reader.path().to_path_buf(),
                            scans: self.scans,
                        });
                    }
                },
            };
            let err = match next {
                Ok(r) if r.scan.len() == self.geometry.ray_count => {
                    self.scans += 1;
                    return Ok(self.last.insert(r));
                }
                Ok(r) => LogError::RayCountMismatch {
                    path: self.reader.path().to_path_buf(),
                    line: r.line,
                    got: r.scan.len(),
                    expected: self.geometry.ray_count,
                },
                Err(e) => e,
            };
            tracing::warn!("skipping: {err}");
            self.skipped += 1;
            if self.errors.len() < KEPT_ERRORS {
                self.errors.push(err);
            }
        }
    }

    /// The log's pose of the last scan delivered (CARMEN corrected pose, estimated pose of a
    /// recording), if it has one.
    pub fn pose(&self) -> Option<Pose2> {
        self.last.as_ref().and_then(|r| r.pose)
    }

    /// The true pose of the last scan (simulator recordings).
    pub fn true_pose(&self) -> Option<Pose2> {
        self.last.as_ref().and_then(|r| r.true_pose)
    }

    /// The last record delivered.
    pub fn last_record(&self) -> Option<&LogRecord> {
        self.last.as_ref()
    }

    /// Scans delivered so far.
    pub fn scans_read(&self) -> usize {
        self.scans
    }

    /// Records skipped so far because they were malformed.
    pub fn skipped(&self) -> usize {
        self.skipped
    }

    /// The first problems met (up to 100), each naming file and line.
    pub fn errors(&self) -> &[LogError] {
        &self.errors
    }

    /// The rest of the log's scans that have a pose (the true one when `use_true`, else the
    /// estimated one or failing that the true one), and the count of every scan read.
    pub fn posed_scans(&mut self, use_true: bool) -> Result<(Vec<(Pose2, Scan)>, usize), LogError> {
        let mut scans = Vec::new();
        let mut total = 0usize;
        loop {
            let rec = match self.next_record() {
                Ok(r) => r,
                Err(e) if e.is_end_of_log() => break,
                Err(e) => return Err(e),
            };
            total += 1;
            let pose = if use_true {
                rec.true_pose
            } else {
                rec.pose.or(rec.true_pose)
            };
            if let Some(p) = pose {
                scans.push((p, rec.scan.clone()));
            }
        }
        Ok((scans, total))
    }
}

impl LaserSource for LogSource {
    type Error = LogError;

    fn geometry(&self) -> &ScanGeometry {
        &self.geometry
    }

    fn next_scan(&mut self) -> Result<Scan, LogError> {
        self.next_record().map(|r| r.scan.clone())
    }
}
