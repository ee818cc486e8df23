//! The MCAP container (`.mcap`, ROS 2's other rosbag2 storage): records of
//! `opcode, u64 length, body`, messages grouped in chunks (uncompressed, lz4
//! or zstd), and a summary section at the end indexing the chunks. An
//! indexed file is opened from its footer, summary and message indexes
//! alone; a file without a summary (a recorder that was killed) is scanned
//! from the start, stopping at the first broken record with everything
//! before it kept. Written here from the format's specification: the `mcap`
//! crate decompresses through C libraries, which do not build for the page.

use std::collections::BTreeMap;

use crate::bytes::{ByteSource, Cursor};
use crate::chunks::{
    claim_region, decompress, dedup_messages, push_message, ChunkCache, ScanBudget, MAX_CHUNK_BYTES,
};
use crate::error::RecordingError;

/// The first and last 8 bytes of every MCAP file.
pub const MAGIC: &[u8] = b"\x89MCAP0\r\n";
/// Largest record read whole outside a chunk (schemas, channels, indexes), bytes.
pub const MAX_RECORD_BYTES: u64 = 64 << 20;

const OP_FOOTER: u8 = 0x02;
const OP_SCHEMA: u8 = 0x03;
const OP_CHANNEL: u8 = 0x04;
const OP_MESSAGE: u8 = 0x05;
const OP_CHUNK: u8 = 0x06;
const OP_MESSAGE_INDEX: u8 = 0x07;
const OP_CHUNK_INDEX: u8 = 0x08;
/// Footer record: opcode, length, summary start, summary offset start, CRC.
const FOOTER_BYTES: u64 = 1 + 8 + 8 + 8 + 4;
/// An uncompressed chunk's header: times, size, CRC, the empty compression
/// string and the records' length.
const PLAIN_CHUNK_HEADER: u64 = 8 + 8 + 8 + 4 + 4 + 8;

/// `true` when `head` starts like an MCAP file.
pub fn is_mcap(head: &[u8]) -> bool {
    head.starts_with(MAGIC)
}

/// A channel (a topic) and its schema's name and the message encoding.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Channel {
    /// Topic.
    pub topic: String,
    /// The schema's name, as `sensor_msgs/msg/Image`.
    pub schema: String,
    /// `cdr` for ROS 2, `ros1` for ROS1 messages.
    pub encoding: String,
}

/// Where one message is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MessageRef {
    /// Channel id.
    pub channel: u16,
    /// Log time, nanoseconds.
    pub time_ns: u64,
    /// Its chunk (index into the chunk list), or `u32::MAX` outside chunks.
    chunk: u32,
    /// Offset of its record in the chunk's records, or in the file.
    offset: u64,
}

#[derive(Debug, Clone, Copy)]
struct ChunkPlace {
    /// File offset of the chunk record.
    pos: u64,
}

/// An opened MCAP file.
pub struct Mcap<R: ByteSource> {
    src: R,
    /// Channels by id.
    pub channels: BTreeMap<u16, Channel>,
    /// Every message, in log-time order.
    pub messages: Vec<MessageRef>,
    chunks: Vec<ChunkPlace>,
    cache: ChunkCache,
    /// What was not read, and why.
    pub warnings: Vec<String>,
}

/// A record at `pos` of the file: opcode and body (read whole, capped).
fn read_record<R: ByteSource>(
    src: &mut R,
    pos: u64,
    cap: u64,
) -> Result<(u8, Vec<u8>, u64), RecordingError> {
    let (op, len, body_at) = record_head(src, pos)?;
    if len > cap {
        return Err(RecordingError::TooLarge {
            what: "MCAP record in bytes",
            size: len,
            max: cap,
        });
    }
    crate::bytes::check_range(src.len(), body_at, len as usize)?;
    let mut body = vec![0u8; len as usize];
    src.read_at(body_at, &mut body)?;
    Ok((op, body, body_at + len))
}

/// Channel id and log time of a message record's body (channel u16,
/// sequence u32, log time u64, ...); `None` when it is too short.
fn message_head(body: &[u8]) -> Option<(u16, u64)> {
    let b = body.get(..14)?;
    let time = u64::from_le_bytes([b[6], b[7], b[8], b[9], b[10], b[11], b[12], b[13]]);
    Some((u16::from_le_bytes([b[0], b[1]]), time))
}

/// The data of message record body `body`, checked to be `channel`'s.
fn message_data(body: &[u8], channel: u16, at: u64) -> Result<&[u8], RecordingError> {
    match (message_head(body), body.get(22..)) {
        (Some((c, _)), Some(data)) if c == channel => Ok(data),
        _ => Err(RecordingError::corrupt(
            at,
            "message of another channel or too short",
        )),
    }
}

/// The opcode and length of the record at `pos`, and where its body starts.
fn record_head<R: ByteSource>(src: &mut R, pos: u64) -> Result<(u8, u64, u64), RecordingError> {
    let mut head = [0u8; 9];
    src.read_at(pos, &mut head)?;
    let len = u64::from_le_bytes([
        head[1], head[2], head[3], head[4], head[5], head[6], head[7], head[8],
    ]);
    Ok((head[0], len, pos + 9))
}

/// The records of a byte run: (offset, opcode, body).
fn records(
    bytes: &[u8],
    base: u64,
) -> impl Iterator<Item = Result<(u64, u8, &[u8]), RecordingError>> + '_ {
    let mut c = Cursor::new(bytes, base);
    let mut failed = false;
    std::iter::from_fn(move || {
        if failed || c.remaining() == 0 {
            return None;
        }
        let at = c.offset() - base;
        let r = (|| {
            let op = c.u8("record opcode")?;
            let len = c.u64("record length")?;
            let body = c.take(usize::try_from(len).unwrap_or(usize::MAX), "record body")?;
            Ok((at, op, body))
        })();
        failed = r.is_err();
        Some(r)
    })
}

/// A chunk record's body: (compression, uncompressed size, the records' bytes).
fn chunk_parts(body: &[u8], at: u64) -> Result<(String, u64, &[u8]), RecordingError> {
    let mut c = Cursor::new(body, at);
    let _start = c.u64("chunk start time")?;
    let _end = c.u64("chunk end time")?;
    let size = c.u64("chunk uncompressed size")?;
    let _crc = c.u32("chunk crc")?;
    let compression = c.string("chunk compression")?;
    let len = c.u64("chunk records length")?;
    let data = c.take(usize::try_from(len).unwrap_or(usize::MAX), "chunk records")?;
    Ok((compression, size, data))
}

impl<R: ByteSource> Mcap<R> {
    /// Opens an MCAP file: its summary when there is one, else a scan.
    pub fn open(mut src: R) -> Result<Self, RecordingError> {
        let mut magic = [0u8; 8];
        src.read_at(0, &mut magic)
            .map_err(|_| RecordingError::UnknownFormat {
                reason: "shorter than an MCAP header".into(),
            })?;
        if magic != MAGIC {
            return Err(RecordingError::UnknownFormat {
                reason: "not an MCAP file".into(),
            });
        }
        let mut m = Self {
            src,
            channels: BTreeMap::new(),
            messages: Vec::new(),
            chunks: Vec::new(),
            cache: ChunkCache::default(),
            warnings: Vec::new(),
        };
        let mut schemas: BTreeMap<u16, String> = BTreeMap::new();
        let mut pending: Vec<(u16, u16, String, String)> = Vec::new();
        match m.read_summary(&mut schemas, &mut pending) {
            Ok(true) => {}
            Ok(false) => {
                m.warnings.push(
                    "the file has no summary (the recorder did not close it); it was scanned"
                        .into(),
                );
                m.scan(&mut schemas, &mut pending)?;
            }
            Err(e @ RecordingError::TooLarge { .. }) => return Err(e),
            Err(e) => {
                m.warnings.push(format!(
                    "the summary could not be read ({e}); the file was scanned instead"
                ));
                m.channels.clear();
                m.messages.clear();
                m.chunks.clear();
                schemas.clear();
                pending.clear();
                m.scan(&mut schemas, &mut pending)?;
            }
        }
        for (id, schema_id, topic, encoding) in pending {
            let schema = schemas.get(&schema_id).cloned().unwrap_or_default();
            m.channels.insert(
                id,
                Channel {
                    topic,
                    schema,
                    encoding,
                },
            );
        }
        dedup_messages(
            &mut m.messages,
            |r| (r.chunk, r.offset),
            |r| (r.time_ns, r.chunk, r.offset),
        );
        Ok(m)
    }

    /// Schema and channel records, gathered wherever they are met.
    fn meta(
        op: u8,
        body: &[u8],
        at: u64,
        schemas: &mut BTreeMap<u16, String>,
        pending: &mut Vec<(u16, u16, String, String)>,
    ) -> Result<(), RecordingError> {
        let mut c = Cursor::new(body, at);
        match op {
            OP_SCHEMA => {
                let id = c.u16("schema id")?;
                schemas.insert(id, c.string("schema name")?);
            }
            OP_CHANNEL => {
                let id = c.u16("channel id")?;
                let schema = c.u16("channel schema")?;
                let topic = c.string("channel topic")?;
                let encoding = c.string("channel encoding")?;
                if !pending.iter().any(|p| p.0 == id) {
                    pending.push((id, schema, topic, encoding));
                }
            }
            _ => {}
        }
        Ok(())
    }

    /// The indexed path; `Ok(false)` when the file has no summary.
    fn read_summary(
        &mut self,
        schemas: &mut BTreeMap<u16, String>,
        pending: &mut Vec<(u16, u16, String, String)>,
    ) -> Result<bool, RecordingError> {
        let len = self.src.len();
        if len < 8 + FOOTER_BYTES + 8 {
            return Ok(false);
        }
        let mut tail = [0u8; 8];
        self.src.read_at(len - 8, &mut tail)?;
        if tail != MAGIC {
            return Ok(false);
        }
        let footer_at = len - 8 - FOOTER_BYTES;
        let (op, body, _) = read_record(&mut self.src, footer_at, 64)?;
        if op != OP_FOOTER {
            return Ok(false);
        }
        let summary_start = Cursor::new(&body, footer_at + 9).u64("summary start")?;
        if summary_start == 0 || summary_start >= footer_at {
            return Ok(false);
        }
        let mut chunk_indexes = Vec::new();
        let mut pos = summary_start;
        while pos < footer_at {
            let (op, body, next) = read_record(&mut self.src, pos, MAX_RECORD_BYTES)?;
            Self::meta(op, &body, pos + 9, schemas, pending)?;
            if op == OP_CHUNK_INDEX {
                let mut c = Cursor::new(&body, pos + 9);
                let _start = c.u64("chunk index")?;
                let _end = c.u64("chunk index")?;
                let chunk_at = c.u64("chunk offset")?;
                let chunk_len = c.u64("chunk length")?;
                let map_len = c.u32("message index offsets")? as usize;
                c.take(map_len, "message index offsets")?;
                let index_len = c.u64("message index length")?;
                let plain = c.string("chunk compression")?.is_empty();
                chunk_indexes.push((chunk_at, chunk_len, index_len, plain));
            }
            pos = next;
        }
        // A chunk indexed twice is read once; chunks and their message
        // indexes must then follow one another without overlapping.
        chunk_indexes.sort_unstable();
        chunk_indexes.dedup_by_key(|c| c.0);
        let mut covered = 0u64;
        for (chunk_at, chunk_len, index_len, plain) in chunk_indexes {
            let chunk = self.chunks.len() as u32;
            self.chunks.push(ChunkPlace { pos: chunk_at });
            if index_len > MAX_RECORD_BYTES {
                return Err(RecordingError::TooLarge {
                    what: "MCAP message index in bytes",
                    size: index_len,
                    max: MAX_RECORD_BYTES,
                });
            }
            let at = chunk_at
                .checked_add(chunk_len)
                .ok_or_else(|| RecordingError::corrupt(chunk_at, "chunk length overflows"))?;
            crate::bytes::check_range(self.src.len(), at, index_len as usize)?;
            claim_region(&mut covered, chunk_at, at)?;
            claim_region(&mut covered, at, at + index_len)?;
            // An uncompressed chunk's records start after its 40-byte header:
            // its messages are read where they lie, without the whole chunk.
            let in_file = |offset: u64| {
                (chunk_at + 9 + PLAIN_CHUNK_HEADER)
                    .checked_add(offset)
                    .filter(|&p| p < at)
                    .ok_or_else(|| {
                        RecordingError::corrupt(chunk_at, "message index points past its chunk")
                    })
            };
            let mut bytes = vec![0u8; index_len as usize];
            self.src.read_at(at, &mut bytes)?;
            for r in records(&bytes, at) {
                let (off, op, body) = r?;
                if op != OP_MESSAGE_INDEX {
                    continue;
                }
                let mut c = Cursor::new(body, at + off + 9);
                let channel = c.u16("index channel")?;
                let n = c.u32("index entries")? as usize;
                if n % 16 != 0 {
                    return Err(RecordingError::corrupt(
                        at + off,
                        "message index entries not 16 bytes each",
                    ));
                }
                for _ in 0..n / 16 {
                    let time_ns = c.u64("index time")?;
                    let offset = c.u64("index offset")?;
                    let (chunk, offset) = if plain {
                        (u32::MAX, in_file(offset)?)
                    } else {
                        (chunk, offset)
                    };
                    push_message(
                        &mut self.messages,
                        MessageRef {
                            channel,
                            time_ns,
                            chunk,
                            offset,
                        },
                    )?;
                }
            }
        }
        Ok(true)
    }

    /// The scan path: every record from the header on.
    fn scan(
        &mut self,
        schemas: &mut BTreeMap<u16, String>,
        pending: &mut Vec<(u16, u16, String, String)>,
    ) -> Result<(), RecordingError> {
        let mut pos = MAGIC.len() as u64;
        let end = self.src.len();
        let mut budget = ScanBudget::for_file(end);
        while pos + 9 <= end {
            let step = (|| -> Result<Option<u64>, RecordingError> {
                let (op, len, body_at) = record_head(&mut self.src, pos)?;
                let complete = body_at.checked_add(len).filter(|&n| n <= end);
                if complete.is_none() && op == OP_CHUNK {
                    // A cut uncompressed chunk: its whole records still count.
                    self.scan_cut_chunk(body_at, schemas, pending)?;
                }
                let next = complete.ok_or_else(|| RecordingError::Truncated {
                    offset: pos,
                    what: "MCAP record runs past the end".into(),
                })?;
                match op {
                    OP_SCHEMA | OP_CHANNEL => {
                        let (_, body, _) = read_record(&mut self.src, pos, MAX_RECORD_BYTES)?;
                        Self::meta(op, &body, body_at, schemas, pending)?;
                    }
                    OP_MESSAGE => {
                        let mut head = [0u8; 14];
                        self.src.read_at(body_at, &mut head)?;
                        let (channel, time_ns) = message_head(&head)
                            .ok_or_else(|| RecordingError::corrupt(pos, "message too short"))?;
                        push_message(
                            &mut self.messages,
                            MessageRef {
                                channel,
                                time_ns,
                                chunk: u32::MAX,
                                offset: pos,
                            },
                        )?;
                    }
                    OP_CHUNK => {
                        let (_, body, _) = read_record(&mut self.src, pos, MAX_CHUNK_BYTES)?;
                        let (compression, size, data) = chunk_parts(&body, body_at)?;
                        budget.spend(size)?;
                        let inner = decompress(&compression, size, data, pos)?;
                        let chunk = self.chunks.len() as u32;
                        let mut found = Vec::new();
                        for r in records(&inner, 0) {
                            let (off, op, b) = r?;
                            Self::meta(op, b, pos, schemas, pending)?;
                            if let (OP_MESSAGE, Some((channel, time_ns))) = (op, message_head(b)) {
                                found.push(MessageRef {
                                    channel,
                                    time_ns,
                                    chunk,
                                    offset: off,
                                });
                            }
                        }
                        self.chunks.push(ChunkPlace { pos });
                        for f in found {
                            push_message(&mut self.messages, f)?;
                        }
                    }
                    // Data end: the summary follows.
                    0x0f => return Ok(None),
                    _ => {}
                }
                Ok(Some(next))
            })();
            match step {
                Ok(Some(next)) => pos = next,
                Ok(None) => break,
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

    /// The whole records of an uncompressed chunk cut short by the end of
    /// the file (a recorder that was killed), as messages read in place.
    fn scan_cut_chunk(
        &mut self,
        body_at: u64,
        schemas: &mut BTreeMap<u16, String>,
        pending: &mut Vec<(u16, u16, String, String)>,
    ) -> Result<(), RecordingError> {
        let avail = self.src.len().saturating_sub(body_at).min(MAX_CHUNK_BYTES);
        let mut body = vec![0u8; avail as usize];
        self.src.read_at(body_at, &mut body)?;
        let mut c = Cursor::new(&body, body_at);
        c.take(28, "chunk header")?;
        if !c.string("chunk compression")?.is_empty() {
            return Ok(());
        }
        c.u64("chunk records length")?;
        let start = (c.offset() - body_at) as usize;
        let records_at = c.offset();
        let mut found = Vec::new();
        for r in records(&body[start..], records_at) {
            let Ok((off, op, b)) = r else { break };
            Self::meta(op, b, records_at + off, schemas, pending)?;
            if let (OP_MESSAGE, Some((channel, time_ns))) = (op, message_head(b)) {
                found.push(MessageRef {
                    channel,
                    time_ns,
                    chunk: u32::MAX,
                    offset: records_at + off,
                });
            }
        }
        for f in found {
            push_message(&mut self.messages, f)?;
        }
        Ok(())
    }

    /// The message data of `m` (without the record's channel, sequence and times).
    pub fn read(&mut self, m: &MessageRef) -> Result<Vec<u8>, RecordingError> {
        if m.chunk == u32::MAX {
            let (op, mut body, _) = read_record(&mut self.src, m.offset, MAX_CHUNK_BYTES)?;
            if op != OP_MESSAGE {
                return Err(RecordingError::corrupt(
                    m.offset,
                    "index does not point at a message",
                ));
            }
            // Checked, then the record's own buffer handed on without a copy.
            message_data(&body, m.channel, m.offset)?;
            body.drain(..22);
            return Ok(body);
        }
        let place = *self
            .chunks
            .get(m.chunk as usize)
            .ok_or_else(|| RecordingError::corrupt(0, "message in an unknown chunk"))?;
        let chunk = match self.cache.get(m.chunk) {
            Some(c) => c,
            None => {
                let (op, body, _) = read_record(&mut self.src, place.pos, MAX_CHUNK_BYTES)?;
                if op != OP_CHUNK {
                    return Err(RecordingError::corrupt(
                        place.pos,
                        "chunk index does not point at a chunk",
                    ));
                }
                let (compression, size, data) = chunk_parts(&body, place.pos + 9)?;
                let data = decompress(&compression, size, data, place.pos)?;
                self.cache.insert(m.chunk, data)
            }
        };
        let start = usize::try_from(m.offset).unwrap_or(usize::MAX);
        let tail = chunk
            .get(start..)
            .ok_or_else(|| RecordingError::corrupt(place.pos, "index points past its chunk"))?;
        let (_, op, body) = records(tail, 0)
            .next()
            .ok_or_else(|| RecordingError::corrupt(place.pos, "index points past its chunk"))??;
        if op != OP_MESSAGE {
            return Err(RecordingError::corrupt(
                place.pos,
                "index does not point at a message",
            ));
        }
        Ok(message_data(body, m.channel, m.offset)?.to_vec())
    }
}
