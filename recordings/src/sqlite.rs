//! A read-only reader of SQLite database files, enough for rosbag2's `.db3`:
//! the header, table B-trees (interior and leaf pages), overflow chains and
//! the record format. It reads pages through a [`ByteSource`], so a
//! recording of several GB is never read whole: listing a table reads only
//! its B-tree pages and each row's on-page part; a row's overflow pages are
//! read when that row's value is asked for.

use crate::bytes::ByteSource;
use crate::error::RecordingError;

/// The first 16 bytes of every SQLite 3 database.
pub const MAGIC: &[u8] = b"SQLite format 3\0";
/// Deepest table B-tree followed (real ones are 3 to 5 levels deep).
pub const MAX_TREE_DEPTH: usize = 32;
/// Largest value read from a row, bytes.
pub const MAX_VALUE_BYTES: u64 = 256 << 20;
/// Most rows in the schema table (a rosbag2 database has 3 to 6 tables).
pub const MAX_SCHEMA_ROWS: usize = 4096;
/// Longest text read from the schema (a table's name or `CREATE` statement), bytes.
pub const MAX_SCHEMA_TEXT_BYTES: u64 = 64 << 10;

/// Pages seen in one traversal, one bit each (a 4 GB file of 4 KB pages: 128 KB).
struct PageSet(Vec<u64>);

impl PageSet {
    fn new(pages: u32) -> Self {
        Self(vec![0; pages as usize / 64 + 1])
    }

    /// Marks page `n`; `false` when it was marked already.
    fn insert(&mut self, n: u32) -> bool {
        let (word, bit) = (n as usize / 64, 1u64 << (n % 64));
        match self.0.get_mut(word) {
            Some(w) if *w & bit == 0 => {
                *w |= bit;
                true
            }
            _ => false,
        }
    }
}

/// `true` when `head` starts like a SQLite 3 database.
pub fn is_sqlite(head: &[u8]) -> bool {
    head.starts_with(MAGIC)
}

/// One column value of a record.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// NULL (and the rowid alias column, whose value is the rowid).
    Null,
    /// An integer.
    Int(i64),
    /// A float.
    Float(f64),
    /// Text or a blob not read yet: its place in the row's payload.
    Bytes {
        /// Offset in the payload.
        offset: u64,
        /// Length.
        len: u64,
        /// `true` for TEXT, `false` for BLOB.
        text: bool,
    },
}

/// Where a row is, to read its payload again later.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RowRef {
    /// The rowid.
    pub rowid: i64,
    /// The leaf page holding the cell (1-based).
    pub page: u32,
    /// Offset of the cell in that page.
    pub cell: u16,
}

/// A row as listed: its place and the values of its columns (from the
/// on-page part of the payload; values past it are read on demand).
#[derive(Debug, Clone, PartialEq)]
pub struct Row {
    /// Where it is.
    pub at: RowRef,
    /// Column values.
    pub values: Vec<Value>,
}

/// An open database.
pub struct Database<R: ByteSource> {
    src: R,
    page_size: u32,
    usable: u32,
    pages: u32,
}

fn be16(b: &[u8]) -> u32 {
    u32::from(b[0]) << 8 | u32::from(b[1])
}

fn be32(b: &[u8]) -> u32 {
    u32::from_be_bytes([b[0], b[1], b[2], b[3]])
}

/// A SQLite varint at `b[at..]`: its value and length.
fn varint(b: &[u8], at: usize, page_offset: u64) -> Result<(u64, usize), RecordingError> {
    let mut v: u64 = 0;
    for i in 0..9 {
        let byte = *b.get(at + i).ok_or_else(|| {
            RecordingError::corrupt(page_offset + at as u64, "varint runs past its page")
        })?;
        if i == 8 {
            return Ok(((v << 8) | u64::from(byte), 9));
        }
        v = (v << 7) | u64::from(byte & 0x7f);
        if byte & 0x80 == 0 {
            return Ok((v, i + 1));
        }
    }
    Ok((v, 9))
}

impl<R: ByteSource> Database<R> {
    /// Opens a database: reads and checks its header.
    pub fn open(mut src: R) -> Result<Self, RecordingError> {
        let mut head = [0u8; 100];
        src.read_at(0, &mut head)
            .map_err(|_| RecordingError::UnknownFormat {
                reason: "shorter than a SQLite header".into(),
            })?;
        if !is_sqlite(&head) {
            return Err(RecordingError::UnknownFormat {
                reason: "not a SQLite 3 database".into(),
            });
        }
        let page_size = match be16(&head[16..18]) {
            1 => 65_536,
            n if (512..=32_768).contains(&n) && n.is_power_of_two() => n,
            n => return Err(RecordingError::corrupt(16, format!("page size {n}"))),
        };
        let reserved = u32::from(head[20]);
        if reserved + 480 > page_size {
            return Err(RecordingError::corrupt(
                20,
                "reserved space leaves no usable page",
            ));
        }
        if be32(&head[56..60]) > 1 {
            return Err(RecordingError::corrupt(
                56,
                "text is not UTF-8 (UTF-16 databases are not read)",
            ));
        }
        let pages = (src.len() / u64::from(page_size)) as u32;
        Ok(Self {
            src,
            page_size,
            usable: page_size - reserved,
            pages,
        })
    }

    fn page(&mut self, n: u32) -> Result<Vec<u8>, RecordingError> {
        if n == 0 || n > self.pages {
            return Err(RecordingError::corrupt(
                0,
                format!("page {n} is outside the file's {} pages", self.pages),
            ));
        }
        let mut buf = vec![0u8; self.page_size as usize];
        self.src
            .read_at(u64::from(n - 1) * u64::from(self.page_size), &mut buf)?;
        Ok(buf)
    }

    fn page_offset(&self, n: u32) -> u64 {
        u64::from(n.saturating_sub(1)) * u64::from(self.page_size)
    }

    /// Bytes of a payload of `total` bytes kept on its leaf page.
    fn local_size(&self, total: u64) -> u64 {
        let u = u64::from(self.usable);
        let x = u - 35;
        if total <= x {
            return total;
        }
        let m = ((u - 12) * 32 / 255) - 23;
        let k = m + (total - m) % (u - 4);
        if k <= x {
            k
        } else {
            m
        }
    }

    /// Calls `each` with every row of the table whose B-tree root is `root`,
    /// in rowid order. The traversal is bounded by the file: a page reached
    /// twice (a loop, or two parents sharing a child) and rowids out of order
    /// (a cell listed twice) are errors, so no page is read twice and at most
    /// one row is listed per two bytes of leaf page.
    pub fn for_each_row(
        &mut self,
        root: u32,
        mut each: impl FnMut(&mut Self, Row) -> Result<(), RecordingError>,
    ) -> Result<(), RecordingError> {
        let mut visited = PageSet::new(self.pages);
        let mut last_rowid: Option<i64> = None;
        // Depth-first, children in key order: a stack of (page, depth).
        let mut stack = vec![(root, 0usize)];
        while let Some((n, depth)) = stack.pop() {
            if depth > MAX_TREE_DEPTH {
                return Err(RecordingError::corrupt(
                    self.page_offset(n),
                    "table B-tree deeper than any real one",
                ));
            }
            let page = self.page(n)?;
            let base = self.page_offset(n);
            if !visited.insert(n) {
                return Err(RecordingError::corrupt(
                    base,
                    format!("page {n} is reached twice in the B-tree of root page {root} (a loop or a shared page)"),
                ));
            }
            let h = if n == 1 { 100 } else { 0 };
            let kind = page[h];
            let cells = be16(&page[h + 3..h + 5]) as usize;
            let header = if kind == 0x05 { 12 } else { 8 };
            let ptrs = h + header;
            if ptrs + 2 * cells > page.len() {
                return Err(RecordingError::corrupt(base, "cell pointers past the page"));
            }
            let cell_at = |i: usize| be16(&page[ptrs + 2 * i..]) as usize;
            match kind {
                0x05 => {
                    let right = be32(&page[h + 8..h + 12]);
                    // Pushed in reverse, so the leftmost child is visited first.
                    stack.push((right, depth + 1));
                    for i in (0..cells).rev() {
                        let c = cell_at(i);
                        let child = page
                            .get(c..c + 4)
                            .map(be32)
                            .ok_or_else(|| RecordingError::corrupt(base, "cell past the page"))?;
                        stack.push((child, depth + 1));
                    }
                }
                0x0d => {
                    for i in 0..cells {
                        let row = self.leaf_row(&page, n, cell_at(i))?;
                        if last_rowid.is_some_and(|last| row.at.rowid <= last) {
                            return Err(RecordingError::corrupt(
                                base,
                                format!(
                                    "rowid {} follows rowid {} (a cell listed twice?)",
                                    row.at.rowid,
                                    last_rowid.unwrap_or_default()
                                ),
                            ));
                        }
                        last_rowid = Some(row.at.rowid);
                        each(self, row)?;
                    }
                }
                other => {
                    return Err(RecordingError::corrupt(
                        base,
                        format!("page type {other:#x} is not a table B-tree page"),
                    ))
                }
            }
        }
        Ok(())
    }

    /// The row of the leaf cell at offset `c` of `page` (number `n`).
    fn leaf_row(&self, page: &[u8], n: u32, c: usize) -> Result<Row, RecordingError> {
        let base = self.page_offset(n);
        let (total, a) = varint(page, c, base)?;
        let (rowid, b) = varint(page, c + a, base)?;
        let start = c + a + b;
        let local = self.local_size(total) as usize;
        let payload = page.get(start..start + local).ok_or_else(|| {
            RecordingError::corrupt(base + c as u64, "cell payload past the page")
        })?;
        let values = record_values(payload, total, base + start as u64)?;
        Ok(Row {
            at: RowRef {
                rowid: rowid as i64,
                page: n,
                cell: c as u16,
            },
            values,
        })
    }

    /// Bytes `offset..offset + len` of the payload of row `at`, following its
    /// overflow chain as far as needed.
    pub fn payload(
        &mut self,
        at: RowRef,
        offset: u64,
        len: u64,
    ) -> Result<Vec<u8>, RecordingError> {
        if len > MAX_VALUE_BYTES {
            return Err(RecordingError::TooLarge {
                what: "value in bytes",
                size: len,
                max: MAX_VALUE_BYTES,
            });
        }
        let page = self.page(at.page)?;
        let base = self.page_offset(at.page);
        let c = at.cell as usize;
        let (total, a) = varint(&page, c, base)?;
        let (_, b) = varint(&page, c + a, base)?;
        let end = offset
            .checked_add(len)
            .filter(|&e| e <= total)
            .ok_or_else(|| {
                RecordingError::corrupt(base + c as u64, "value runs past its row's payload")
            })?;
        let start = c + a + b;
        let local = self.local_size(total);
        let mut out = Vec::with_capacity(len as usize);
        // The on-page part.
        if offset < local {
            let from = start + offset as usize;
            let to = start + end.min(local) as usize;
            out.extend_from_slice(page.get(from..to).ok_or_else(|| {
                RecordingError::corrupt(base + c as u64, "cell payload past the page")
            })?);
        }
        if end <= local {
            return Ok(out);
        }
        // The overflow chain: each page a next-page number and usable - 4 bytes.
        let chunk = u64::from(self.usable) - 4;
        let next_at = start + local as usize;
        let mut next = page.get(next_at..next_at + 4).map(be32).ok_or_else(|| {
            RecordingError::corrupt(base + c as u64, "overflow pointer past the page")
        })?;
        let mut pos = local;
        // Each overflow page at most once: a chain that loops is corrupt.
        let mut seen = PageSet::new(self.pages);
        while pos < end {
            if next == 0 || !seen.insert(next) {
                return Err(RecordingError::corrupt(
                    base + c as u64,
                    "overflow chain ends early, leaves the file or loops",
                ));
            }
            let here = pos;
            pos += chunk;
            if pos <= offset {
                // Skipped without its bytes: only the next pointer is needed.
                let mut ptr = [0u8; 4];
                self.src.read_at(self.page_offset(next), &mut ptr)?;
                next = be32(&ptr);
                continue;
            }
            let p = self.page(next)?;
            next = be32(&p[..4]);
            let from = offset.saturating_sub(here) as usize;
            let to = (end.min(pos) - here) as usize;
            out.extend_from_slice(&p[4 + from..4 + to]);
        }
        Ok(out)
    }

    /// The text of value `v` of row `at`, refused when longer than `max` bytes.
    pub fn text(&mut self, at: RowRef, v: &Value, max: u64) -> Result<String, RecordingError> {
        match v {
            Value::Bytes { offset, len, .. } => {
                if *len > max {
                    return Err(RecordingError::TooLarge {
                        what: "text value in bytes",
                        size: *len,
                        max,
                    });
                }
                let b = self.payload(at, *offset, *len)?;
                String::from_utf8(b).map_err(|_| {
                    RecordingError::corrupt(self.page_offset(at.page), "text is not UTF-8")
                })
            }
            Value::Null => Ok(String::new()),
            Value::Int(i) => Ok(i.to_string()),
            Value::Float(f) => Ok(f.to_string()),
        }
    }

    /// The tables of the schema: name, root page and `CREATE TABLE` text.
    /// At most [`MAX_SCHEMA_ROWS`] rows, each text at most [`MAX_SCHEMA_TEXT_BYTES`].
    pub fn tables(&mut self) -> Result<Vec<(String, u32, String)>, RecordingError> {
        let mut out = Vec::new();
        let mut seen = 0usize;
        self.for_each_row(1, |db, row| {
            seen += 1;
            if seen > MAX_SCHEMA_ROWS {
                return Err(RecordingError::TooLarge {
                    what: "rows in the schema",
                    size: seen as u64,
                    max: MAX_SCHEMA_ROWS as u64,
                });
            }
            let [kind, name, _, root, sql] = row.values.as_slice() else {
                return Ok(());
            };
            if db.text(row.at, kind, MAX_SCHEMA_TEXT_BYTES)? != "table" {
                return Ok(());
            }
            let Value::Int(root) = root else {
                return Ok(());
            };
            let name = db.text(row.at, name, MAX_SCHEMA_TEXT_BYTES)?;
            let sql = db.text(row.at, sql, MAX_SCHEMA_TEXT_BYTES)?;
            out.push((name, u32::try_from(*root).unwrap_or(0), sql));
            Ok(())
        })?;
        Ok(out)
    }
}

/// The values of a record whose payload (`total` bytes) starts with `local`.
fn record_values(local: &[u8], total: u64, at: u64) -> Result<Vec<Value>, RecordingError> {
    let (header_len, mut p) = varint(local, 0, at)?;
    let header_len = header_len as usize;
    if header_len > local.len() {
        return Err(RecordingError::corrupt(
            at,
            "record header longer than the on-page payload",
        ));
    }
    let mut types = Vec::new();
    while p < header_len {
        let (t, n) = varint(local, p, at)?;
        types.push(t);
        p += n;
    }
    let mut offset = header_len as u64;
    let mut out = Vec::with_capacity(types.len());
    for t in types {
        let size: u64 = match t {
            0 | 8 | 9 => 0,
            1..=4 => t,
            5 => 6,
            6 | 7 => 8,
            10 | 11 => return Err(RecordingError::corrupt(at, "reserved serial type")),
            n => (n - 12) / 2,
        };
        let value_end = offset
            .checked_add(size)
            .filter(|&e| e <= total)
            .ok_or_else(|| RecordingError::corrupt(at, "record value past its payload"))?;
        let int = |local: &[u8]| -> Result<i64, RecordingError> {
            let b = local
                .get(offset as usize..value_end as usize)
                .ok_or_else(|| RecordingError::corrupt(at, "integer past the on-page payload"))?;
            let mut v: i64 = if b.first().is_some_and(|&x| x & 0x80 != 0) {
                -1
            } else {
                0
            };
            for &x in b {
                v = (v << 8) | i64::from(x);
            }
            Ok(v)
        };
        out.push(match t {
            0 => Value::Null,
            8 => Value::Int(0),
            9 => Value::Int(1),
            1..=6 => Value::Int(int(local)?),
            7 => Value::Float(f64::from_bits(int(local)? as u64)),
            n => Value::Bytes {
                offset,
                len: size,
                text: n % 2 == 1,
            },
        });
        offset = value_end;
    }
    Ok(out)
}

/// The column names of a `CREATE TABLE name(col TYPE ..., ...)` statement.
pub fn column_names(sql: &str) -> Vec<String> {
    let Some(open) = sql.find('(') else {
        return Vec::new();
    };
    let body = sql[open + 1..].trim_end().trim_end_matches(')');
    body.split(',')
        .filter_map(|col| col.split_whitespace().next())
        .map(|c| {
            c.trim_matches(|ch| ch == '"' || ch == '`' || ch == '[' || ch == ']')
                .to_string()
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn varints_of_one_to_nine_bytes() {
        assert_eq!(varint(&[0x05], 0, 0).ok(), Some((5, 1)));
        assert_eq!(varint(&[0x81, 0x00], 0, 0).ok(), Some((128, 2)));
        let nine = [0xff; 9];
        assert_eq!(varint(&nine, 0, 0).ok(), Some((u64::MAX, 9)));
        assert!(varint(&[0x81], 0, 0).is_err());
        // Read where it starts, not from the page's start.
        assert_eq!(varint(&[0x7f, 0x82, 0x01], 1, 0).ok(), Some((257, 2)));
    }

    #[test]
    fn record_of_null_int_text_and_blob() {
        // Header: 5 bytes (len, NULL, int8, text of 2, blob of 3).
        let rec = [5u8, 0, 1, 17, 18, 0xfe, b'h', b'i', 1, 2, 3];
        let v = record_values(&rec, rec.len() as u64, 0).expect("record");
        assert_eq!(v[0], Value::Null);
        assert_eq!(v[1], Value::Int(-2));
        assert_eq!(
            v[2],
            Value::Bytes {
                offset: 6,
                len: 2,
                text: true
            }
        );
        assert_eq!(
            v[3],
            Value::Bytes {
                offset: 8,
                len: 3,
                text: false
            }
        );
    }

    #[test]
    fn column_names_of_rosbag2_tables() {
        let sql = "CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL, data BLOB NOT NULL)";
        assert_eq!(column_names(sql), ["id", "topic_id", "timestamp", "data"]);
        // Names quoted in each of SQLite's ways.
        let quoted = "CREATE TABLE t(\"a\" INTEGER, `b` TEXT, [c] BLOB, d)";
        assert_eq!(column_names(quoted), ["a", "b", "c", "d"]);
    }

    #[test]
    fn payload_split_between_page_and_overflow() {
        // SQLite's own thresholds for 4096-byte pages: 4061 bytes fit on the page.
        let db = Database {
            src: Vec::new(),
            page_size: 4096,
            usable: 4096,
            pages: 0,
        };
        assert_eq!(db.local_size(4061), 4061);
        // One byte more: the minimum (489) stays, as K = 4062 would not fit.
        assert_eq!(db.local_size(4062), 489);
        // K = M + (P - M) mod (U - 4) fits: 1792 bytes on the page.
        assert_eq!(db.local_size(100_000), 1792);
    }

    #[test]
    fn a_value_above_its_cap_is_refused_before_a_page_is_read() {
        // No pages at all: only the caps can answer.
        let mut db = Database {
            src: Vec::new(),
            page_size: 4096,
            usable: 4096,
            pages: 0,
        };
        let at = RowRef {
            rowid: 1,
            page: 1,
            cell: 0,
        };
        assert!(matches!(
            db.payload(at, 0, MAX_VALUE_BYTES + 1),
            Err(RecordingError::TooLarge { .. })
        ));
        let name = Value::Bytes {
            offset: 0,
            len: MAX_SCHEMA_TEXT_BYTES + 1,
            text: true,
        };
        assert!(matches!(
            db.text(at, &name, MAX_SCHEMA_TEXT_BYTES),
            Err(RecordingError::TooLarge { .. })
        ));
        // At the cap, the page is read (and here is missing).
        assert!(matches!(
            db.payload(at, 0, MAX_VALUE_BYTES),
            Err(RecordingError::Corrupt { .. })
        ));
        let at_cap = Value::Bytes {
            offset: 0,
            len: MAX_SCHEMA_TEXT_BYTES,
            text: true,
        };
        assert!(matches!(
            db.text(at, &at_cap, MAX_SCHEMA_TEXT_BYTES),
            Err(RecordingError::Corrupt { .. })
        ));
    }

    #[test]
    fn a_page_set_marks_each_page_once() {
        let mut s = PageSet::new(100);
        assert!(s.insert(1) && s.insert(64) && s.insert(100));
        assert!(!s.insert(64));
        assert!(!s.insert(1_000), "a page past the file is never new");
    }
}
