//! Errors of mesh and matrix file I/O.

use crate::mesh::MeshError;

/// What went wrong reading or writing a file. Text formats give 1-based line numbers,
/// binary formats byte offsets from the start of the stream.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// Underlying I/O failure (shown as the OS's message; callers add the file name).
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// Malformed text.
    #[error("line {line}: {message}")]
    Syntax {
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// Malformed or truncated binary data.
    #[error("byte {offset}: {message}")]
    Binary {
        /// Byte offset where the problem was found.
        offset: u64,
        /// What is wrong.
        message: String,
    },
    /// A count or size exceeds the reader's limits (see [`super::limits`]).
    #[error("{what} = {value} exceeds the limit {limit}")]
    Limit {
        /// What was counted.
        what: &'static str,
        /// The value found.
        value: u64,
        /// The limit.
        limit: u64,
    },
    /// The file extension or header names an unsupported format.
    #[error("unsupported format: {0}")]
    UnsupportedFormat(String),
    /// The data cannot be written in the requested format.
    #[error("cannot write: {0}")]
    Unwritable(String),
    /// The polygons do not form a manifold mesh.
    #[error(transparent)]
    Mesh(#[from] MeshError),
}

impl IoError {
    pub(crate) fn syntax(line: usize, message: impl Into<String>) -> Self {
        Self::Syntax {
            line,
            message: message.into(),
        }
    }
    pub(crate) fn binary(offset: u64, message: impl Into<String>) -> Self {
        Self::Binary {
            offset,
            message: message.into(),
        }
    }
}
