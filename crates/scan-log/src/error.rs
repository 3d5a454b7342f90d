//! The crate's error type.

use std::path::PathBuf;

/// What can go wrong while reading or writing a log.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum LogError {
    /// Reading or writing the file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// A line of a text log is truncated or malformed.
    #[error("{}:{line} (byte {byte_offset}): {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// Line number, 1-based.
        line: usize,
        /// Byte offset of the line's start in the (decompressed) text.
        byte_offset: u64,
        /// What is wrong.
        message: String,
    },
    /// The MCAP container is damaged or cannot be written.
    #[error("{}: MCAP: {source}", path.display())]
    Mcap {
        /// The file.
        path: PathBuf,
        /// The MCAP error.
        #[source]
        source: mcap::McapError,
    },
    /// One message of an MCAP recording does not decode.
    #[error("{}: message {index} on {topic}: {message}", path.display())]
    Message {
        /// The file.
        path: PathBuf,
        /// Index of the message in the file, 0-based.
        index: usize,
        /// Its topic.
        topic: String,
        /// What is wrong.
        message: String,
    },
    /// The file's format cannot be told from its name or its first bytes.
    #[error("{}: unknown log format (goalseek reads CARMEN .log/.clf, BreezySLAM .dat, MCAP files and rosbag2 bags: {})", path.display(), crate::topics::SUPPORTED_TOPICS)]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
    /// A bag or MCAP file holds nothing goalseek reads as laser scans.
    #[error("{}: {found}; goalseek reads {}", path.display(), crate::topics::SUPPORTED_TOPICS)]
    Unsupported {
        /// The file (or bag folder).
        path: PathBuf,
        /// What it holds instead.
        found: String,
    },
    /// A file holds several laser topics and none was chosen.
    #[error("{}: several laser scan topics ({}); choose one with --topic", path.display(), topics.join(", "))]
    SeveralTopics {
        /// The file (or bag folder).
        path: PathBuf,
        /// Its laser topics.
        topics: Vec<String>,
    },
    /// The topic asked for is not a laser topic of the file.
    #[error("{}: no laser scan topic {topic} (laser topics: {}; other topics: {})", path.display(), list(laser_topics), list(other_topics))]
    NoSuchTopic {
        /// The file (or bag folder).
        path: PathBuf,
        /// The topic asked for.
        topic: String,
        /// The file's laser topics.
        laser_topics: Vec<String>,
        /// The file's other topics, each as `topic (type)`.
        other_topics: Vec<String>,
    },
    /// A rosbag2 SQLite file or bag folder cannot be read.
    #[error("{}: rosbag2 bag: {message}", path.display())]
    Bag {
        /// The file (or bag folder).
        path: PathBuf,
        /// What is wrong.
        message: String,
        /// The SQLite or YAML error, if any.
        #[source]
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
    /// A scan's ray count differs from the geometry of the log.
    #[error("{}:{line}: scan has {got} rays, the log's geometry has {expected}", path.display())]
    RayCountMismatch {
        /// The file.
        path: PathBuf,
        /// Line number (text logs) or message index (MCAP).
        line: usize,
        /// Rays in this scan.
        got: usize,
        /// Rays in the geometry.
        expected: usize,
    },
    /// The log holds no readable scan.
    #[error("{}: no readable scan in the log ({skipped} records skipped)", path.display())]
    NoScans {
        /// The file.
        path: PathBuf,
        /// Records that failed to parse.
        skipped: usize,
    },
    /// The source has delivered every scan of the log.
    #[error("{}: end of log after {scans} scans", path.display())]
    EndOfLog {
        /// The file.
        path: PathBuf,
        /// Scans delivered.
        scans: usize,
    },
    /// A geometry read from the log or given by the caller is invalid.
    #[error("invalid geometry: {0}")]
    Geometry(#[from] scan_types::ScanTypesError),
    /// A scan CSV (the form `robot-app scan` writes) has no first line.
    #[error("{file}: empty file, expected a '# goalseek-scan' line")]
    CsvEmpty {
        /// The file (or `<stdin>`).
        file: String,
    },
    /// A line of a scan CSV is unreadable or malformed; the message names the field.
    #[error("{file}:{line}: {message}")]
    Csv {
        /// The file (or `<stdin>`).
        file: String,
        /// Line number, 1-based.
        line: usize,
        /// What is wrong, naming the geometry key or column.
        message: String,
        /// The underlying error (I/O, number parsing, geometry), if any.
        #[source]
        source: Option<Box<dyn std::error::Error + Send + Sync>>,
    },
    /// A scan CSV holds another number of rays than its geometry line says.
    #[error("{file}: geometry says {expected} rays, file has {got}")]
    CsvRayCount {
        /// The file (or `<stdin>`).
        file: String,
        /// Rays in the geometry line.
        expected: usize,
        /// Ray rows in the file.
        got: usize,
    },
    /// A metadata record of a recording is missing or does not decode.
    #[error("{context}")]
    Metadata {
        /// Which record and key, and the file where known.
        context: String,
        /// The JSON error, if the value is there but does not decode.
        #[source]
        source: Option<serde_json::Error>,
    },
    /// [`crate::McapRecorder::write`] was called before any geometry was known.
    #[error("{}: no scan geometry to record a bare scan with", path.display())]
    NoGeometry {
        /// The file.
        path: PathBuf,
    },
    /// A map given to [`crate::Ros2Recorder::write_map`] has another number of cells than
    /// its width and height say.
    #[error("{}: a map of {width} x {height} cells with {cells} values", path.display())]
    MapSize {
        /// The recording.
        path: PathBuf,
        /// Cells per row.
        width: u32,
        /// Rows.
        height: u32,
        /// Values given.
        cells: usize,
    },
    /// The recorder was used after `finish`.
    #[error("{}: the recording is already finished", path.display())]
    Finished {
        /// The file.
        path: PathBuf,
    },
}

/// A list for messages: the items joined with commas, or `none`.
fn list(items: &[String]) -> String {
    if items.is_empty() {
        "none".into()
    } else {
        items.join(", ")
    }
}

impl LogError {
    /// True for the end-of-log marker of [`crate::LogSource`].
    pub fn is_end_of_log(&self) -> bool {
        matches!(self, LogError::EndOfLog { .. })
    }
}
