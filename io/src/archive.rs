//! Sequences packed as a .zip: unpacked into a [`MemorySource`], with caps
//! checked before anything large is allocated and unsafe names refused.

use std::io::Read;

use crate::error::SequenceError;
use crate::source::{check_file_size, is_inside_name, MemorySource};

/// Most entries accepted in one archive.
pub const MAX_ARCHIVE_ENTRIES: usize = 200_000;
/// Most bytes accepted once unpacked (the sum of the declared sizes).
pub const MAX_ARCHIVE_BYTES: u64 = 2 * 1024 * 1024 * 1024;
/// Largest unpacked/packed ratio accepted for one entry (zip-bomb guard).
pub const MAX_COMPRESSION_RATIO: u64 = 1000;

/// `true` when the bytes start like a zip archive.
pub fn is_zip(bytes: &[u8]) -> bool {
    bytes.starts_with(b"PK\x03\x04") || bytes.starts_with(b"PK\x05\x06")
}

/// Unpacks `bytes` (a .zip named `name` in messages) into memory. Folders,
/// and names with `..`, absolute paths or drive letters are refused; the
/// common top folder, if any, is removed.
pub fn unpack_zip(bytes: &[u8], name: &str) -> Result<MemorySource, SequenceError> {
    let invalid = |m: String| SequenceError::invalid(name, m);
    if !is_zip(bytes) {
        return Err(invalid("not a zip archive".into()));
    }
    let mut archive = zip::ZipArchive::new(std::io::Cursor::new(bytes))
        .map_err(|e| invalid(format!("not a readable zip archive: {e}")))?;
    if archive.len() > MAX_ARCHIVE_ENTRIES {
        return Err(SequenceError::too_large(
            name.to_string(),
            "number of archive entries",
            archive.len() as u64,
            MAX_ARCHIVE_ENTRIES as u64,
        ));
    }
    // Declared sizes first: nothing is unpacked if the total is too large.
    let mut total = 0u64;
    for i in 0..archive.len() {
        let entry = archive
            .by_index_raw(i)
            .map_err(|e| invalid(format!("entry {i}: {e}")))?;
        total = total.saturating_add(entry.size());
        check_file_size(format!("{name}/{}", entry.name()), entry.size())?;
        if entry.compressed_size() > 0
            && entry.size() / entry.compressed_size().max(1) > MAX_COMPRESSION_RATIO
        {
            return Err(invalid(format!(
                "entry `{}` claims {} bytes from {} (ratio above {MAX_COMPRESSION_RATIO}): refused as a zip bomb",
                entry.name(),
                entry.size(),
                entry.compressed_size()
            )));
        }
    }
    if total > MAX_ARCHIVE_BYTES {
        return Err(SequenceError::too_large(
            name.to_string(),
            "unpacked size in bytes",
            total,
            MAX_ARCHIVE_BYTES,
        ));
    }
    let mut source = MemorySource::new(name);
    for i in 0..archive.len() {
        let mut entry = archive
            .by_index(i)
            .map_err(|e| invalid(format!("entry {i}: {e}")))?;
        if entry.is_dir() {
            continue;
        }
        let raw_name = entry.name().to_string();
        if !is_inside_name(&raw_name) {
            return Err(invalid(format!(
                "entry `{raw_name}` points outside the archive: refused"
            )));
        }
        let declared = entry.size();
        let mut data = Vec::with_capacity(declared.min(64 * 1024 * 1024) as usize);
        (&mut entry)
            .take(declared + 1)
            .read_to_end(&mut data)
            .map_err(|e| invalid(format!("entry `{raw_name}`: {e}")))?;
        if data.len() as u64 != declared {
            return Err(invalid(format!(
                "entry `{raw_name}` is not the size its header declares"
            )));
        }
        source.insert(&raw_name, data);
    }
    if source.is_empty() {
        return Err(invalid("the archive holds no files".into()));
    }
    source.strip_common_root();
    Ok(source)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    fn zip_of(entries: &[(&str, &[u8])]) -> Vec<u8> {
        let mut buf = std::io::Cursor::new(Vec::new());
        {
            let mut w = zip::ZipWriter::new(&mut buf);
            let opts: zip::write::SimpleFileOptions = zip::write::SimpleFileOptions::default()
                .compression_method(zip::CompressionMethod::Deflated);
            for (name, data) in entries {
                w.start_file(*name, opts).expect("start");
                w.write_all(data).expect("write");
            }
            w.finish().expect("finish");
        }
        buf.into_inner()
    }

    #[test]
    fn unpacks_and_strips_the_sequence_folder() {
        let z = zip_of(&[
            ("seq/camera_intrinsic.json", b"{}"),
            ("seq/color/0.png", b"x"),
        ]);
        let s = unpack_zip(&z, "seq.zip").expect("unpack");
        use crate::source::Source;
        assert!(s.is_file("camera_intrinsic.json") && s.is_file("color/0.png"));
    }

    #[test]
    fn path_traversal_and_non_zip_are_refused() {
        let z = zip_of(&[("../evil.json", b"{}")]);
        let e = unpack_zip(&z, "evil.zip").expect_err("refused").to_string();
        assert!(e.contains("evil.zip") && e.contains("outside"), "{e}");
        let e = unpack_zip(b"hello", "x.zip")
            .expect_err("refused")
            .to_string();
        assert!(e.contains("not a zip"), "{e}");
        let e = unpack_zip(b"PK\x03\x04garbage", "y.zip")
            .expect_err("refused")
            .to_string();
        assert!(e.contains("y.zip"), "{e}");
    }

    #[test]
    fn highly_compressed_entries_are_refused_as_bombs() {
        let zeros = vec![0u8; 5_000_000];
        let z = zip_of(&[("big.bin", &zeros)]);
        let e = unpack_zip(&z, "bomb.zip").expect_err("refused").to_string();
        assert!(e.contains("zip bomb"), "{e}");
    }

    #[test]
    fn an_entry_above_the_file_cap_is_refused_before_it_is_unpacked() {
        // Stored, so no ratio rule applies: only the per-file cap can refuse it.
        let big = vec![7u8; crate::source::MAX_FILE_BYTES as usize + 1];
        let mut buf = std::io::Cursor::new(Vec::new());
        {
            let mut w = zip::ZipWriter::new(&mut buf);
            let opts = zip::write::SimpleFileOptions::default()
                .compression_method(zip::CompressionMethod::Stored)
                .large_file(false);
            w.start_file("seq/color/0.png", opts).expect("start");
            w.write_all(&big).expect("write");
            w.finish().expect("finish");
        }
        let e = unpack_zip(buf.get_ref(), "big.zip").expect_err("refused");
        assert!(
            matches!(e, SequenceError::TooLarge { ref path, .. } if path.contains("color/0.png")),
            "{e}"
        );
    }
}
