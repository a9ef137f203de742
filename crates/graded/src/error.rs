//! The crate's error type: every failure names what was wrong and where
//! (file, line, column, index), and keeps its underlying cause.

use std::num::ParseFloatError;
use std::path::PathBuf;

/// Errors of this crate.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The I/O layer refused or failed (an existing output, an input that
    /// would be overwritten, a failed rename).
    #[error(transparent)]
    File(microfrep_io::IoError),
    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or directory.
        path: PathBuf,
        /// The operating system's error.
        #[source]
        source: std::io::Error,
    },
    /// Encoding a PNG layer failed.
    #[error("{}: PNG encoding failed: {source}", path.display())]
    Png {
        /// The layer file.
        path: PathBuf,
        /// The encoder's error.
        #[source]
        source: png::EncodingError,
    },
    /// A CSV field that should be a number is not one.
    #[error("{file}:{line}: field {column} ({name}) is {text:?}, expected a number")]
    CsvNumber {
        /// The CSV file (or the name given for a string).
        file: String,
        /// 1-based line.
        line: usize,
        /// 1-based field index.
        column: usize,
        /// Which field: x, y, z or value.
        name: &'static str,
        /// The text found.
        text: String,
        /// The parser's error.
        #[source]
        source: ParseFloatError,
    },
    /// CSV data that is not a regular grid of samples, or malformed rows.
    #[error("{file}:{line}: {message}")]
    Csv {
        /// The CSV file (or the name given for a string).
        file: String,
        /// 1-based line the problem was found at (the line after the last
        /// one for a problem with the whole file).
        line: usize,
        /// What is wrong and what was expected.
        message: String,
    },
    /// A palette specification that cannot be used.
    #[error("palette entry {entry} ({text:?}): {message}")]
    Palette {
        /// 1-based entry in the comma-separated list (0: the whole list).
        entry: usize,
        /// The entry's text.
        text: String,
        /// What is wrong and what was expected.
        message: String,
    },
    /// Bezier degrees, weights, box or vertices that do not define a field.
    #[error("{0}")]
    Bezier(String),
    /// An invalid argument (sizes, counts, grids, indices).
    #[error("{0}")]
    Invalid(String),
    /// A job whose buffers would exceed the memory limit.
    #[error("{what} needs {bytes} bytes, more than the limit of {limit} bytes")]
    TooLarge {
        /// What would be allocated.
        what: String,
        /// Bytes needed.
        bytes: u128,
        /// The limit.
        limit: u128,
    },
}

/// Result with this crate's [`Error`].
pub type Result<T> = std::result::Result<T, Error>;

/// A closure turning an `io::Error` into [`Error::Io`] for `path`.
pub(crate) fn io_at(path: &std::path::Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}
