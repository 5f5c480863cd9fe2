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

/// Why [`crate::play`] stopped: its options, the simulation, or the caller's `on_frame`
/// (whose own error type `E` comes back unchanged).
#[derive(Debug, Error)]
pub enum PlayError<E> {
    /// The [`crate::BakeOptions`] are invalid.
    #[error("{0}")]
    Options(#[source] GltfError),
    /// The simulation refused a frame (a non-finite pose, a broken state).
    #[error("frame at {time} s: {source}")]
    Simulation {
        /// Seconds into the clip (negative during the warm-up).
        time: f32,
        /// What the simulation said.
        source: tassel::Error,
    },
    /// `on_frame` returned an error.
    #[error("{0}")]
    Frame(E),
}
