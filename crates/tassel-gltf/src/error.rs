//! The one error type of this crate.

use thiserror::Error;

/// What can go wrong reading or writing glTF.
#[derive(Debug, Error)]
pub enum GltfError {
    /// The file could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The OS error.
        source: std::io::Error,
    },
    /// The file is not valid glTF (truncated, bad JSON, bad references).
    #[error("{path}: not a valid glTF file: {message}")]
    Invalid {
        /// The file (or `<memory>`).
        path: String,
        /// What is wrong.
        message: String,
    },
    /// The node hierarchy does not make a skeleton (cycle, too many nodes...).
    #[error("{path}: {source}")]
    Skeleton {
        /// The file.
        path: String,
        /// The skeleton error.
        source: tassel::Error,
    },
}
