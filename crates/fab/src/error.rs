//! The error type of slicing, voxel export and reading back.

/// Everything that can go wrong while slicing, exporting or reading back.
#[derive(Debug, thiserror::Error)]
pub enum FabError {
    /// Bad parameters (no underlying error).
    #[error("invalid parameters: {0}")]
    Invalid(String),
    /// The job would not fit in the memory the process may use.
    #[error("{0}")]
    TooLarge(String),
    /// f32 sampling cannot resolve the model (its values underflow or
    /// overflow in f32); the message says where.
    #[error("cannot sample this model: {0}")]
    Precision(microfrep_io::precision::PrecisionError),
    /// The output would hold nothing (no pixel or voxel inside the
    /// model); the message says why. Nothing was written.
    #[error("{0}")]
    Empty(String),
    /// Reading or writing a file failed, or the I/O layer refused (an
    /// output that would replace an input, an existing output directory).
    #[error(transparent)]
    File(#[from] microfrep_io::IoError),
    /// A file read back is malformed.
    #[error("line {line}: {msg}")]
    Parse {
        /// Line, from 1.
        line: usize,
        /// What is wrong.
        msg: String,
    },
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, FabError>;

/// Attaches the path to an I/O error.
pub(crate) fn io_at(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> FabError + '_ {
    move |source| {
        FabError::File(microfrep_io::IoError::Io {
            path: path.to_path_buf(),
            source,
        })
    }
}
