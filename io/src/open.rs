//! Opening what a user names on the command line: a sequence folder or a
//! `.zip` of one, as a [`Source`]. The one place that knows every kind of
//! input, so neither the folder reader nor the archive needs the other.

use crate::archive;
use crate::error::SequenceError;
use crate::source::{FolderSource, Source};

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
    if !archive::is_zip(&bytes) {
        return Err(SequenceError::invalid(
            &shown,
            "not a sequence folder or a .zip (a sequence has camera_intrinsic.json, color/ and depth/)",
        ));
    }
    Ok(Box::new(archive::unpack_zip(&bytes, &shown)?))
}
