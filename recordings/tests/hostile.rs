//! Hostile files made from the genuine recordings of `tests/recordings`: a
//! few bytes of pages or index records changed or added so that a reader
//! trusting the file's structure would list the same data many times over.
//! Each test failed on the readers before they were bounded by the file.

use std::path::{Path, PathBuf};

use upetrack_recordings::store::Store;
use upetrack_recordings::{Recording, RecordingError, RecordingOptions};

fn fixture(name: &str) -> Vec<u8> {
    let path: PathBuf = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/recordings")
        .join(name);
    std::fs::read(path).expect("fixture exists")
}

fn be16(b: &[u8]) -> usize {
    usize::from(b[0]) << 8 | usize::from(b[1])
}

/// SQLite page `n` (1-based) of `db`, as a byte range.
fn page_range(db: &[u8], n: usize) -> std::ops::Range<usize> {
    let size = be16(&db[16..18]);
    (n - 1) * size..n * size
}

/// The `messages` table's root page of `librealsense.db3` (page 3: an
/// interior page over 15 leaves) and the page numbers of its children.
fn messages_root(db: &[u8]) -> (usize, Vec<usize>) {
    let root = 3;
    let p = &db[page_range(db, root)];
    assert_eq!(
        p[0], 0x05,
        "the fixture's messages root is an interior page"
    );
    let cells = be16(&p[3..5]);
    let mut children: Vec<usize> = (0..cells)
        .map(|i| {
            let c = be16(&p[12 + 2 * i..]);
            u32::from_be_bytes([p[c], p[c + 1], p[c + 2], p[c + 3]]) as usize
        })
        .collect();
    children.push(u32::from_be_bytes([p[8], p[9], p[10], p[11]]) as usize);
    (root, children)
}

fn corrupt_text(e: Result<Store<Vec<u8>>, RecordingError>) -> String {
    match e {
        Err(e @ RecordingError::Corrupt { .. }) => e.to_string(),
        Err(e) => panic!("another error: {e}"),
        Ok(s) => panic!("opened, with {} messages", s.messages.len()),
    }
}

#[test]
fn sqlite_btree_whose_parents_share_a_leaf_is_refused_not_listed_again() {
    let mut db = fixture("librealsense.db3");
    let (root, children) = messages_root(&db);
    // Every child pointer of the root made the first leaf.
    let first = (children[0] as u32).to_be_bytes();
    let range = page_range(&db, root);
    let p = &mut db[range];
    let cells = be16(&p[3..5]);
    for i in 0..cells {
        let c = be16(&p[12 + 2 * i..]);
        p[c..c + 4].copy_from_slice(&first);
    }
    p[8..12].copy_from_slice(&first);
    let text = corrupt_text(Store::open(db));
    assert!(text.contains("reached twice"), "{text}");
}

#[test]
fn sqlite_leaf_listing_one_cell_twice_is_refused() {
    let mut db = fixture("librealsense.db3");
    let (_, children) = messages_root(&db);
    let range = page_range(&db, children[0]);
    let p = &mut db[range];
    assert_eq!(p[0], 0x0d);
    assert!(be16(&p[3..5]) >= 2);
    // The second cell pointer made the first's.
    let (a, b) = (p[8], p[9]);
    p[10] = a;
    p[11] = b;
    let text = corrupt_text(Store::open(db));
    assert!(text.contains("rowid"), "{text}");
}

/// The ROS1 bag records from `pos` to the end: (start, end, op).
fn bag_records(bag: &[u8], mut pos: usize) -> Vec<(usize, usize, u8)> {
    let u32_at = |p: usize| u32::from_le_bytes([bag[p], bag[p + 1], bag[p + 2], bag[p + 3]]);
    let mut out = Vec::new();
    while pos < bag.len() {
        let header_len = u32_at(pos) as usize;
        let header = &bag[pos + 4..pos + 4 + header_len];
        let data_len = u32_at(pos + 4 + header_len) as usize;
        let end = pos + 8 + header_len + data_len;
        let mut op = 0;
        let mut h = 0;
        while h < header.len() {
            let n = u32::from_le_bytes([header[h], header[h + 1], header[h + 2], header[h + 3]])
                as usize;
            let field = &header[h + 4..h + 4 + n];
            if let Some(v) = field.strip_prefix(b"op=") {
                op = v[0];
            }
            h += 4 + n;
        }
        out.push((pos, end, op));
        pos = end;
    }
    out
}

#[test]
fn bag_index_listing_its_chunks_many_times_lists_each_message_once() {
    let genuine = fixture("ros_lz4.bag");
    let expected = Store::open(genuine.clone())
        .expect("genuine")
        .messages
        .len();
    // The index section (connections and chunk infos) is the file's tail:
    // its chunk-info records are appended again, a hundred times.
    let records = bag_records(&genuine, 13);
    let infos: Vec<u8> = records
        .iter()
        .filter(|r| r.2 == 0x06)
        .flat_map(|r| genuine[r.0..r.1].iter().copied())
        .collect();
    assert!(!infos.is_empty());
    let mut bag = genuine.clone();
    for _ in 0..100 {
        bag.extend_from_slice(&infos);
    }
    let store = Store::open(bag).expect("a repeated chunk info is read once");
    assert!(store.warnings().is_empty(), "{:?}", store.warnings());
    assert_eq!(store.messages.len(), expected);
}

fn u64_le(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// Where an MCAP file's footer starts (its opcode, length, summary start,
/// summary offset start and CRC; then the closing magic), and its summary's
/// records as (start, end, opcode).
fn mcap_summary(mcap: &[u8]) -> (usize, Vec<(usize, usize, u8)>) {
    let footer_at = mcap.len() - 8 - 29;
    assert_eq!(mcap[footer_at], 0x02);
    let mut pos = u64_le(mcap, footer_at + 9) as usize;
    let mut records = Vec::new();
    while pos < footer_at {
        let end = pos + 9 + u64_le(mcap, pos + 1) as usize;
        records.push((pos, end, mcap[pos]));
        pos = end;
    }
    (footer_at, records)
}

/// `mcap` with `extra` inserted just before its footer (inside the summary,
/// which the reader walks up to the footer).
fn mcap_with_summary_records(mcap: &[u8], extra: &[u8]) -> Vec<u8> {
    let (footer_at, _) = mcap_summary(mcap);
    [&mcap[..footer_at], extra, &mcap[footer_at..]].concat()
}

const MCAP_CHUNK_INDEX: u8 = 0x08;

#[test]
fn mcap_summary_listing_its_chunks_many_times_lists_each_message_once() {
    let genuine = fixture("ros2_png.mcap");
    let expected = Store::open(genuine.clone())
        .expect("genuine")
        .messages
        .len();
    let (_, records) = mcap_summary(&genuine);
    let indexes: Vec<u8> = records
        .iter()
        .filter(|r| r.2 == MCAP_CHUNK_INDEX)
        .flat_map(|r| genuine[r.0..r.1].iter().copied())
        .collect();
    assert!(!indexes.is_empty());
    // The chunk indexes repeated a hundred times just before the footer.
    let mcap = mcap_with_summary_records(&genuine, &indexes.repeat(100));
    let store = Store::open(mcap).expect("a repeated chunk index is read once");
    assert!(store.warnings().is_empty(), "{:?}", store.warnings());
    assert_eq!(store.messages.len(), expected);
}

#[test]
fn mcap_chunk_index_overlapping_the_one_before_is_refused_and_the_file_scanned() {
    // A second chunk index naming the first chunk one byte later and one byte
    // shorter: a different chunk by its offset, the same message index by its
    // end. The index's regions overlap, so the summary is refused and the file
    // scanned instead, which lists each message once.
    let genuine = fixture("ros2_png.mcap");
    let expected = Store::open(genuine.clone())
        .expect("genuine")
        .messages
        .len();
    let (_, records) = mcap_summary(&genuine);
    let (start, end, _) = *records
        .iter()
        .find(|r| r.2 == MCAP_CHUNK_INDEX)
        .expect("a chunk index");
    let index = &genuine[start..end];
    let mut shifted = index.to_vec();
    // Body: start time, end time, chunk offset, chunk length, ...
    let (at, len) = (u64_le(index, 9 + 16), u64_le(index, 9 + 24));
    shifted[9 + 16..9 + 24].copy_from_slice(&(at + 1).to_le_bytes());
    shifted[9 + 24..9 + 32].copy_from_slice(&(len - 1).to_le_bytes());
    let mcap = mcap_with_summary_records(&genuine, &shifted);
    let store = Store::open(mcap).expect("scanned");
    assert!(
        store.warnings().iter().any(|w| w.contains("overlaps")),
        "{:?}",
        store.warnings()
    );
    assert_eq!(store.messages.len(), expected);
}

#[test]
fn corrupt_chunk_is_an_error_naming_its_offset_not_a_panic() {
    let genuine = fixture("ros_lz4.bag");
    let chunks: Vec<(usize, usize, u8)> = bag_records(&genuine, 13)
        .into_iter()
        .filter(|r| r.2 == 0x05)
        .collect();
    assert!(chunks.len() >= 2, "{} chunks", chunks.len());
    // The middle of the last chunk's compressed data scribbled over (the
    // first holds the calibration, read on opening).
    let (start, end, _) = chunks[chunks.len() - 1];
    let mut bag = genuine.clone();
    let mid = (start + end) / 2;
    for b in &mut bag[mid..mid + 64] {
        *b ^= 0x5a;
    }
    // The index is intact: the bag opens, and the damage shows when the
    // frames of that chunk are read, as an error naming the chunk's offset.
    let mut rec = Recording::open(bag, &RecordingOptions::default()).expect("index intact");
    let mut errors = Vec::new();
    for i in 0..rec.len() {
        if let Err(e) = rec.frame(i) {
            errors.push(e);
        }
    }
    assert!(
        !errors.is_empty() && errors.len() < rec.len(),
        "{} errors",
        errors.len()
    );
    for e in &errors {
        assert!(
            matches!(e, RecordingError::Corrupt { offset, .. } if *offset == start as u64),
            "{e} (chunk at {start})"
        );
    }
}

/// A file of `len` bytes whose first bytes are `head` and the rest zeros,
/// never held: a cap on a size the file must contain is reached without
/// writing hundreds of MB.
struct Sparse {
    head: Vec<u8>,
    len: u64,
}

impl upetrack_recordings::ByteSource for Sparse {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
        upetrack_recordings::bytes::check_range(self.len, offset, buf.len())?;
        for (k, b) in buf.iter_mut().enumerate() {
            *b = usize::try_from(offset + k as u64)
                .ok()
                .and_then(|i| self.head.get(i))
                .copied()
                .unwrap_or(0);
        }
        Ok(())
    }
}

/// A ROS1 bag record: header fields `name=value`, then `data_len` and `data`.
fn bag_record(fields: &[(&str, &[u8])], data_len: u32, data: &[u8]) -> Vec<u8> {
    let mut header = Vec::new();
    for (name, value) in fields {
        let field = [name.as_bytes(), b"=", value].concat();
        header.extend((field.len() as u32).to_le_bytes());
        header.extend(field);
    }
    let mut out = (header.len() as u32).to_le_bytes().to_vec();
    out.extend(header);
    out.extend(data_len.to_le_bytes());
    out.extend(data);
    out
}

/// `#ROSBAG V2.0` and a bag header without an index (so the bag is scanned).
fn unindexed_bag() -> Vec<u8> {
    let mut bag = b"#ROSBAG V2.0\n".to_vec();
    bag.extend(bag_record(
        &[("op", &[0x03]), ("index_pos", &0u64.to_le_bytes())],
        0,
        &[],
    ));
    bag
}

fn too_large(e: Result<Store<Sparse>, RecordingError>) -> &'static str {
    match e {
        Err(RecordingError::TooLarge { what, .. }) => what,
        Err(e) => panic!("another error: {e}"),
        Ok(s) => panic!("opened, with {} messages", s.messages.len()),
    }
}

#[test]
fn bag_record_header_above_its_cap_is_refused_before_it_is_read() {
    let mut head = b"#ROSBAG V2.0\n".to_vec();
    let huge = upetrack_recordings::rosbag1::MAX_HEADER_BYTES + 1;
    head.extend(huge.to_le_bytes());
    let src = Sparse {
        head,
        len: 64 << 20,
    };
    assert!(too_large(Store::open(src)).contains("record header"));
}

#[test]
fn bag_chunk_above_its_cap_is_refused_before_it_is_read() {
    let mut head = unindexed_bag();
    let huge = upetrack_recordings::rosbag1::MAX_CHUNK_DATA_BYTES + 1;
    head.extend(bag_record(
        &[
            ("op", &[0x05]),
            ("compression", b"none"),
            ("size", &huge.to_le_bytes()),
        ],
        huge,
        &[],
    ));
    let len = head.len() as u64 + u64::from(huge);
    assert!(too_large(Store::open(Sparse { head, len })).contains("compressed chunk"));
}

#[test]
fn bag_with_more_connections_than_its_cap_is_refused() {
    let max = upetrack_recordings::rosbag1::MAX_CONNECTIONS as u32;
    // A connection's data is header fields too: its message type.
    let data = [&8u32.to_le_bytes()[..], b"type=a/B"].concat();
    let mut head = unindexed_bag();
    for id in 0..=max {
        head.extend(bag_record(
            &[
                ("op", &[0x07]),
                ("conn", &id.to_le_bytes()),
                ("topic", b"/t"),
            ],
            data.len() as u32,
            &data,
        ));
    }
    let len = head.len() as u64;
    assert!(too_large(Store::open(Sparse { head, len })).contains("connections"));
}

#[test]
fn mcap_summary_record_above_its_cap_is_refused_before_it_is_read() {
    let mut mcap = fixture("ros2_png.mcap");
    let (_, records) = mcap_summary(&mcap);
    let at = records[0].0 + 1;
    let huge = upetrack_recordings::mcap::MAX_RECORD_BYTES + 1;
    mcap[at..at + 8].copy_from_slice(&huge.to_le_bytes());
    let len = mcap.len() as u64;
    let e = Store::open(Sparse { head: mcap, len });
    assert!(too_large(e).contains("MCAP record"));
}

/// `librealsense.db3` with the `messages` root's children replaced by a
/// chain of `chain` interior pages (no cells, each the next's parent) over
/// the first leaf: that leaf then lies at depth `chain + 1`.
fn db3_with_chain(chain: usize) -> Vec<u8> {
    let mut db = fixture("librealsense.db3");
    let (root, children) = messages_root(&db);
    let size = page_range(&db, 1).len();
    let first_new = db.len() / size + 1;
    for k in 0..chain {
        let mut p = vec![0u8; size];
        p[0] = 0x05;
        let next = if k + 1 == chain {
            children[0]
        } else {
            first_new + k + 1
        };
        p[8..12].copy_from_slice(&(next as u32).to_be_bytes());
        db.extend(p);
    }
    let range = page_range(&db, root);
    let p = &mut db[range];
    p[3..5].copy_from_slice(&[0, 0]);
    p[8..12].copy_from_slice(&(first_new as u32).to_be_bytes());
    db
}

#[test]
fn sqlite_btree_deeper_than_any_real_one_is_refused() {
    let max = upetrack_recordings::sqlite::MAX_TREE_DEPTH;
    // A leaf at the deepest depth taken is read...
    let store = Store::open(db3_with_chain(max - 1)).expect("as deep as taken");
    assert!(!store.messages.is_empty());
    // ...one level deeper is refused.
    let text = corrupt_text(Store::open(db3_with_chain(max)));
    assert!(text.contains("deeper"), "{text}");
}

#[test]
fn sqlite_value_read_from_any_offset_equals_the_slice_of_the_whole() {
    use upetrack_recordings::sqlite::{column_names, Database, Value};
    let mut db = Database::open(fixture("librealsense.db3")).expect("opens");
    let (root, sql) = db
        .tables()
        .expect("schema")
        .into_iter()
        .find(|t| t.0 == "messages")
        .map(|t| (t.1, t.2))
        .expect("messages table");
    let data = column_names(&sql)
        .iter()
        .position(|c| c == "data")
        .expect("data column");
    // The longest blob: an image, over many overflow pages.
    let mut longest = None;
    db.for_each_row(root, |_, row| {
        if let Some(Value::Bytes { offset, len, .. }) = row.values.get(data).cloned() {
            if longest.as_ref().is_none_or(|(_, _, l)| len > *l) {
                longest = Some((row.at, offset, len));
            }
        }
        Ok(())
    })
    .expect("rows");
    let (at, offset, len) = longest.expect("a blob");
    assert!(len > 50_000, "{len} bytes");
    let whole = db.payload(at, offset, len).expect("whole");
    // Windows that start on the leaf, in the first overflow page, and far
    // down the chain (whose pages before it are skipped unread).
    for (from, n) in [(0u64, 10u64), (3000, 5000), (len / 2, 4000), (len - 7, 7)] {
        let part = db.payload(at, offset + from, n).expect("part");
        assert_eq!(
            part,
            whole[from as usize..(from + n) as usize],
            "from {from}"
        );
    }
    // `data` is the row's last column: a read past it runs past the payload.
    assert!(db.payload(at, offset + len - 1, 2).is_err());

    // The blob's overflow chain made a loop (its first overflow page naming
    // itself): refused, never read round and round.
    let mut bytes = fixture("librealsense.db3");
    let size = page_range(&bytes, 1).len();
    let cell = (at.page as usize - 1) * size + at.cell as usize;
    let varint = |b: &[u8], mut p: usize| {
        let mut v = 0u64;
        for _ in 0..9 {
            let x = b[p];
            p += 1;
            v = (v << 7) | u64::from(x & 0x7f);
            if x & 0x80 == 0 {
                break;
            }
        }
        (v, p)
    };
    let (total, p) = varint(&bytes, cell);
    let (_, start) = varint(&bytes, p);
    // SQLite's on-page share of a payload of `total` bytes (usable = page size here).
    let u = size as u64;
    let (x, m) = (u - 35, (u - 12) * 32 / 255 - 23);
    let k = m + (total - m) % (u - 4);
    let local = if k <= x { k } else { m } as usize;
    let ptr = start + local;
    let first = u32::from_be_bytes(bytes[ptr..ptr + 4].try_into().expect("4 bytes"));
    let first_at = (first as usize - 1) * size;
    bytes[first_at..first_at + 4].copy_from_slice(&first.to_be_bytes());
    let mut looped = Database::open(bytes).expect("opens");
    let e = looped.payload(at, offset, len).expect_err("a loop");
    assert!(e.to_string().contains("loops"), "{e}");
}

#[test]
fn sqlite_header_of_an_impossible_page_size_or_encoding_is_refused() {
    use upetrack_recordings::sqlite::Database;
    let genuine = fixture("librealsense.db3");
    let with = |at: usize, bytes: &[u8]| {
        let mut db = genuine.clone();
        db[at..at + bytes.len()].copy_from_slice(bytes);
        Database::open(db).err().map(|e| e.to_string())
    };
    assert!(with(16, &[0x10, 0x00]).is_none(), "4096: the fixture's own");
    for bad in [[0x03, 0xe8], [0x01, 0x00], [0x00, 0x00], [0xff, 0xff]] {
        let e = with(16, &bad).expect("refused");
        assert!(e.contains("page size"), "{bad:?}: {e}");
    }
    // Reserved space leaving fewer than 480 usable bytes of a 512-byte page.
    let mut small = genuine.clone();
    small[16..18].copy_from_slice(&[0x02, 0x00]);
    small[20] = 33;
    assert!(Database::open(small.clone()).is_err());
    small[20] = 32;
    assert!(Database::open(small).is_ok(), "480 usable bytes are enough");
    assert!(with(56, &[0, 0, 0, 2]).expect("UTF-16").contains("UTF-8"));
    assert!(with(56, &[0, 0, 0, 1]).is_none());
}
