//! rosbag2 bags: a SQLite `.db3` file, or a bag folder (its `metadata.yaml` names the
//! storage files, SQLite or MCAP).

use std::path::{Path, PathBuf};

use rusqlite::{Connection, OpenFlags};

use crate::foreign::{self, ROS2_LASER_SCAN};
use crate::topics::{Decoded, Found};
use crate::{LogError, LogRecord, mcap_io};

/// The first 16 bytes of an SQLite 3 database file.
pub const SQLITE_MAGIC: &[u8; 16] = b"SQLite format 3\0";

/// The name of a rosbag2 bag folder's description.
pub const BAG_METADATA: &str = "metadata.yaml";

fn bag_error(path: &Path, message: String) -> LogError {
    LogError::Bag {
        path: path.to_path_buf(),
        message,
        source: None,
    }
}

fn sqlite_error(path: &Path, what: &str, e: rusqlite::Error) -> LogError {
    LogError::Bag {
        path: path.to_path_buf(),
        message: format!("{what} (expected a rosbag2 SQLite bag with tables topics and messages)"),
        source: Some(Box::new(e)),
    }
}

/// Every laser topic of a rosbag2 SQLite file, decoded in time-stamp order.
fn scan_db3(path: &Path) -> Result<Found, LogError> {
    let db = Connection::open_with_flags(
        path,
        OpenFlags::SQLITE_OPEN_READ_ONLY | OpenFlags::SQLITE_OPEN_NO_MUTEX,
    )
    .map_err(|e| sqlite_error(path, "cannot open the SQLite file", e))?;
    let mut found = Found::default();
    // Topic id -> name, for the laser topics.
    let mut laser: Vec<(i64, String)> = Vec::new();
    {
        let mut q = db
            .prepare("SELECT id, name, type, serialization_format FROM topics ORDER BY id")
            .map_err(|e| sqlite_error(path, "no readable topics table", e))?;
        let rows = q
            .query_map([], |r| {
                Ok((
                    r.get::<_, i64>(0)?,
                    r.get::<_, String>(1)?,
                    r.get::<_, String>(2)?,
                    r.get::<_, String>(3)?,
                ))
            })
            .map_err(|e| sqlite_error(path, "reading the topics table", e))?;
        for row in rows {
            let (id, name, ty, format) =
                row.map_err(|e| sqlite_error(path, "reading the topics table", e))?;
            if ty == ROS2_LASER_SCAN && format == "cdr" {
                found.laser_topic(&name);
                laser.push((id, name));
            } else {
                found.other_topic(format!("{name} ({ty} in {format})"));
            }
        }
    }
    if laser.is_empty() {
        return Ok(found);
    }
    let mut q = db
        .prepare("SELECT topic_id, data FROM messages ORDER BY timestamp, id")
        .map_err(|e| sqlite_error(path, "no readable messages table", e))?;
    let mut rows = q
        .query([])
        .map_err(|e| sqlite_error(path, "reading the messages table", e))?;
    let mut index = 0usize;
    loop {
        let row = match rows.next() {
            Ok(Some(r)) => r,
            Ok(None) => break,
            Err(e) => {
                found
                    .tail
                    .push(sqlite_error(path, "reading the messages table", e));
                break;
            }
        };
        index += 1;
        let Ok(topic_id) = row.get::<_, i64>(0) else {
            continue;
        };
        let Some((_, topic)) = laser.iter().find(|(id, _)| *id == topic_id) else {
            continue;
        };
        let decoded = match row.get_ref(1).map(|v| v.as_blob()) {
            Ok(Ok(data)) => foreign::decode_ros2_laser_scan(data)
                .map(Decoded::Foreign)
                .map_err(|m| format!("not a CDR {ROS2_LASER_SCAN}: {m}")),
            _ => Err("the message data is not a blob".to_string()),
        };
        let decoded = decoded.map_err(|message| LogError::Message {
            path: path.to_path_buf(),
            index: index - 1,
            topic: topic.clone(),
            message,
        });
        found.laser_topic(topic).entries.push(decoded);
    }
    Ok(found)
}

/// The storage files of a bag folder, from its `metadata.yaml`.
fn bag_files(dir: &Path) -> Result<Vec<PathBuf>, LogError> {
    let meta_path = dir.join(BAG_METADATA);
    if !meta_path.is_file() {
        return Err(bag_error(
            dir,
            format!("a folder without {BAG_METADATA}, not a rosbag2 bag"),
        ));
    }
    let text = std::fs::read_to_string(&meta_path).map_err(|source| LogError::Io {
        path: meta_path.clone(),
        source,
    })?;
    let meta: serde_norway::Value = serde_norway::from_str(&text).map_err(|e| LogError::Bag {
        path: meta_path.clone(),
        message: "not YAML".into(),
        source: Some(Box::new(e)),
    })?;
    let info = &meta["rosbag2_bagfile_information"];
    let compression = info["compression_format"].as_str().unwrap_or("");
    if !compression.is_empty() {
        return Err(bag_error(
            &meta_path,
            format!(
                "compressed bag ({compression}, mode {}): goalseek reads uncompressed rosbag2 bags (their MCAP files may have zstd or lz4 chunks)",
                info["compression_mode"].as_str().unwrap_or("?")
            ),
        ));
    }
    let Some(files) = info["relative_file_paths"].as_sequence() else {
        return Err(bag_error(
            &meta_path,
            "no rosbag2_bagfile_information.relative_file_paths list".into(),
        ));
    };
    let mut out = Vec::new();
    for f in files {
        let Some(name) = f.as_str() else {
            return Err(bag_error(
                &meta_path,
                "relative_file_paths holds a non-string".into(),
            ));
        };
        // Older rosbag2 writes the paths with the bag folder's name in front.
        let p = dir.join(name);
        let p = match Path::new(name).file_name() {
            Some(base) if !p.exists() => dir.join(base),
            _ => p,
        };
        out.push(p);
    }
    if out.is_empty() {
        return Err(bag_error(&meta_path, "the bag lists no files".into()));
    }
    Ok(out)
}

/// Reads the scans of the laser topic `topic` (`None`: the only one) of a rosbag2 bag: a
/// SQLite `.db3` file or a bag folder (`metadata.yaml` and its `.db3` or `.mcap` files, read
/// in the order it lists them).
pub fn read_bag(
    path: &Path,
    topic: Option<&str>,
) -> Result<Vec<Result<LogRecord, LogError>>, LogError> {
    let found = if path.is_dir() {
        let mut found = Found::default();
        for file in bag_files(path)? {
            let head = crate::source::read_head(&file)?;
            if head.starts_with(mcap::MAGIC) {
                let bytes = std::fs::read(&file).map_err(|source| LogError::Io {
                    path: file.clone(),
                    source,
                })?;
                found.merge(mcap_io::scan_mcap(&bytes, &file));
            } else if &head == SQLITE_MAGIC {
                found.merge(scan_db3(&file)?);
            } else {
                return Err(bag_error(
                    &file,
                    "neither an SQLite nor an MCAP file (by its first bytes)".into(),
                ));
            }
        }
        found
    } else {
        scan_db3(path)?
    };
    found.select(path, topic)
}
