//! The error type of rendering.

/// What can go wrong while rendering or writing an image.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Bad parameters (no underlying error).
    #[error("invalid parameters: {0}")]
    Invalid(String),
    /// Encoding or writing the image failed.
    #[error(transparent)]
    File(#[from] microfrep_io::IoError),
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, RenderError>;
