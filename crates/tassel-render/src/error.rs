//! The one error type of this crate.

use std::fmt;

/// What can go wrong turning pictures into files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum RenderError {
    /// The PNG encoder refused the image (the message is the encoder's).
    Png(String),
    /// The frames cannot make a GIF: none, of different sizes, or too large.
    Gif(String),
}

impl fmt::Display for RenderError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RenderError::Png(m) => write!(f, "PNG: {m}"),
            RenderError::Gif(m) => write!(f, "GIF: {m}"),
        }
    }
}

impl std::error::Error for RenderError {}
