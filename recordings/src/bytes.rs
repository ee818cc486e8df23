//! Random access to a recording's bytes: a file that is seeked, never read
//! whole, or bytes already in memory (tests, fuzzing, a browser's slice reader).

use std::io::{Read, Seek, SeekFrom};

use crate::error::RecordingError;

/// Bytes addressed by offset. Implemented for files and byte buffers; the page
/// implements it over `Blob.slice`.
pub trait ByteSource {
    /// Total length in bytes.
    fn len(&self) -> u64;
    /// `true` when there are no bytes.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Fills `buf` from `offset`; an error when fewer bytes remain.
    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError>;
}

impl<T: ByteSource + ?Sized> ByteSource for Box<T> {
    fn len(&self) -> u64 {
        (**self).len()
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
        (**self).read_at(offset, buf)
    }
}

/// A file on disk, read by seeking.
#[derive(Debug)]
pub struct FileBytes {
    file: std::fs::File,
    len: u64,
    name: String,
}

impl FileBytes {
    /// Opens `path` for reading.
    pub fn open(path: &std::path::Path) -> Result<Self, RecordingError> {
        let name = path.display().to_string();
        let io = |source| RecordingError::Io {
            what: name.clone(),
            source,
        };
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        Ok(Self { file, len, name })
    }
}

impl ByteSource for FileBytes {
    fn len(&self) -> u64 {
        self.len
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
        check_range(self.len, offset, buf.len())?;
        let name = &self.name;
        let io = |source| RecordingError::Io {
            what: name.clone(),
            source,
        };
        self.file.seek(SeekFrom::Start(offset)).map_err(io)?;
        self.file.read_exact(buf).map_err(io)
    }
}

impl ByteSource for Vec<u8> {
    fn len(&self) -> u64 {
        self.as_slice().len() as u64
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
        read_slice(self, offset, buf)
    }
}

impl ByteSource for &[u8] {
    fn len(&self) -> u64 {
        <[u8]>::len(self) as u64
    }

    fn read_at(&mut self, offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
        read_slice(self, offset, buf)
    }
}

fn read_slice(bytes: &[u8], offset: u64, buf: &mut [u8]) -> Result<(), RecordingError> {
    check_range(bytes.len() as u64, offset, buf.len())?;
    // In range after the check, so the conversions and the slice cannot fail.
    let start = offset as usize;
    buf.copy_from_slice(&bytes[start..start + buf.len()]);
    Ok(())
}

/// An error unless `len` bytes from `offset` lie inside a source of `total` bytes.
pub fn check_range(total: u64, offset: u64, len: usize) -> Result<(), RecordingError> {
    match offset.checked_add(len as u64) {
        Some(end) if end <= total => Ok(()),
        _ => Err(RecordingError::Truncated {
            offset,
            what: format!("{len} bytes wanted, the file has {total}"),
        }),
    }
}

/// A little-endian reader over a byte slice, for ROS1 records and messages.
/// Every read is bounds-checked; `base` is the slice's offset in the file, for messages.
#[derive(Debug, Clone)]
pub struct Cursor<'a> {
    bytes: &'a [u8],
    pos: usize,
    base: u64,
}

impl<'a> Cursor<'a> {
    /// A cursor at the start of `bytes`, which begin at file offset `base`.
    pub fn new(bytes: &'a [u8], base: u64) -> Self {
        Self {
            bytes,
            pos: 0,
            base,
        }
    }

    /// Bytes not yet read.
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.pos
    }

    /// File offset of the next byte.
    pub fn offset(&self) -> u64 {
        self.base + self.pos as u64
    }

    /// The next `n` bytes.
    pub fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], RecordingError> {
        if n > self.remaining() {
            return Err(RecordingError::Truncated {
                offset: self.offset(),
                what: format!("{what}: {n} bytes wanted, {} left", self.remaining()),
            });
        }
        let out = &self.bytes[self.pos..self.pos + n];
        self.pos += n;
        Ok(out)
    }

    /// One byte.
    pub fn u8(&mut self, what: &str) -> Result<u8, RecordingError> {
        Ok(self.take(1, what)?[0])
    }

    /// A little-endian `u16`.
    pub fn u16(&mut self, what: &str) -> Result<u16, RecordingError> {
        let b = self.take(2, what)?;
        Ok(u16::from_le_bytes([b[0], b[1]]))
    }

    /// A little-endian `u32`.
    pub fn u32(&mut self, what: &str) -> Result<u32, RecordingError> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A little-endian `u64`.
    pub fn u64(&mut self, what: &str) -> Result<u64, RecordingError> {
        let lo = u64::from(self.u32(what)?);
        let hi = u64::from(self.u32(what)?);
        Ok(lo | (hi << 32))
    }

    /// A little-endian `f32`.
    pub fn f32(&mut self, what: &str) -> Result<f32, RecordingError> {
        Ok(f32::from_bits(self.u32(what)?))
    }

    /// A little-endian `f64`.
    pub fn f64(&mut self, what: &str) -> Result<f64, RecordingError> {
        Ok(f64::from_bits(self.u64(what)?))
    }

    /// A `u32`-length-prefixed byte array.
    pub fn bytes(&mut self, what: &str) -> Result<&'a [u8], RecordingError> {
        let n = self.u32(what)? as usize;
        self.take(n, what)
    }

    /// A `u32`-length-prefixed UTF-8 string.
    pub fn string(&mut self, what: &str) -> Result<String, RecordingError> {
        let offset = self.offset();
        let b = self.bytes(what)?;
        String::from_utf8(b.to_vec())
            .map_err(|_| RecordingError::corrupt(offset, format!("{what}: not UTF-8")))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cursor_reads_little_endian_and_refuses_past_the_end() {
        let bytes = [1u8, 0, 0, 0, 2, 0, 0, 0, 0, 0, 0, 0, 3];
        let mut c = Cursor::new(&bytes, 100);
        assert_eq!(c.u32("a").ok(), Some(1));
        assert_eq!(c.u64("b").ok(), Some(2));
        assert_eq!(c.offset(), 112);
        assert_eq!(c.u8("c").ok(), Some(3));
        assert!(matches!(
            c.u32("d"),
            Err(RecordingError::Truncated { offset: 113, .. })
        ));
    }

    #[test]
    fn length_prefix_past_the_end_is_truncation_not_allocation() {
        let bytes = [0xff, 0xff, 0xff, 0xff, b'x'];
        assert!(matches!(
            Cursor::new(&bytes, 0).bytes("data"),
            Err(RecordingError::Truncated { .. })
        ));
    }

    #[test]
    fn slice_source_checks_its_range() {
        let mut src: &[u8] = &[1, 2, 3];
        let mut buf = [0u8; 2];
        assert!(src.read_at(1, &mut buf).is_ok());
        assert_eq!(buf, [2, 3]);
        assert!(src.read_at(2, &mut buf).is_err());
        assert!(src.read_at(u64::MAX, &mut buf).is_err());
    }
}
