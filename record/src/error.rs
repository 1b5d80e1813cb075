//! Typed errors of the recording reader and writer.

use std::path::PathBuf;

/// Anything that can go wrong reading or writing a recording.
#[derive(Debug, thiserror::Error)]
pub enum RecordError {
    /// An I/O error on a file.
    #[error("{path}: {cause}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The cause (shown in the message, so not also exposed as the error source).
        cause: std::io::Error,
    },
    /// A JSON document or JSON line that does not parse.
    #[error("{path}:{line}: {cause}")]
    Json {
        /// The file.
        path: PathBuf,
        /// 1-based line number (1 for whole-file JSON).
        line: usize,
        /// The cause (shown in the message, so not also exposed as the error source).
        cause: serde_json::Error,
    },
    /// `meta.json` is not a FIRES recording.
    #[error("{path}: format is {found:?}, expected \"fires-recording\"")]
    NotARecording {
        /// The file.
        path: PathBuf,
        /// The `format` value found.
        found: String,
    },
    /// The format version is not `MAJOR.MINOR` or has a major this reader does not know.
    #[error(
        "{path}: unsupported format version {found:?} (this reader reads major {supported_major})"
    )]
    UnsupportedVersion {
        /// The file.
        path: PathBuf,
        /// The version found.
        found: String,
        /// The major version supported.
        supported_major: u32,
    },
    /// `link.bin` ends inside a record.
    #[error("{path}: truncated record at byte offset {offset}")]
    LinkTruncated {
        /// The file.
        path: PathBuf,
        /// Offset of the record's start.
        offset: u64,
    },
    /// A `link.bin` record declares an implausible length.
    #[error("{path}: record at byte offset {offset} declares {len} bytes (limit {limit})")]
    LinkRecordTooLong {
        /// The file.
        path: PathBuf,
        /// Offset of the record's start.
        offset: u64,
        /// Declared length.
        len: u32,
        /// Largest accepted length.
        limit: u32,
    },
    /// A `link.bin` record whose time is before the previous record's (times never decrease).
    #[error("{path}: record at byte offset {offset} has time {time_ns} ns, the previous record {previous_ns} ns")]
    LinkTimeOutOfOrder {
        /// The file.
        path: PathBuf,
        /// Offset of the record's start.
        offset: u64,
        /// The record's time.
        time_ns: u64,
        /// The previous record's time.
        previous_ns: u64,
    },
    /// `meta.json` parses but describes an impossible rig, pen or link.
    #[error("{path}: {problem}")]
    InvalidMeta {
        /// The file.
        path: PathBuf,
        /// The field and what is wrong with it.
        problem: crate::validate::MetaProblem,
    },
    /// A PGM image that is not an 8-bit binary (P5) PGM of the stated size.
    #[error("{path}: bad PGM image: {reason}")]
    BadImage {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        reason: String,
    },
    /// A frame refers to a camera the metadata does not describe.
    #[error("no camera {camera} in this recording")]
    UnknownCamera {
        /// The camera id.
        camera: u8,
    },
    /// A frame's image file name is not a plain file name inside its camera directory.
    #[error("{path}:{line}: image name {name:?} must be a plain file name")]
    BadImageName {
        /// The frames file.
        path: PathBuf,
        /// 1-based line.
        line: usize,
        /// The name.
        name: String,
    },
}

impl RecordError {
    /// Wraps an I/O error with its file.
    pub fn io(path: impl Into<PathBuf>, cause: std::io::Error) -> Self {
        RecordError::Io {
            path: path.into(),
            cause,
        }
    }
}
