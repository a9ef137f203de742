use std::path::PathBuf;

/// Everything that can go wrong while slicing, exporting or reading back.
#[derive(Debug, thiserror::Error)]
pub enum FabError {
    #[error("invalid parameters: {0}")]
    Invalid(String),
    // The I/O error is part of the message, not a source, so error chains
    // do not print it twice.
    #[error("{}: {err}", path.display())]
    Io { path: PathBuf, err: std::io::Error },
    #[error("{}: {msg}", path.display())]
    Encode { path: PathBuf, msg: String },
    #[error("line {line}: {msg}")]
    Parse { line: usize, msg: String },
}

pub type Result<T> = std::result::Result<T, FabError>;

/// Attaches the path to an I/O error.
pub(crate) fn io_at(path: &std::path::Path) -> impl FnOnce(std::io::Error) -> FabError + '_ {
    move |err| FabError::Io {
        path: path.to_path_buf(),
        err,
    }
}
