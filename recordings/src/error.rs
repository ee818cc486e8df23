//! What can go wrong reading a recording, as one typed error.

/// An error reading a recording. Every variant names where it happened, so a
/// user can tell a truncated file from an unsupported one.
#[derive(Debug, thiserror::Error)]
pub enum RecordingError {
    /// Reading the underlying file failed.
    #[error("reading {what}: {source}")]
    Io {
        /// What was being read.
        what: String,
        /// The I/O error.
        #[source]
        source: std::io::Error,
    },
    /// The file is not a container this crate reads.
    #[error("not a recording this reader knows: {reason}")]
    UnknownFormat {
        /// What was found instead.
        reason: String,
    },
    /// The file ends inside a record.
    #[error("truncated at byte {offset}: {what}")]
    Truncated {
        /// Byte offset where more data was expected.
        offset: u64,
        /// The record being read.
        what: String,
    },
    /// A record is malformed.
    #[error("corrupt data at byte {offset}: {what}")]
    Corrupt {
        /// Byte offset of the record.
        offset: u64,
        /// What is wrong.
        what: String,
    },
    /// A chunk uses a compression this reader does not decode.
    #[error("chunk at byte {offset} uses compression `{name}` (readable: none, lz4, bz2)")]
    UnsupportedCompression {
        /// Byte offset of the chunk.
        offset: u64,
        /// The compression named in the chunk header.
        name: String,
    },
    /// An image stream uses a pixel encoding this reader does not convert.
    #[error("topic {topic}: unsupported image encoding `{encoding}` ({supported})")]
    UnsupportedEncoding {
        /// The topic.
        topic: String,
        /// The encoding named in the message.
        encoding: String,
        /// What is supported for this kind of stream.
        supported: &'static str,
    },
    /// A size read from the file is above its documented cap; nothing was allocated.
    #[error("{what} is {size}, above the cap of {max}")]
    TooLarge {
        /// What was measured.
        what: &'static str,
        /// The size found.
        size: u64,
        /// The documented cap.
        max: u64,
    },
    /// A stream the tracker needs is missing.
    #[error("{what}{topics}")]
    MissingStream {
        /// What is missing.
        what: String,
        /// The image topics that are there, for the user to choose from.
        topics: String,
    },
    /// A message could not be decoded.
    #[error("topic {topic}: {what}")]
    Message {
        /// The topic.
        topic: String,
        /// What is wrong.
        what: String,
    },
    /// A frame index past the end.
    #[error("no frame {index}: the recording has {len} paired frames")]
    NoFrame {
        /// The index asked for.
        index: usize,
        /// Paired frames available.
        len: usize,
    },
}

impl RecordingError {
    pub(crate) fn corrupt(offset: u64, what: impl Into<String>) -> Self {
        Self::Corrupt {
            offset,
            what: what.into(),
        }
    }

    pub(crate) fn message(topic: &str, what: impl Into<String>) -> Self {
        Self::Message {
            topic: topic.to_string(),
            what: what.into(),
        }
    }
}

/// Adds `item` to a list that may hold at most `max` items (`what` names
/// them in the error), refusing the one past the cap.
pub fn push_capped<T>(
    list: &mut Vec<T>,
    item: T,
    max: usize,
    what: &'static str,
) -> Result<(), RecordingError> {
    if list.len() >= max {
        return Err(RecordingError::TooLarge {
            what,
            size: list.len() as u64 + 1,
            max: max as u64,
        });
    }
    list.push(item);
    Ok(())
}
