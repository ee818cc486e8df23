//! Where a sequence's files come from: a folder on disk, or files held in
//! memory (a browser's folder picker, an unpacked .zip).

use std::collections::BTreeMap;
use std::path::PathBuf;

use crate::error::SequenceError;

/// Largest single file read, bytes (a 1280x720 PNG is a few MB).
pub const MAX_FILE_BYTES: u64 = 64 * 1024 * 1024;

/// An error when a file of `len` bytes (named `path`) is above [`MAX_FILE_BYTES`].
pub(crate) fn check_file_size(path: impl Into<String>, len: u64) -> Result<(), SequenceError> {
    if len > MAX_FILE_BYTES {
        return Err(SequenceError::too_large(
            path,
            "file size in bytes",
            len,
            MAX_FILE_BYTES,
        ));
    }
    Ok(())
}

/// A tree of files addressed by `/`-separated paths relative to the sequence root.
pub trait Source {
    /// Names of the files directly inside folder `dir` ("" for the root), unsorted.
    fn list(&self, dir: &str) -> Result<Vec<String>, SequenceError>;
    /// `true` when `path` is a file.
    fn is_file(&self, path: &str) -> bool;
    /// `true` when `dir` is a folder.
    fn is_dir(&self, dir: &str) -> bool;
    /// The bytes of `path`.
    fn read(&self, path: &str) -> Result<Vec<u8>, SequenceError>;
    /// How to name `path` in messages.
    fn display(&self, path: &str) -> String;
}

/// A sequence folder on disk.
#[derive(Debug, Clone)]
pub struct FolderSource {
    root: PathBuf,
}

impl FolderSource {
    /// The folder at `root`.
    pub fn new(root: impl Into<PathBuf>) -> Self {
        Self { root: root.into() }
    }

    fn path(&self, rel: &str) -> PathBuf {
        if rel.is_empty() {
            self.root.clone()
        } else {
            self.root.join(rel)
        }
    }
}

impl Source for FolderSource {
    fn list(&self, dir: &str) -> Result<Vec<String>, SequenceError> {
        let p = self.path(dir);
        let io = |source| SequenceError::Io {
            path: p.display().to_string(),
            source,
        };
        let mut names = Vec::new();
        for entry in std::fs::read_dir(&p).map_err(io)? {
            let entry = entry.map_err(io)?;
            // Follows symbolic links: a folder of linked frames is a folder of frames.
            if std::fs::metadata(entry.path()).is_ok_and(|m| m.is_file()) {
                if let Some(name) = entry.file_name().to_str() {
                    names.push(name.to_string());
                }
            }
        }
        Ok(names)
    }

    fn is_file(&self, path: &str) -> bool {
        self.path(path).is_file()
    }

    fn is_dir(&self, dir: &str) -> bool {
        self.path(dir).is_dir()
    }

    fn read(&self, path: &str) -> Result<Vec<u8>, SequenceError> {
        let p = self.path(path);
        let io = |source| SequenceError::Io {
            path: p.display().to_string(),
            source,
        };
        let len = std::fs::metadata(&p).map_err(io)?.len();
        check_file_size(p.display().to_string(), len)?;
        std::fs::read(&p).map_err(io)
    }

    fn display(&self, path: &str) -> String {
        self.path(path).display().to_string()
    }
}

/// Files held in memory, keyed by relative path.
#[derive(Debug, Clone, Default)]
pub struct MemorySource {
    /// Name shown in messages.
    pub name: String,
    files: BTreeMap<String, Vec<u8>>,
}

impl MemorySource {
    /// An empty source called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        Self {
            name: name.into(),
            files: BTreeMap::new(),
        }
    }

    /// Adds a file. A common leading folder (the sequence folder's own name)
    /// is removed later by [`MemorySource::strip_common_root`].
    pub fn insert(&mut self, path: &str, bytes: Vec<u8>) {
        let clean: Vec<&str> = path
            .split(['/', '\\'])
            .filter(|s| !s.is_empty() && *s != ".")
            .collect();
        self.files.insert(clean.join("/"), bytes);
    }

    /// Every file path, sorted.
    pub fn paths(&self) -> impl Iterator<Item = &str> {
        self.files.keys().map(String::as_str)
    }

    /// Number of files.
    pub fn len(&self) -> usize {
        self.files.len()
    }

    /// `true` when there are no files.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// When every file sits under one top folder that is not itself part of
    /// the layout (`myseq/color/...`), drops that folder from every path.
    pub fn strip_common_root(&mut self) {
        let Some(root) = common_root(self.files.keys().map(String::as_str)) else {
            return;
        };
        let prefix = format!("{root}/");
        self.files = std::mem::take(&mut self.files)
            .into_iter()
            .map(|(k, v)| (k[prefix.len()..].to_string(), v))
            .collect();
    }
}

/// The folders every path sits under that are not part of a sequence's
/// layout (`myseq` in `myseq/color/0.jpg`, `a/b` when nested), or `None`.
/// Paths are `/`-separated and relative.
pub fn common_root<'a>(paths: impl IntoIterator<Item = &'a str>) -> Option<String> {
    let known = |s: &str| matches!(s, "color" | "rgb" | "image" | "depth") || s.ends_with(".json");
    let paths: Vec<Vec<&str>> = paths
        .into_iter()
        .map(|p| p.split('/').filter(|s| !s.is_empty()).collect())
        .collect();
    let mut depth = 0;
    while let Some(first) = paths.first().and_then(|p| p.get(depth)) {
        // A folder only: every path must go deeper than it.
        if known(first)
            || !paths
                .iter()
                .all(|p| p.len() > depth + 1 && p[depth] == *first)
        {
            break;
        }
        depth += 1;
    }
    (depth > 0).then(|| paths[0][..depth].join("/"))
}

impl Source for MemorySource {
    fn list(&self, dir: &str) -> Result<Vec<String>, SequenceError> {
        let prefix = if dir.is_empty() {
            String::new()
        } else {
            format!("{dir}/")
        };
        Ok(self
            .files
            .keys()
            .filter_map(|k| k.strip_prefix(&prefix))
            .filter(|rest| !rest.contains('/') && !rest.is_empty())
            .map(str::to_string)
            .collect())
    }

    fn is_file(&self, path: &str) -> bool {
        self.files.contains_key(path)
    }

    fn is_dir(&self, dir: &str) -> bool {
        let prefix = format!("{dir}/");
        self.files.keys().any(|k| k.starts_with(&prefix))
    }

    fn read(&self, path: &str) -> Result<Vec<u8>, SequenceError> {
        let bytes = self.files.get(path).ok_or_else(|| SequenceError::Missing {
            path: self.display(path),
            what: "file",
        })?;
        // The same rule as a folder's, whoever filled the source.
        check_file_size(self.display(path), bytes.len() as u64)?;
        Ok(bytes.clone())
    }

    fn display(&self, path: &str) -> String {
        if self.name.is_empty() {
            path.to_string()
        } else {
            format!("{}/{}", self.name, path)
        }
    }
}

impl Source for Box<dyn Source> {
    fn list(&self, dir: &str) -> Result<Vec<String>, SequenceError> {
        (**self).list(dir)
    }
    fn is_file(&self, path: &str) -> bool {
        (**self).is_file(path)
    }
    fn is_dir(&self, dir: &str) -> bool {
        (**self).is_dir(dir)
    }
    fn read(&self, path: &str) -> Result<Vec<u8>, SequenceError> {
        (**self).read(path)
    }
    fn display(&self, path: &str) -> String {
        (**self).display(path)
    }
}

/// `true` for a relative path that stays inside its folder: not empty, not
/// absolute (nor a Windows drive or UNC path), no `..` component.
pub fn is_inside_name(name: &str) -> bool {
    let parts: Vec<&str> = name.split(['/', '\\']).collect();
    !name.is_empty()
        && !name.starts_with(['/', '\\'])
        && !parts.first().is_some_and(|p| p.contains(':'))
        && !parts.contains(&"..")
        && parts.iter().any(|p| !p.is_empty() && *p != ".")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn memory_source_lists_one_level_and_strips_the_sequence_folder() {
        let mut m = MemorySource::new("drop");
        m.insert("seq/color/000001.jpg", vec![1]);
        m.insert("seq/color/000000.jpg", vec![0]);
        m.insert("seq/camera_intrinsic.json", vec![]);
        m.strip_common_root();
        let mut names = m.list("color").expect("list");
        names.sort();
        assert_eq!(names, ["000000.jpg", "000001.jpg"]);
        assert!(m.is_dir("color") && m.is_file("camera_intrinsic.json"));
        assert_eq!(m.read("color/000001.jpg").expect("read"), vec![1]);
    }

    #[test]
    fn memory_source_refuses_a_file_above_the_cap_as_a_folder_does() {
        let mut m = MemorySource::new("page");
        m.insert("color/0.png", vec![0; MAX_FILE_BYTES as usize + 1]);
        m.insert("color/1.png", vec![0; 8]);
        assert!(matches!(
            m.read("color/0.png"),
            Err(SequenceError::TooLarge { .. })
        ));
        assert!(m.read("color/1.png").is_ok());
    }

    #[test]
    fn common_root_is_the_folders_above_the_layout() {
        assert_eq!(
            common_root(["a/b/color/0.jpg", "a/b/dlo.json"]),
            Some("a/b".into())
        );
        assert_eq!(common_root(["color/0.jpg", "dlo.json"]), None);
        assert_eq!(common_root(["x/color/0.jpg", "y/color/0.jpg"]), None);
        // A file at the top: nothing is a folder of everything.
        assert_eq!(common_root(["x/color/0.jpg", "readme.txt"]), None);
        assert_eq!(common_root(["seq/notes.txt"]), Some("seq".into()));
        assert_eq!(common_root([]), None);
    }

    #[test]
    fn names_inside_the_folder_are_told_from_those_outside() {
        for ok in ["groundtruth.json", "gt/frames.json", "./gt.json"] {
            assert!(is_inside_name(ok), "{ok}");
        }
        for bad in [
            "/etc/passwd",
            "../gt.json",
            "a/../../b",
            "C:\\gt.json",
            "\\\\host\\x",
            "",
            ".",
        ] {
            assert!(!is_inside_name(bad), "{bad}");
        }
    }
}
