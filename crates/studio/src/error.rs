//! The studio's error type.

use crate::engine::EngineError;

/// What can go wrong in the studio; each endpoint turns it into a status
/// code and a JSON `{"error": message}`.
#[derive(Debug, thiserror::Error)]
pub enum StudioError {
    /// The server could not listen on the address.
    #[error("cannot listen on {addr}: {source}")]
    Listen {
        /// The address asked for.
        addr: String,
        /// What the socket layer said.
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// A file or folder could not be read or written.
    #[error("{path}: {source}")]
    Io {
        /// The path.
        path: String,
        /// The cause.
        source: std::io::Error,
    },
    /// A path from the page was refused.
    #[error("path '{path}' refused: {reason}")]
    Path {
        /// The path as given.
        path: String,
        /// Why.
        reason: String,
    },
    /// A request was malformed (missing field, bad number, unknown session).
    #[error("{0}")]
    Request(String),
    /// An engine call failed.
    #[error(transparent)]
    Engine(#[from] EngineError),
    /// Writing a zip archive failed.
    #[error("zip: {0}")]
    Zip(#[from] zip::result::ZipError),
    /// A job ran past its time limit.
    #[error("stopped after {0:.0} s (the studio's time limit for one job)")]
    Timeout(f64),
    /// A job was superseded by a newer edit.
    #[error("superseded by a newer edit")]
    Stale,
    /// The client of a job closed its connection, so the job was stopped.
    #[error("stopped: the client closed the connection")]
    Gone,
    /// Too much is running at once; the request may be retried.
    #[error("{0}")]
    Busy(String),
    /// A job panicked; the server caught it and goes on.
    #[error("internal error: {0}")]
    Panic(String),
}

impl StudioError {
    /// HTTP status for this error.
    pub fn status(&self) -> u16 {
        match self {
            StudioError::Path { .. } => 403,
            StudioError::Request(_) => 400,
            StudioError::Stale => 409,
            StudioError::Gone => 499,
            StudioError::Busy(_) => 503,
            StudioError::Engine(EngineError::Limit(_)) | StudioError::Timeout(_) => 422,
            StudioError::Engine(_) => 422,
            _ => 500,
        }
    }
}

/// `StudioError::Io` for `path`.
pub(crate) fn io_at(path: &std::path::Path) -> impl Fn(std::io::Error) -> StudioError + '_ {
    move |source| StudioError::Io {
        path: path.display().to_string(),
        source,
    }
}
