//! The ROS1 bag 2.0 container: records of `header_len, header, data_len, data`,
//! messages grouped in chunks (uncompressed, lz4 or bz2), and an index at the
//! end of the file. An indexed bag is opened by reading only its index and
//! one small header per chunk; a bag without an index (a recorder that was
//! killed) is scanned from the start, and a scan stops at the first broken
//! record with everything before it kept.

use std::collections::BTreeMap;

use crate::bytes::{ByteSource, Cursor};
use crate::chunks::{
    claim_region, decompress, dedup_messages, push_message, ChunkCache, ScanBudget,
};
use crate::error::RecordingError;

/// The first bytes of every ROS1 bag 2.0.
pub const MAGIC: &[u8] = b"#ROSBAG V2.0\n";
/// Largest record header read, bytes (real headers are under 1 KB; a
/// connection's message definition is a few KB).
pub const MAX_HEADER_BYTES: u32 = 1 << 20;
/// Largest compressed chunk read, bytes.
pub const MAX_CHUNK_DATA_BYTES: u32 = 256 << 20;
/// Most connections (topics) in one bag.
pub const MAX_CONNECTIONS: usize = 65_536;

const OP_MESSAGE: u8 = 0x02;
const OP_BAG_HEADER: u8 = 0x03;
const OP_INDEX: u8 = 0x04;
const OP_CHUNK: u8 = 0x05;
const OP_CHUNK_INFO: u8 = 0x06;
const OP_CONNECTION: u8 = 0x07;

/// One topic of the bag.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Connection {
    /// The bag's connection id.
    pub id: u32,
    /// Topic name.
    pub topic: String,
    /// Message type, as `sensor_msgs/Image`.
    pub msg_type: String,
}

/// Where one message is: its chunk and its offset in the chunk's uncompressed data.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageRef {
    /// Connection id.
    pub conn: u32,
    /// Bag time, nanoseconds.
    pub time_ns: u64,
    chunk: u32,
    offset: u32,
}

/// A chunk's place in the file.
#[derive(Debug, Clone, Copy)]
struct ChunkPlace {
    pos: u64,
    /// Where an uncompressed chunk's data starts in the file: its messages
    /// are read from there directly, without reading the whole chunk.
    plain_data: Option<u64>,
}

/// The file offset of an uncompressed chunk's data, from its record.
fn plain_data(rec: &Record) -> Result<Option<u64>, RecordingError> {
    let f = fields(&rec.header, rec.header_pos)?;
    let compression = field(&f, "compression", rec.header_pos)?;
    Ok((compression == b"none").then_some(rec.data_pos))
}

/// An opened ROS1 bag: its connections and the index of every message.
pub struct Bag<R: ByteSource> {
    src: R,
    /// Connections by id.
    pub connections: BTreeMap<u32, Connection>,
    /// Every message, in bag-time order.
    pub messages: Vec<MessageRef>,
    chunks: Vec<ChunkPlace>,
    cache: ChunkCache,
    /// What was not read, and why (a truncated tail, a broken chunk).
    pub warnings: Vec<String>,
}

/// `true` when `bytes` start like a ROS1 bag 2.0.
pub fn is_bag(bytes: &[u8]) -> bool {
    bytes.starts_with(MAGIC)
}

struct Record {
    header: Vec<u8>,
    header_pos: u64,
    data_pos: u64,
    data_len: u32,
}

impl Record {
    fn end(&self) -> u64 {
        self.data_pos + u64::from(self.data_len)
    }
}

/// A record's header fields, `name=value`, in order.
fn fields(header: &[u8], offset: u64) -> Result<Vec<(&str, &[u8])>, RecordingError> {
    let mut c = Cursor::new(header, offset);
    let mut out = Vec::new();
    while c.remaining() > 0 {
        let at = c.offset();
        let field = c.bytes("header field")?;
        let eq = field
            .iter()
            .position(|&b| b == b'=')
            .ok_or_else(|| RecordingError::corrupt(at, "header field without `=`"))?;
        let name = std::str::from_utf8(&field[..eq])
            .map_err(|_| RecordingError::corrupt(at, "header field name is not UTF-8"))?;
        out.push((name, &field[eq + 1..]));
    }
    Ok(out)
}

fn field<'a>(
    fields: &[(&str, &'a [u8])],
    name: &str,
    offset: u64,
) -> Result<&'a [u8], RecordingError> {
    fields
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, v)| *v)
        .ok_or_else(|| RecordingError::corrupt(offset, format!("record without `{name}`")))
}

fn field_u32(fields: &[(&str, &[u8])], name: &str, offset: u64) -> Result<u32, RecordingError> {
    Cursor::new(field(fields, name, offset)?, offset).u32(name)
}

fn field_u64(fields: &[(&str, &[u8])], name: &str, offset: u64) -> Result<u64, RecordingError> {
    Cursor::new(field(fields, name, offset)?, offset).u64(name)
}

fn field_str(fields: &[(&str, &[u8])], name: &str, offset: u64) -> Result<String, RecordingError> {
    let v = field(fields, name, offset)?;
    String::from_utf8(v.to_vec())
        .map_err(|_| RecordingError::corrupt(offset, format!("`{name}` is not UTF-8")))
}

fn op(fields: &[(&str, &[u8])], offset: u64) -> Result<u8, RecordingError> {
    let v = field(fields, "op", offset)?;
    match v {
        [b] => Ok(*b),
        _ => Err(RecordingError::corrupt(offset, "`op` is not one byte")),
    }
}

/// A ROS time (`sec`, `nsec` as two `u32`) in nanoseconds.
pub fn ros_time_ns(c: &mut Cursor<'_>, what: &str) -> Result<u64, RecordingError> {
    let sec = u64::from(c.u32(what)?);
    let nsec = u64::from(c.u32(what)?);
    Ok(sec * 1_000_000_000 + nsec)
}

fn read_u32_at<R: ByteSource>(src: &mut R, pos: u64) -> Result<u32, RecordingError> {
    let mut b = [0u8; 4];
    src.read_at(pos, &mut b)?;
    Ok(u32::from_le_bytes(b))
}

/// Reads the record at `pos`: its header in full, its data's place only.
fn read_record<R: ByteSource>(src: &mut R, pos: u64) -> Result<Record, RecordingError> {
    let header_len = read_u32_at(src, pos)?;
    if header_len > MAX_HEADER_BYTES {
        return Err(RecordingError::TooLarge {
            what: "record header in bytes",
            size: u64::from(header_len),
            max: u64::from(MAX_HEADER_BYTES),
        });
    }
    let header_pos = pos + 4;
    crate::bytes::check_range(src.len(), header_pos, header_len as usize)?;
    let mut header = vec![0u8; header_len as usize];
    src.read_at(header_pos, &mut header)?;
    let len_pos = header_pos + u64::from(header_len);
    let data_len = read_u32_at(src, len_pos)?;
    let data_pos = len_pos + 4;
    crate::bytes::check_range(src.len(), data_pos, data_len as usize)?;
    Ok(Record {
        header,
        header_pos,
        data_pos,
        data_len,
    })
}

fn read_data<R: ByteSource>(src: &mut R, rec: &Record) -> Result<Vec<u8>, RecordingError> {
    let mut data = vec![0u8; rec.data_len as usize];
    src.read_at(rec.data_pos, &mut data)?;
    Ok(data)
}

fn connection_from(rec_header: &[u8], data: &[u8], at: u64) -> Result<Connection, RecordingError> {
    let f = fields(rec_header, at)?;
    let id = field_u32(&f, "conn", at)?;
    let topic = field_str(&f, "topic", at)?;
    let df = fields(data, at)?;
    let msg_type = field_str(&df, "type", at)?;
    Ok(Connection {
        id,
        topic,
        msg_type,
    })
}

/// Reads and decompresses the chunk whose record starts at `pos`.
fn load_chunk<R: ByteSource>(src: &mut R, pos: u64) -> Result<Vec<u8>, RecordingError> {
    let rec = read_record(src, pos)?;
    chunk_data(src, &rec, pos, None)
}

/// The uncompressed data of chunk record `rec` (at `pos`), its header
/// already read; a scan pays its declared size from `budget` first.
fn chunk_data<R: ByteSource>(
    src: &mut R,
    rec: &Record,
    pos: u64,
    budget: Option<&mut ScanBudget>,
) -> Result<Vec<u8>, RecordingError> {
    let f = fields(&rec.header, rec.header_pos)?;
    if op(&f, pos)? != OP_CHUNK {
        return Err(RecordingError::corrupt(pos, "expected a chunk record"));
    }
    let compression = field_str(&f, "compression", pos)?;
    let size = field_u32(&f, "size", pos)?;
    if rec.data_len > MAX_CHUNK_DATA_BYTES {
        return Err(RecordingError::TooLarge {
            what: "compressed chunk in bytes",
            size: u64::from(rec.data_len),
            max: u64::from(MAX_CHUNK_DATA_BYTES),
        });
    }
    if let Some(budget) = budget {
        budget.spend(u64::from(size))?;
    }
    let data = read_data(src, rec)?;
    decompress(&compression, u64::from(size), &data, pos)
}

/// The records inside a chunk's uncompressed data, as (offset, header, data).
fn chunk_records(
    chunk: &[u8],
    base: u64,
) -> impl Iterator<Item = Result<(u32, &[u8], &[u8]), RecordingError>> + '_ {
    let mut c = Cursor::new(chunk, base);
    let mut failed = false;
    std::iter::from_fn(move || {
        if failed || c.remaining() == 0 {
            return None;
        }
        let at = (c.offset() - base) as u32;
        let rec = (|| {
            let header = c.bytes("record header")?;
            let data = c.bytes("record data")?;
            Ok((at, header, data))
        })();
        failed = rec.is_err();
        Some(rec)
    })
}

impl<R: ByteSource> Bag<R> {
    /// Opens a bag: reads its index, or scans it when the index is missing or broken.
    pub fn open(mut src: R) -> Result<Self, RecordingError> {
        let mut magic = [0u8; MAGIC.len()];
        src.read_at(0, &mut magic)
            .map_err(|_| RecordingError::UnknownFormat {
                reason: "shorter than a bag's first line".into(),
            })?;
        if magic != MAGIC {
            return Err(RecordingError::UnknownFormat {
                reason:
                    "does not start with `#ROSBAG V2.0` (ROS1 bag 1.2 and other files are not read)"
                        .into(),
            });
        }
        let head = read_record(&mut src, MAGIC.len() as u64)?;
        let f = fields(&head.header, head.header_pos)?;
        if op(&f, head.header_pos)? != OP_BAG_HEADER {
            return Err(RecordingError::corrupt(
                head.header_pos,
                "the first record is not the bag header",
            ));
        }
        let index_pos = field_u64(&f, "index_pos", head.header_pos)?;
        let mut bag = Self {
            src,
            connections: BTreeMap::new(),
            messages: Vec::new(),
            chunks: Vec::new(),
            cache: ChunkCache::default(),
            warnings: Vec::new(),
        };
        let indexed = index_pos > head.end() && index_pos < bag.src.len();
        if indexed {
            match bag.read_index(index_pos) {
                Ok(()) => {}
                Err(e) => {
                    bag.warnings.push(format!(
                        "the bag's index could not be read ({e}); the file was scanned instead"
                    ));
                    bag.scan(head.end())?;
                }
            }
        } else {
            bag.warnings.push(
                "the bag has no index (the recorder did not close it); the file was scanned".into(),
            );
            bag.scan(head.end())?;
        }
        dedup_messages(
            &mut bag.messages,
            |m| (m.chunk, m.offset),
            |m| (m.time_ns, m.chunk, m.offset),
        );
        Ok(bag)
    }

    fn add_connection(&mut self, c: Connection) -> Result<(), RecordingError> {
        if self.connections.len() >= MAX_CONNECTIONS && !self.connections.contains_key(&c.id) {
            return Err(RecordingError::TooLarge {
                what: "number of connections",
                size: self.connections.len() as u64 + 1,
                max: MAX_CONNECTIONS as u64,
            });
        }
        self.connections.insert(c.id, c);
        Ok(())
    }

    /// Reads the data of connection record `rec` (at `pos`) and adds the connection.
    fn add_connection_record(&mut self, rec: &Record, pos: u64) -> Result<(), RecordingError> {
        let data = read_data(&mut self.src, rec)?;
        let c = connection_from(&rec.header, &data, pos)?;
        self.add_connection(c)
    }

    /// The index path: connections and chunk infos at `index_pos`, then the
    /// index records after each chunk. No chunk is decompressed.
    fn read_index(&mut self, index_pos: u64) -> Result<(), RecordingError> {
        let mut pos = index_pos;
        let mut chunk_infos = Vec::new();
        while pos < self.src.len() {
            let rec = read_record(&mut self.src, pos)?;
            let f = fields(&rec.header, rec.header_pos)?;
            match op(&f, pos)? {
                OP_CONNECTION => self.add_connection_record(&rec, pos)?,
                OP_CHUNK_INFO => {
                    let chunk_pos = field_u64(&f, "chunk_pos", pos)?;
                    let count = field_u32(&f, "count", pos)?;
                    chunk_infos.push((chunk_pos, count));
                }
                _ => {}
            }
            pos = rec.end();
        }
        // A chunk listed twice is read once.
        chunk_infos.sort_unstable();
        chunk_infos.dedup_by_key(|(pos, _)| *pos);
        let mut covered = 0u64;
        for (chunk_pos, count) in chunk_infos {
            let chunk = read_record(&mut self.src, chunk_pos)?;
            let chunk_index = self.chunks.len() as u32;
            self.chunks.push(ChunkPlace {
                pos: chunk_pos,
                plain_data: plain_data(&chunk)?,
            });
            let mut at = chunk.end();
            claim_region(&mut covered, chunk_pos, at)?;
            for _ in 0..count {
                let rec = read_record(&mut self.src, at)?;
                claim_region(&mut covered, at, rec.end())?;
                let f = fields(&rec.header, rec.header_pos)?;
                if op(&f, at)? != OP_INDEX {
                    return Err(RecordingError::corrupt(
                        at,
                        "expected an index record after a chunk",
                    ));
                }
                let conn = field_u32(&f, "conn", at)?;
                let n = field_u32(&f, "count", at)? as usize;
                if n.checked_mul(12) != Some(rec.data_len as usize) {
                    return Err(RecordingError::corrupt(
                        at,
                        "index record's size does not match its count",
                    ));
                }
                let data = read_data(&mut self.src, &rec)?;
                let mut c = Cursor::new(&data, rec.data_pos);
                for _ in 0..n {
                    let time_ns = ros_time_ns(&mut c, "index entry")?;
                    let offset = c.u32("index entry")?;
                    push_message(
                        &mut self.messages,
                        MessageRef {
                            conn,
                            time_ns,
                            chunk: chunk_index,
                            offset,
                        },
                    )?;
                }
                at = rec.end();
            }
        }
        Ok(())
    }

    /// The scan path: every record from `start`, chunks decompressed one by
    /// one. Stops at the first record that cannot be read, keeping the rest.
    fn scan(&mut self, start: u64) -> Result<(), RecordingError> {
        self.connections.clear();
        self.messages.clear();
        self.chunks.clear();
        let mut pos = start;
        let mut budget = ScanBudget::for_file(self.src.len());
        while pos < self.src.len() {
            match self.scan_record(pos, &mut budget) {
                Ok(next) => pos = next,
                Err(e @ RecordingError::TooLarge { .. }) => return Err(e),
                Err(e) => {
                    self.warnings
                        .push(crate::chunks::scan_stopped(pos, &e, self.messages.len()));
                    break;
                }
            }
        }
        Ok(())
    }

    fn scan_record(&mut self, pos: u64, budget: &mut ScanBudget) -> Result<u64, RecordingError> {
        let rec = read_record(&mut self.src, pos)?;
        let f = fields(&rec.header, rec.header_pos)?;
        match op(&f, pos)? {
            OP_CONNECTION => self.add_connection_record(&rec, pos)?,
            OP_CHUNK => {
                let chunk = chunk_data(&mut self.src, &rec, pos, Some(budget))?;
                let chunk_index = self.chunks.len() as u32;
                let (mut connections, mut messages) = (Vec::new(), Vec::new());
                for r in chunk_records(&chunk, 0) {
                    let (offset, header, data) = r?;
                    let at = pos + u64::from(offset);
                    let f = fields(header, at)?;
                    match op(&f, at)? {
                        OP_CONNECTION => connections.push(connection_from(header, data, at)?),
                        OP_MESSAGE => {
                            let conn = field_u32(&f, "conn", at)?;
                            let time =
                                ros_time_ns(&mut Cursor::new(field(&f, "time", at)?, at), "time")?;
                            messages.push(MessageRef {
                                conn,
                                time_ns: time,
                                chunk: chunk_index,
                                offset,
                            });
                        }
                        _ => {}
                    }
                }
                // Only a chunk read whole counts: its records are added together.
                self.chunks.push(ChunkPlace {
                    pos,
                    plain_data: plain_data(&rec)?,
                });
                for c in connections {
                    self.add_connection(c)?;
                }
                for m in messages {
                    push_message(&mut self.messages, m)?;
                }
            }
            _ => {}
        }
        Ok(rec.end())
    }

    /// The connection of `m`.
    pub fn connection(&self, m: &MessageRef) -> Option<&Connection> {
        self.connections.get(&m.conn)
    }

    /// The serialised message `m` (its data, without the record header).
    pub fn read(&mut self, m: &MessageRef) -> Result<Vec<u8>, RecordingError> {
        let place = self
            .chunks
            .get(m.chunk as usize)
            .copied()
            .ok_or_else(|| RecordingError::corrupt(0, "message in an unknown chunk"))?;
        if let Some(data_pos) = place.plain_data {
            // The message record read where it lies: one read, no chunk buffer.
            let at = data_pos + u64::from(m.offset);
            let rec = read_record(&mut self.src, at)?;
            let f = fields(&rec.header, rec.header_pos)?;
            if op(&f, at)? != OP_MESSAGE || field_u32(&f, "conn", at)? != m.conn {
                return Err(RecordingError::corrupt(
                    at,
                    "index does not point at a message of its connection",
                ));
            }
            return read_data(&mut self.src, &rec);
        }
        let chunk = match self.cache.get(m.chunk) {
            Some(c) => c,
            None => {
                let data = load_chunk(&mut self.src, place.pos)?;
                self.cache.insert(m.chunk, data)
            }
        };
        let start = m.offset as usize;
        let tail = chunk.get(start..).ok_or_else(|| {
            RecordingError::corrupt(place.pos, "index points past the end of its chunk")
        })?;
        let at = place.pos + u64::from(m.offset);
        let mut c = Cursor::new(tail, at);
        let header = c.bytes("message header")?;
        let f = fields(header, at)?;
        if op(&f, at)? != OP_MESSAGE || field_u32(&f, "conn", at)? != m.conn {
            return Err(RecordingError::corrupt(
                at,
                "index does not point at a message of its connection",
            ));
        }
        Ok(c.bytes("message data")?.to_vec())
    }
}
