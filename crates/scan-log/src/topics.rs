//! The laser topics found in a bag or MCAP file, and the choice of one (`--topic`).

use std::path::Path;

use crate::foreign::ForeignScan;
use crate::{LogError, LogRecord};

/// What goalseek reads from bags and MCAP files, for error messages.
pub const SUPPORTED_TOPICS: &str = "sensor_msgs/msg/LaserScan in CDR (ROS 2 MCAP or rosbag2 .db3 bags), foxglove.LaserScan in protobuf or JSON (MCAP), goalseek recordings";

/// One decoded message of a laser topic.
pub(crate) enum Decoded {
    /// A goalseek recording's scan, exact.
    Exact(LogRecord),
    /// Another tool's scan, turned into a record once the topic is chosen.
    Foreign(ForeignScan),
}

/// The messages of one laser topic, in file order.
pub(crate) struct TopicScans {
    /// The topic name.
    pub topic: String,
    /// The decoded messages (or why one does not decode).
    pub entries: Vec<Result<Decoded, LogError>>,
}

/// Everything found in a file: its laser topics, its other topics, and errors after them.
#[derive(Default)]
pub(crate) struct Found {
    /// The laser topics, in the order they first appear.
    pub laser: Vec<TopicScans>,
    /// The other topics, each as `topic (type)`.
    pub other: Vec<String>,
    /// Errors that end the reading (damage, a cut file), reported after the scans.
    pub tail: Vec<LogError>,
}

impl Found {
    /// The laser topic `topic`, added if new.
    pub fn laser_topic(&mut self, topic: &str) -> &mut TopicScans {
        let i = match self.laser.iter().position(|t| t.topic == topic) {
            Some(i) => i,
            None => {
                self.laser.push(TopicScans {
                    topic: topic.to_string(),
                    entries: Vec::new(),
                });
                self.laser.len() - 1
            }
        };
        &mut self.laser[i]
    }

    /// Notes a topic that holds no laser scans, described as `topic (type)`.
    pub fn other_topic(&mut self, description: String) {
        if !self.other.contains(&description) {
            self.other.push(description);
        }
    }

    /// Adds what another file of the same bag holds.
    pub fn merge(&mut self, more: Found) {
        for t in more.laser {
            self.laser_topic(&t.topic).entries.extend(t.entries);
        }
        for o in more.other {
            self.other_topic(o);
        }
        self.tail.extend(more.tail);
    }

    /// The records of the chosen laser topic (`topic`, or the only one), then the tail errors.
    pub fn select(
        mut self,
        path: &Path,
        topic: Option<&str>,
    ) -> Result<Vec<Result<LogRecord, LogError>>, LogError> {
        let names = || {
            self.laser
                .iter()
                .map(|t| t.topic.clone())
                .collect::<Vec<_>>()
        };
        let chosen = match topic {
            Some(name) => match self.laser.iter().position(|t| t.topic == name) {
                Some(i) => self.laser.swap_remove(i),
                None => {
                    return Err(LogError::NoSuchTopic {
                        path: path.to_path_buf(),
                        topic: name.to_string(),
                        laser_topics: names(),
                        other_topics: self.other.clone(),
                    });
                }
            },
            None if self.laser.len() == 1 => self.laser.remove(0),
            None if self.laser.len() > 1 => {
                return Err(LogError::SeveralTopics {
                    path: path.to_path_buf(),
                    topics: names(),
                });
            }
            None if self.other.is_empty() => {
                // Nothing readable at all: the damage (if any) says why.
                return Ok(self.tail.into_iter().map(Err).collect());
            }
            None => {
                return Err(LogError::Unsupported {
                    path: path.to_path_buf(),
                    found: format!("no laser scan topic, only {}", self.other.join(", ")),
                });
            }
        };
        let max_range_m = chosen
            .entries
            .iter()
            .filter_map(|e| match e {
                Ok(Decoded::Foreign(s)) if s.limits_m.is_none() => s.largest_reading(),
                _ => None,
            })
            .reduce(f64::max)
            .unwrap_or(1.0);
        let topic = chosen.topic;
        let mut out: Vec<Result<LogRecord, LogError>> = chosen
            .entries
            .into_iter()
            .enumerate()
            .map(|(index, e)| match e? {
                Decoded::Exact(r) => Ok(r),
                Decoded::Foreign(s) => {
                    s.into_record(index, max_range_m)
                        .map_err(|message| LogError::Message {
                            path: path.to_path_buf(),
                            index,
                            topic: topic.clone(),
                            message,
                        })
                }
            })
            .collect();
        out.extend(self.tail.into_iter().map(Err));
        Ok(out)
    }
}
