//! Opening what a user names on the command line: a sequence folder or a
//! `.zip` of one, as a [`Source`]. The one place that knows every kind of
//! input, so neither the folder reader nor the archive needs the other.

use crate::archive;
use crate::error::SequenceError;
use crate::source::{FolderSource, Source};

/// Bytes of a file's start that tell its kind.
pub const HEAD_BYTES: usize = 16;

/// What a single file given as input is, told by its first bytes (never by
/// its name): the page and the command share this rule.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InputKind {
    /// A camera recording the readers take (ROS1 bag 2.0, rosbag2 `.db3`, MCAP).
    Recording,
    /// A `.zip`, of a sequence folder.
    Zip,
    /// Anything else, named for messages ("a JPEG image").
    Other(&'static str),
}

/// The kind of a file starting with `head` (its first [`HEAD_BYTES`] or all of it).
pub fn input_kind(head: &[u8]) -> InputKind {
    if upetrack_recordings::is_recording(head) {
        return InputKind::Recording;
    }
    if archive::is_zip(head) {
        return InputKind::Zip;
    }
    let text_start = head.iter().find(|b| !b.is_ascii_whitespace());
    InputKind::Other(match head {
        [] => "an empty file",
        [0xff, 0xd8, 0xff, ..] => "a JPEG image",
        [0x89, b'P', b'N', b'G', ..] => "a PNG image",
        [0x1f, 0x8b, ..] => "a gzip file (unpack it first)",
        _ if head.starts_with(b"#ROSBAG V1.2") => "a ROS1 bag of format 1.2 (only 2.0 is read)",
        _ if matches!(text_start, Some(b'{' | b'[')) => "a JSON file",
        _ => "a file of no kind this reader knows",
    })
}

/// [`input_kind`] of the file at `path` (an unreadable file reads as empty).
pub fn input_kind_of_file(path: &std::path::Path) -> InputKind {
    use std::io::Read;
    let mut head = [0u8; HEAD_BYTES];
    let n = std::fs::File::open(path)
        .and_then(|mut f| f.read(&mut head))
        .unwrap_or(0);
    input_kind(&head[..n])
}

/// Opens a sequence folder, or a .zip of one, as a source.
pub fn open_path(path: &std::path::Path) -> Result<Box<dyn Source>, SequenceError> {
    let shown = path.display().to_string();
    if path.is_dir() {
        return Ok(Box::new(FolderSource::new(path)));
    }
    if !path.exists() {
        return Err(SequenceError::Missing {
            path: shown,
            what: "sequence folder or .zip",
        });
    }
    let len = std::fs::metadata(path)
        .map_err(|source| SequenceError::Io {
            path: shown.clone(),
            source,
        })?
        .len();
    if len > archive::MAX_ARCHIVE_BYTES {
        return Err(SequenceError::too_large(
            shown,
            "archive size in bytes",
            len,
            archive::MAX_ARCHIVE_BYTES,
        ));
    }
    let bytes = std::fs::read(path).map_err(|source| SequenceError::Io {
        path: shown.clone(),
        source,
    })?;
    if let InputKind::Other(what) = input_kind(&bytes) {
        return Err(SequenceError::invalid(
            &shown,
            format!("{what}, not a sequence folder, a .zip of one or a recording (a sequence has camera_intrinsic.json, color/ and depth/)"),
        ));
    }
    Ok(Box::new(archive::unpack_zip(&bytes, &shown)?))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_named_for_what_its_bytes_say() {
        assert_eq!(input_kind(b"#ROSBAG V2.0\n"), InputKind::Recording);
        assert_eq!(input_kind(b"SQLite format 3\0"), InputKind::Recording);
        assert_eq!(input_kind(b"\x89MCAP0\r\n"), InputKind::Recording);
        assert_eq!(input_kind(b"PK\x03\x04rest"), InputKind::Zip);
        assert_eq!(input_kind(b""), InputKind::Other("an empty file"));
        assert!(
            matches!(input_kind(&[0xff, 0xd8, 0xff, 0xe0]), InputKind::Other(w) if w.contains("JPEG"))
        );
        assert!(matches!(input_kind(b"\x89PNG\r\n"), InputKind::Other(w) if w.contains("PNG")));
        assert!(matches!(input_kind(b"#ROSBAG V1.2\n"), InputKind::Other(w) if w.contains("1.2")));
        assert!(matches!(input_kind(b"  {\"a\": 1}"), InputKind::Other(w) if w.contains("JSON")));
        assert!(matches!(input_kind(b"hello"), InputKind::Other(w) if w.contains("no kind")));
        assert!(matches!(input_kind(&[0x1f, 0x8b, 8]), InputKind::Other(w) if w.contains("gzip")));
    }
}
