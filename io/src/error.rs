//! The error of everything that reads or writes sequences: each variant
//! names the file and the problem.

/// A sequence, image or JSON file that cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum SequenceError {
    /// A file or folder is missing.
    #[error("{path}: not found ({what})")]
    Missing {
        /// Where it was looked for.
        path: String,
        /// What it should have been.
        what: &'static str,
    },
    /// The operating system refused a read or write.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The underlying error.
        source: std::io::Error,
    },
    /// A JSON file does not parse or has wrong types.
    #[error("{path}: invalid JSON: {message}")]
    Json {
        /// The file.
        path: String,
        /// What serde_json said.
        message: String,
    },
    /// A value in a file is out of range or contradicts another.
    #[error("{path}: {message}")]
    Invalid {
        /// The file.
        path: String,
        /// What is wrong.
        message: String,
    },
    /// An image file cannot be decoded.
    #[error("{path}: cannot decode image: {message}")]
    Decode {
        /// The file.
        path: String,
        /// What the decoder said.
        message: String,
    },
    /// A camera recording (.bag) that cannot be read.
    #[error("{path}: {source}")]
    Recording {
        /// The recording.
        path: String,
        /// What the recording reader said.
        source: upetrack_recordings::RecordingError,
    },
    /// A size cap was exceeded.
    #[error("{path}: {what} is {actual}, above the limit of {limit}")]
    TooLarge {
        /// The file or folder.
        path: String,
        /// What was measured.
        what: &'static str,
        /// The value found.
        actual: u64,
        /// The cap.
        limit: u64,
    },
}

impl SequenceError {
    pub(crate) fn too_large(
        path: impl Into<String>,
        what: &'static str,
        actual: u64,
        limit: u64,
    ) -> Self {
        Self::TooLarge {
            path: path.into(),
            what,
            actual,
            limit,
        }
    }

    pub(crate) fn invalid(path: &str, message: impl Into<String>) -> Self {
        Self::Invalid {
            path: path.to_string(),
            message: message.into(),
        }
    }
}
