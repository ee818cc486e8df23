//! rosbag2's SQLite storage (`.db3`, written by ROS 2's `ros2 bag record`
//! and by librealsense 2.59): a `topics` table (id, name, type,
//! serialization format) and a `messages` table (topic id, timestamp in
//! nanoseconds, the serialised message as a blob), read through
//! [`crate::sqlite`]. Listing the messages reads only the table's pages;
//! each blob is read when its message is.

use crate::bytes::ByteSource;
use crate::chunks::push_message;
use crate::error::{push_capped, RecordingError};
use crate::sqlite::{column_names, Database, RowRef, Value};

/// The first bytes of a zstd frame: a message compressed by rosbag2's
/// `--compression-mode message`.
const ZSTD_MAGIC: [u8; 4] = [0x28, 0xb5, 0x2f, 0xfd];
/// Most topics in one database.
pub const MAX_TOPICS: usize = 65_536;
/// Longest topic name, type or serialisation format read, bytes.
pub const MAX_TOPIC_TEXT_BYTES: u64 = 64 << 10;
/// Largest decompressed message, bytes.
pub const MAX_MESSAGE_BYTES: u64 = 256 << 20;
// The cap holds real messages: a 1920x1080 RGB8 image with its header.
const _: () = assert!(MAX_MESSAGE_BYTES > 1920 * 1080 * 3 + 1024);

/// One topic.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topic {
    /// Its id in the `messages` table.
    pub id: i64,
    /// Topic name.
    pub name: String,
    /// Message type as rosbag2 writes it (`sensor_msgs/msg/Image`).
    pub msg_type: String,
    /// `cdr` for every ROS 2 recording.
    pub serialization: String,
}

/// Where one message's blob is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlobRef {
    row: RowRef,
    offset: u64,
    len: u64,
}

/// One message as listed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Message {
    /// Topic id.
    pub topic: i64,
    /// Receive time, nanoseconds.
    pub time_ns: u64,
    /// Its blob.
    pub blob: BlobRef,
}

/// An opened rosbag2 database.
pub struct Rosbag2<R: ByteSource> {
    db: Database<R>,
    /// Topics.
    pub topics: Vec<Topic>,
    /// Messages in time order.
    pub messages: Vec<Message>,
}

fn column(cols: &[String], name: &str, table: &str) -> Result<usize, RecordingError> {
    cols.iter().position(|c| c == name).ok_or_else(|| RecordingError::UnknownFormat {
        reason: format!("a SQLite database whose `{table}` table has no `{name}` column (not a rosbag2 recording)"),
    })
}

fn int(v: Option<&Value>, rowid: i64) -> Option<i64> {
    match v {
        Some(Value::Int(i)) => Some(*i),
        // The INTEGER PRIMARY KEY column is stored as NULL: it is the rowid.
        Some(Value::Null) => Some(rowid),
        _ => None,
    }
}

impl<R: ByteSource> Rosbag2<R> {
    /// Opens a `.db3`: reads its schema, topics and the list of messages.
    pub fn open(src: R) -> Result<Self, RecordingError> {
        let mut db = Database::open(src)?;
        let tables = db.tables()?;
        let find = |name: &str| {
            tables
                .iter()
                .find(|(n, _, _)| n == name)
                .map(|(_, root, sql)| (*root, column_names(sql)))
                .ok_or_else(|| RecordingError::UnknownFormat {
                    reason: format!(
                        "a SQLite database without a `{name}` table (not a rosbag2 recording)"
                    ),
                })
        };
        let (topics_root, tcols) = find("topics")?;
        let (messages_root, mcols) = find("messages")?;
        let (t_id, t_name, t_type, t_ser) = (
            column(&tcols, "id", "topics")?,
            column(&tcols, "name", "topics")?,
            column(&tcols, "type", "topics")?,
            column(&tcols, "serialization_format", "topics")?,
        );
        let mut topics: Vec<Topic> = Vec::new();
        db.for_each_row(topics_root, |db, row| {
            let v = &row.values;
            let bad = || RecordingError::corrupt(0, "a `topics` row of the wrong shape");
            let id = int(v.get(t_id), row.at.rowid).ok_or_else(bad)?;
            let mut text = |i: usize| match v.get(i) {
                Some(val) => db.text(row.at, val, MAX_TOPIC_TEXT_BYTES),
                None => Err(bad()),
            };
            let topic = Topic {
                id,
                name: text(t_name)?,
                msg_type: text(t_type)?,
                serialization: text(t_ser)?,
            };
            push_capped(&mut topics, topic, MAX_TOPICS, "number of topics")
        })?;
        let (m_topic, m_time, m_data) = (
            column(&mcols, "topic_id", "messages")?,
            column(&mcols, "timestamp", "messages")?,
            column(&mcols, "data", "messages")?,
        );
        // Listed row by row, keeping only where each blob is: a row's other
        // values are never held, so memory is a few words per message.
        let mut messages = Vec::new();
        db.for_each_row(messages_root, |_, row| {
            let v = &row.values;
            let (Some(topic), Some(time), Some(Value::Bytes { offset, len, .. })) = (
                int(v.get(m_topic), row.at.rowid),
                int(v.get(m_time), row.at.rowid),
                v.get(m_data),
            ) else {
                return Err(RecordingError::corrupt(
                    0,
                    "a `messages` row of the wrong shape",
                ));
            };
            push_message(
                &mut messages,
                Message {
                    topic,
                    time_ns: time.max(0) as u64,
                    blob: BlobRef {
                        row: row.at,
                        offset: *offset,
                        len: *len,
                    },
                },
            )
        })?;
        messages.sort_by_key(|m| (m.time_ns, m.blob.row.rowid));
        Ok(Self {
            db,
            topics,
            messages,
        })
    }

    /// The serialised message `m`, decompressed when rosbag2 compressed it.
    pub fn read(&mut self, m: &Message) -> Result<Vec<u8>, RecordingError> {
        let b = m.blob;
        let data = self.db.payload(b.row, b.offset, b.len)?;
        message_bytes(data, MAX_MESSAGE_BYTES)
    }
}

/// A stored message as its bytes: `data` itself, or its zstd frame
/// decompressed to at most `max` bytes (rosbag2's per-message compression).
fn message_bytes(data: Vec<u8>, max: u64) -> Result<Vec<u8>, RecordingError> {
    if !data.starts_with(&ZSTD_MAGIC) {
        return Ok(data);
    }
    use std::io::Read;
    let mut out = Vec::new();
    ruzstd::decoding::StreamingDecoder::new(data.as_slice())
        .map_err(|e| RecordingError::corrupt(0, format!("zstd message: {e}")))?
        .take(max + 1)
        .read_to_end(&mut out)
        .map_err(|e| RecordingError::corrupt(0, format!("zstd message: {e}")))?;
    if out.len() as u64 > max {
        return Err(RecordingError::TooLarge {
            what: "decompressed message in bytes",
            size: out.len() as u64,
            max,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_zstd_message_decompresses_up_to_its_cap_and_no_further() {
        let plain: Vec<u8> = (0..1000u32).map(|i| (i % 7) as u8).collect();
        let packed = ruzstd::encoding::compress_to_vec(
            plain.as_slice(),
            ruzstd::encoding::CompressionLevel::Fastest,
        );
        assert!(packed.starts_with(&ZSTD_MAGIC));
        assert_eq!(
            message_bytes(packed.clone(), 1000).expect("at the cap"),
            plain
        );
        assert!(matches!(
            message_bytes(packed, 999),
            Err(RecordingError::TooLarge {
                size: 1000,
                max: 999,
                ..
            })
        ));
        // A message that is not compressed is handed back as it is.
        assert_eq!(message_bytes(vec![1, 2, 3], 0).expect("plain"), [1, 2, 3]);
    }
}
