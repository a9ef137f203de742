//! Errors of the writers and readers. Every error on a package names the
//! part (`/3D/3dmodel.model`, `[Content_Types].xml`, ...) and, inside XML,
//! the byte offset of the element, so a bad file can be found and fixed.

use thiserror::Error;

/// Errors writing or reading a 3MF package.
#[derive(Debug, Error)]
pub enum Error {
    /// The file could not be opened, created or written.
    #[error("{path}: {source}")]
    Io {
        /// File or part being read or written.
        path: String,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The zip container is broken or a part could not be stored.
    #[error("{part}: zip archive error: {source}")]
    Zip {
        /// Part (or the archive itself) that failed.
        part: String,
        /// The zip layer's error.
        source: zip::result::ZipError,
    },
    /// A part that the package needs is not in it.
    #[error("missing part {part}{context}")]
    MissingPart {
        /// Name of the missing part.
        part: String,
        /// What referenced it (empty, or ": referenced by ...").
        context: String,
    },
    /// XML that does not parse.
    #[error("{part}: XML error at byte {offset}: {source}")]
    Xml {
        /// Part holding the XML.
        part: String,
        /// Byte offset in the (uncompressed) part.
        offset: u64,
        /// The parser's error.
        source: quick_xml::Error,
    },
    /// An attribute value that does not decode (bad escape, bad UTF-8).
    #[error("{part}: bad attribute at byte {offset}: {source}")]
    Attribute {
        /// Part holding the XML.
        part: String,
        /// Byte offset in the part.
        offset: u64,
        /// The parser's error.
        source: quick_xml::Error,
    },
    /// Well-formed XML that breaks a rule of the specification.
    #[error("{part}: at byte {offset}: {message}")]
    Invalid {
        /// Part holding the XML.
        part: String,
        /// Byte offset in the part (0 when not tied to one element).
        offset: u64,
        /// What is wrong.
        message: String,
    },
    /// A model requires an extension this crate does not implement.
    #[error("{part}: requires extension {namespace} (prefix `{prefix}`), which is not supported; supported: core, materials, slice, beam lattice (+ balls), volumetric, implicit")]
    UnsupportedExtension {
        /// Part holding the model.
        part: String,
        /// Prefix listed in `requiredextensions`.
        prefix: String,
        /// The namespace it stands for (or "undeclared").
        namespace: String,
    },
    /// A PNG sheet of an image stack could not be encoded.
    #[error("{part}: PNG encoding failed: {source}")]
    PngEncode {
        /// Part being written.
        part: String,
        /// The PNG encoder's error.
        source: png::EncodingError,
    },
    /// A PNG sheet of an image stack could not be decoded.
    #[error("{part}: PNG decoding failed: {source}")]
    PngDecode {
        /// Part being read.
        part: String,
        /// The PNG decoder's error.
        source: png::DecodingError,
    },
    /// Data given to a writer that cannot form a valid package.
    #[error("cannot write: {0}")]
    BadInput(String),
    /// A size beyond the limits (counts, memory) this crate accepts.
    #[error("{part}: {message}")]
    TooLarge {
        /// Part being read or written.
        part: String,
        /// Which limit and by how much.
        message: String,
    },
}

/// Result with this crate's [`enum@Error`].
pub type Result<T> = std::result::Result<T, Error>;

pub(crate) fn invalid(part: &str, offset: u64, message: impl Into<String>) -> Error {
    Error::Invalid {
        part: part.to_string(),
        offset,
        message: message.into(),
    }
}
