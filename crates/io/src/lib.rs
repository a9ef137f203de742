//! microfrep's one I/O layer, shared by every crate that writes files.
//!
//! - [`atomic`]: every output (a file or a directory) is written under a
//!   unique temporary name next to its target and renamed into place only
//!   when complete; on an error, a drop, Ctrl-C or SIGTERM the temporary is
//!   removed ([`atomic::cleanup_all`], called by the CLI's signal handler),
//!   and an output that would replace one of the run's inputs is refused;
//!   large files go to the disk by direct I/O (Linux) as they are written.
//! - [`bounded`]: reading files, lines and streams with a bound on what
//!   is read (devices and pipes report no size).
//! - [`png`]: the one PNG encoder and decoder (grey 1 and 8 bit, RGB, RGBA).
//! - [`mod@format`]: output formats behind one trait, chosen by file extension
//!   from a registry, so that a new format plugs in without touching the
//!   others.
//! - [`limits`]: the memory a job may use (the smallest of available RAM,
//!   the cgroup limit and `RLIMIT_AS`), the peak resident size, and the free
//!   space on the disk an output goes to.
//! - [`colormap`]: scalar values to colour (viridis, grey), shared by the
//!   coloured mesh writers and attribute renderings.
//! - [`precision`]: the boxes and cells f32 sampling can resolve, and a
//!   probe comparing a model's f32 and f64 values.
//!
//! ```
//! use microfrep_io::atomic::AtomicFile;
//! use std::io::Write;
//! let dir = std::env::temp_dir().join(format!("mf-io-doc-{}", std::process::id()));
//! std::fs::create_dir_all(&dir).unwrap();
//! let target = dir.join("out.txt");
//! let mut f = AtomicFile::create(&target).unwrap();
//! f.write_all(b"hello").unwrap();
//! assert!(!target.exists()); // nothing visible until commit
//! f.commit().unwrap();
//! assert_eq!(std::fs::read(&target).unwrap(), b"hello");
//! # std::fs::remove_dir_all(&dir).unwrap();
//! ```

#![warn(missing_docs)]

pub mod atomic;
pub mod bounded;
pub mod colormap;
pub mod format;
pub mod limits;
pub mod png;
pub mod precision;
pub mod text;

pub use atomic::{AtomicDir, AtomicFile};
pub use format::{FormatRegistry, OutputFormat};

/// Errors of the I/O layer, with the path they concern.
#[derive(Debug, thiserror::Error)]
pub enum IoError {
    /// A system call on `path` failed.
    #[error("{path}: {source}")]
    Io {
        /// The file or directory concerned (the target, never a temporary).
        path: std::path::PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The output would replace an input of this run.
    #[error("{path}: refusing to overwrite an input of this run; choose another output")]
    WouldOverwriteInput {
        /// The output asked for.
        path: std::path::PathBuf,
    },
    /// The output path names no file (e.g. ends in `..` or is empty).
    #[error("{path}: not a file name")]
    NotAFileName {
        /// The output asked for.
        path: std::path::PathBuf,
    },
    /// An output directory already exists.
    #[error("{path} already exists; remove it or choose another output")]
    Exists {
        /// The output asked for.
        path: std::path::PathBuf,
    },
    /// The extension names no known format.
    #[error("{path}: unknown {kind} format (use {known})")]
    UnknownFormat {
        /// The output asked for.
        path: std::path::PathBuf,
        /// What is written, e.g. "mesh".
        kind: &'static str,
        /// The known extensions, e.g. ".stl, .obj".
        known: String,
    },
    /// PNG encoding failed.
    #[error("{path}: PNG encoding failed: {source}")]
    Png {
        /// The image's file.
        path: std::path::PathBuf,
        /// The encoder's error.
        #[source]
        source: ::png::EncodingError,
    },
    /// PNG decoding failed.
    #[error("{path}: not a readable PNG: {source}")]
    PngDecode {
        /// The image's file.
        path: std::path::PathBuf,
        /// The decoder's error.
        #[source]
        source: ::png::DecodingError,
    },
}

impl IoError {
    /// An [`IoError::Io`] at `path`.
    pub fn at(path: &std::path::Path) -> impl Fn(std::io::Error) -> IoError + '_ {
        move |source| IoError::Io {
            path: path.to_path_buf(),
            source,
        }
    }
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, IoError>;
