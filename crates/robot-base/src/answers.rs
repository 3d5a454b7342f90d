//! A base's answers, read line by line on a thread of their own, so that waiting for one can
//! be given up (Ctrl-C during a move) and an endless line cannot fill memory.

use std::io::BufRead;
use std::sync::mpsc::{Receiver, RecvTimeoutError, SyncSender, sync_channel};
use std::time::Duration;

use crate::BaseError;

/// Longest answer line kept, bytes; the rest of a longer line is read and dropped.
pub const MAX_LINE_BYTES: usize = 4096;
/// How often a wait that may be given up checks whether it should be.
const POLL: Duration = Duration::from_millis(50);
/// Lines read ahead of the one waited for.
const AHEAD: usize = 64;

/// What the reader thread hands over.
enum Item {
    /// A line without its end, lossily decoded, and its length in bytes when it was cut.
    Line(String, Option<usize>),
    /// The link closed.
    End,
    /// Reading failed.
    Failed(std::io::Error),
}

/// The lines of a reader, read ahead on a thread.
pub(crate) struct Answers {
    rx: Receiver<Item>,
}

impl Answers {
    /// Starts reading `reader` (a serial port's timeouts are waited through).
    pub(crate) fn new<R: BufRead + Send + 'static>(reader: R) -> Self {
        let (tx, rx) = sync_channel(AHEAD);
        std::thread::Builder::new()
            .name("base-answers".into())
            .spawn(move || read_lines(reader, &tx))
            .expect("a thread for the base's answers");
        Self { rx }
    }

    /// The next line; `Ok(None)` when the link closed, `Err(Cancelled)` when `cancel` returned
    /// true while waiting. A line longer than [`MAX_LINE_BYTES`] is cut and says so.
    pub(crate) fn next(
        &self,
        command: &str,
        cancel: Option<fn() -> bool>,
    ) -> Result<Option<String>, BaseError> {
        let item = match cancel {
            None => self.rx.recv().unwrap_or(Item::End),
            Some(cancelled) => loop {
                match self.rx.recv_timeout(POLL) {
                    Ok(item) => break item,
                    Err(RecvTimeoutError::Disconnected) => break Item::End,
                    Err(RecvTimeoutError::Timeout) if cancelled() => {
                        return Err(BaseError::Cancelled {
                            command: command.to_string(),
                        });
                    }
                    Err(RecvTimeoutError::Timeout) => {}
                }
            },
        };
        match item {
            Item::Line(text, None) => Ok(Some(text)),
            Item::Line(text, Some(bytes)) => Ok(Some(format!(
                "{}... ({bytes} bytes without a line end; at most {MAX_LINE_BYTES})",
                text.chars().take(80).collect::<String>()
            ))),
            Item::End => Ok(None),
            Item::Failed(e) => Err(e.into()),
        }
    }
}

/// Sends each line of `reader` (cut at [`MAX_LINE_BYTES`]) until it ends or nobody listens.
fn read_lines<R: BufRead>(mut reader: R, tx: &SyncSender<Item>) {
    loop {
        let mut line = Vec::new();
        let mut bytes = 0usize;
        let ended = loop {
            let chunk = match reader.fill_buf() {
                Ok(c) => c,
                Err(e)
                    if matches!(
                        e.kind(),
                        std::io::ErrorKind::TimedOut | std::io::ErrorKind::Interrupted
                    ) =>
                {
                    continue;
                }
                Err(e) => {
                    let _ = tx.send(Item::Failed(e));
                    return;
                }
            };
            if chunk.is_empty() {
                break true;
            }
            let (take, used, done) = match chunk.iter().position(|&b| b == b'\n') {
                Some(i) => (i, i + 1, true),
                None => (chunk.len(), chunk.len(), false),
            };
            let room = MAX_LINE_BYTES.saturating_sub(line.len());
            line.extend_from_slice(&chunk[..take.min(room)]);
            bytes += take;
            reader.consume(used);
            if done {
                break false;
            }
        };
        if !line.is_empty() || !ended {
            let text = String::from_utf8_lossy(&line).into_owned();
            let cut = (bytes > MAX_LINE_BYTES).then_some(bytes);
            if tx.send(Item::Line(text, cut)).is_err() {
                return;
            }
        }
        if ended {
            let _ = tx.send(Item::End);
            return;
        }
    }
}
