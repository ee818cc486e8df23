//! What the chunked containers (ROS1 bags, MCAP) share: decompressing a
//! chunk with its declared size checked before anything is allocated, a
//! bounded cache of decompressed chunks, the cap on their message index, and
//! how a scan says where it stopped.

use std::io::Read;
use std::rc::Rc;

use crate::error::{push_capped, RecordingError};

/// Largest uncompressed chunk, bytes: checked against the chunk's declared
/// size before anything is allocated or decompressed.
pub const MAX_CHUNK_BYTES: u64 = 256 << 20;
/// Decompressed chunks kept in memory, bytes. With this cap a reader's memory
/// stays under 300 MB whatever the size of the file.
pub const CHUNK_CACHE_BYTES: usize = 192 << 20;

/// `data` decompressed with `compression` (`none` or empty, `lz4` frames,
/// `bz2`, `zstd`) to exactly `size` bytes; `offset` names the chunk in errors.
pub fn decompress(
    compression: &str,
    size: u64,
    data: &[u8],
    offset: u64,
) -> Result<Vec<u8>, RecordingError> {
    if size > MAX_CHUNK_BYTES {
        return Err(RecordingError::TooLarge {
            what: "uncompressed chunk in bytes",
            size,
            max: MAX_CHUNK_BYTES,
        });
    }
    // Reserved up to a plausible ratio only: a tiny corrupt chunk declaring
    // a huge size grows its buffer as data actually comes out.
    let mut out = Vec::with_capacity((size as usize).min(data.len().saturating_mul(8) + 4096));
    // One byte more than declared is read, so a chunk longer than it says is caught.
    let limit = size + 1;
    let corrupt =
        |e: std::io::Error| RecordingError::corrupt(offset, format!("{compression} chunk: {e}"));
    match compression {
        "none" | "" => return check_size(data.to_vec(), size, offset),
        "lz4" => lz4_flex::frame::FrameDecoder::new(data)
            .take(limit)
            .read_to_end(&mut out)
            .map_err(corrupt)?,
        "bz2" => bzip2::read::BzDecoder::new(data)
            .take(limit)
            .read_to_end(&mut out)
            .map_err(corrupt)?,
        "zstd" => ruzstd::decoding::StreamingDecoder::new(data)
            .map_err(|e| RecordingError::corrupt(offset, format!("zstd chunk: {e}")))?
            .take(limit)
            .read_to_end(&mut out)
            .map_err(corrupt)?,
        other => {
            return Err(RecordingError::UnsupportedCompression {
                offset,
                name: other.to_string(),
            })
        }
    };
    check_size(out, size, offset)
}

fn check_size(out: Vec<u8>, size: u64, offset: u64) -> Result<Vec<u8>, RecordingError> {
    if out.len() as u64 != size {
        return Err(RecordingError::corrupt(
            offset,
            format!(
                "chunk declares {size} bytes uncompressed but holds {}",
                out.len()
            ),
        ));
    }
    Ok(out)
}

/// Most messages indexed in one bag or MCAP file (a 4 GB D435i recording
/// has about 10^5).
pub const MAX_MESSAGES: usize = 20_000_000;

/// Bytes a scan may decompress per byte of the file. A genuine recording's
/// chunks inflate 1 to 10 times (depth images of a room compress best); a
/// chunk of a few KB declaring hundreds of MB is what this stops.
pub const MAX_EXPANSION: u64 = 64;

/// What a scan may still decompress: [`MAX_EXPANSION`] times the file's
/// size, and always one chunk of [`MAX_CHUNK_BYTES`].
pub struct ScanBudget {
    left: u64,
    max: u64,
}

impl ScanBudget {
    /// The budget of a scan over a file of `len` bytes.
    pub fn for_file(len: u64) -> Self {
        let max = len.saturating_mul(MAX_EXPANSION).max(MAX_CHUNK_BYTES);
        Self { left: max, max }
    }

    /// Takes `size` bytes about to be decompressed, or refuses them.
    pub fn spend(&mut self, size: u64) -> Result<(), RecordingError> {
        self.left = self
            .left
            .checked_sub(size)
            .ok_or(RecordingError::TooLarge {
                what: "bytes decompressed while scanning",
                size: self.max - self.left + size,
                max: self.max,
            })?;
        Ok(())
    }
}

/// Drops the messages that repeat another's place (`place`: its chunk and
/// offset), as an index listing one message twice makes, then orders the
/// rest by `time`.
pub fn dedup_messages<T, P: Ord, K: Ord>(
    messages: &mut Vec<T>,
    place: impl Fn(&T) -> P,
    time: impl Fn(&T) -> K,
) {
    messages.sort_unstable_by_key(&place);
    messages.dedup_by(|a, b| place(a) == place(b));
    messages.sort_by_key(time);
}

/// An index's regions, met in file order, must not overlap: checks that the
/// region `start..end` begins at or after `*covered` (the end of the ones
/// before), then moves `*covered` to `end`. With it each byte of an index is
/// read once, so the messages listed are at most one per index entry's bytes.
pub fn claim_region(covered: &mut u64, start: u64, end: u64) -> Result<(), RecordingError> {
    if start < *covered {
        return Err(RecordingError::corrupt(
            start,
            format!("index region overlaps the one before it (which ends at byte {covered})"),
        ));
    }
    *covered = end;
    Ok(())
}

/// Adds `m` to a container's message index, refusing the one past [`MAX_MESSAGES`].
pub fn push_message<T>(messages: &mut Vec<T>, m: T) -> Result<(), RecordingError> {
    push_capped(messages, m, MAX_MESSAGES, "number of messages")
}

/// The warning of a scan that stopped at byte `pos` on `e`, keeping `kept` messages.
pub fn scan_stopped(pos: u64, e: &RecordingError, kept: usize) -> String {
    format!("reading stopped at byte {pos} ({e}); the {kept} messages before it are kept")
}

/// Decompressed chunks, least recently used dropped first, at most
/// [`CHUNK_CACHE_BYTES`] in total (the last chunk read is always kept).
#[derive(Default)]
pub struct ChunkCache {
    entries: Vec<(u32, Rc<Vec<u8>>)>,
}

impl ChunkCache {
    /// Chunk `chunk`, if it is held.
    pub fn get(&mut self, chunk: u32) -> Option<Rc<Vec<u8>>> {
        let i = self.entries.iter().position(|(c, _)| *c == chunk)?;
        let entry = self.entries.remove(i);
        let data = entry.1.clone();
        self.entries.push(entry);
        Some(data)
    }

    /// Holds `data` as chunk `chunk`, dropping the oldest beyond the cap.
    pub fn insert(&mut self, chunk: u32, data: Vec<u8>) -> Rc<Vec<u8>> {
        let data = Rc::new(data);
        self.entries.push((chunk, data.clone()));
        let mut total: usize = self.entries.iter().map(|(_, d)| d.len()).sum();
        while total > CHUNK_CACHE_BYTES && self.entries.len() > 1 {
            total -= self.entries.remove(0).1.len();
        }
        data
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn declared_size_is_checked_before_and_after() {
        assert!(matches!(
            decompress("lz4", MAX_CHUNK_BYTES + 1, &[0; 8], 5),
            Err(RecordingError::TooLarge { .. })
        ));
        assert!(decompress("none", 3, &[1, 2, 3], 0).is_ok());
        assert!(matches!(
            decompress("", 4, &[1, 2, 3], 0),
            Err(RecordingError::Corrupt { .. })
        ));
        assert!(matches!(
            decompress("brotli", 3, &[1, 2, 3], 0),
            Err(RecordingError::UnsupportedCompression { .. })
        ));
    }

    #[test]
    fn cache_keeps_the_newest_within_its_cap() {
        let mut c = ChunkCache::default();
        c.insert(1, vec![0; 8]);
        c.insert(2, vec![0; 8]);
        assert!(c.get(1).is_some() && c.get(2).is_some() && c.get(3).is_none());
        // Filled to the cap exactly: nothing is dropped.
        let half = CHUNK_CACHE_BYTES / 2;
        let mut c = ChunkCache::default();
        c.insert(1, vec![0; half - 8]);
        c.insert(2, vec![0; 8]);
        c.insert(3, vec![0; half]);
        assert!(c.get(1).is_some() && c.get(2).is_some() && c.get(3).is_some());
        // One byte more: the least recently used (1, as 2 and 3 were read
        // after it) goes, and only it.
        c.get(2);
        c.get(3);
        c.insert(4, vec![0; 1]);
        assert!(c.get(1).is_none());
        assert!(c.get(2).is_some() && c.get(3).is_some() && c.get(4).is_some());
        // A chunk alone above the cap is still kept (the last one read).
        c.insert(5, vec![0; CHUNK_CACHE_BYTES + 1]);
        assert!(c.get(5).is_some() && c.get(4).is_none());
    }

    #[test]
    fn a_chunk_of_exactly_the_largest_size_is_decompressed_not_refused() {
        // Declared at the cap: decompressed (and found short), not refused.
        assert!(matches!(
            decompress("lz4", MAX_CHUNK_BYTES, &[0; 8], 5),
            Err(RecordingError::Corrupt { .. })
        ));
    }

    #[test]
    fn a_stopped_scan_says_where_and_what_it_kept() {
        let e = RecordingError::corrupt(120, "broken");
        let w = scan_stopped(100, &e, 7);
        assert!(
            w.contains("byte 100") && w.contains("7 messages") && w.contains("broken"),
            "{w}"
        );
    }

    #[test]
    fn a_scan_decompresses_at_most_its_budget() {
        // A small file may always inflate one chunk of the largest size...
        let mut b = ScanBudget::for_file(1000);
        assert!(b.spend(100).is_ok());
        // The refusal reports all that the scan would have decompressed.
        assert!(matches!(
            b.spend(MAX_CHUNK_BYTES),
            Err(RecordingError::TooLarge { size, max, .. })
                if size == MAX_CHUNK_BYTES + 100 && max == MAX_CHUNK_BYTES
        ));
        assert!(b.spend(MAX_CHUNK_BYTES - 100).is_ok());
        assert!(matches!(b.spend(1), Err(RecordingError::TooLarge { .. })));
        // ...a large one MAX_EXPANSION times its size.
        let len = 100 * MAX_CHUNK_BYTES;
        let mut b = ScanBudget::for_file(len);
        assert!(b.spend(len * MAX_EXPANSION).is_ok());
        assert!(b.spend(1).is_err());
    }

    #[test]
    fn index_regions_may_touch_but_not_overlap() {
        let mut covered = 0;
        assert!(claim_region(&mut covered, 10, 20).is_ok());
        assert!(claim_region(&mut covered, 20, 30).is_ok());
        assert!(claim_region(&mut covered, 29, 40).is_err());
    }

    #[test]
    fn a_message_listed_twice_is_kept_once_in_time_order() {
        let mut m = vec![(5u64, 1u32, 10u64), (3, 0, 4), (5, 1, 10), (1, 2, 0)];
        dedup_messages(&mut m, |x| (x.1, x.2), |x| x.0);
        assert_eq!(m, [(1, 2, 0), (3, 0, 4), (5, 1, 10)]);
    }
}
