//! The crate's error type.

use std::path::PathBuf;

/// Result with [`ScanError`].
pub type Result<T, E = ScanError> = std::result::Result<T, E>;

/// Everything that can go wrong reading a scan or building a field from it.
/// Each variant names the file (or folder) and where in it the problem is.
#[derive(Debug, thiserror::Error)]
pub enum ScanError {
    /// Reading or opening a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// The voxel data ends before the header's sizes say it should.
    #[error(
        "{}: truncated voxel data: expected {expected} bytes from byte offset {offset}, found {found}",
        path.display()
    )]
    Truncated {
        /// The data file.
        path: PathBuf,
        /// Byte offset (in the decoded stream) where the voxel data starts.
        offset: u64,
        /// Bytes the header's sizes need.
        expected: u64,
        /// Bytes that were there.
        found: u64,
    },
    /// The data is longer than the header's sizes say (a raw file with
    /// bytes left over, a slice of the wrong size).
    #[error("{}: size mismatch{}: expected {expected}, found {found}", path.display(), at(.what))]
    SizeMismatch {
        /// The file.
        path: PathBuf,
        /// What was measured (bytes of data, pixels of a slice, ...).
        what: String,
        /// What the header or the first slice says.
        expected: u64,
        /// What is there.
        found: u64,
    },
    /// A malformed or unsupported header line (NRRD) or field (NIfTI,
    /// JSON sidecar, TIFF tag, DICOM attribute).
    #[error("{}:{location}: {message}", path.display())]
    Header {
        /// The file.
        path: PathBuf,
        /// Line number (`line 7`), field name or tag (`(0028,0030) PixelSpacing`).
        location: String,
        /// What is wrong, with the expected and found values.
        message: String,
    },
    /// The NIfTI header could not be parsed.
    #[error("{}: NIfTI header: {source}", path.display())]
    Nifti {
        /// The file.
        path: PathBuf,
        /// The nifti crate's error.
        #[source]
        source: nifti::NiftiError,
    },
    /// A TIFF file or page could not be decoded.
    #[error("{}: TIFF page {page}: {source}", path.display())]
    Tiff {
        /// The file.
        path: PathBuf,
        /// Page (directory) index in the file, from 0.
        page: usize,
        /// The tiff crate's error.
        #[source]
        source: tiff::TiffError,
    },
    /// A DICOM file could not be parsed, or an attribute could not be read.
    #[error("{}: DICOM{}: {source}", path.display(), at(.tag))]
    Dicom {
        /// The file.
        path: PathBuf,
        /// The attribute being read (empty for the file as a whole).
        tag: String,
        /// The dicom crate's error.
        #[source]
        source: Box<dyn std::error::Error + Send + Sync>,
    },
    /// The JSON sidecar of a `.raw` file could not be parsed.
    #[error("{}: {source}", path.display())]
    Json {
        /// The sidecar.
        path: PathBuf,
        /// The parser's error (with line and column).
        #[source]
        source: serde_json::Error,
    },
    /// The result would need more memory than the limit allows.
    #[error(
        "{what} needs {} ({need} bytes), over the memory limit of {}; {hint}",
        human(*need),
        human(*limit)
    )]
    TooLarge {
        /// What was about to be allocated.
        what: String,
        /// Predicted bytes.
        need: u64,
        /// The limit.
        limit: u64,
        /// What would fit: a crop or a downsampling step.
        hint: String,
    },
    /// The voxel axes are not aligned with the coordinate axes.
    #[error(
        "{}: oblique orientation: the voxel axes (columns) {matrix:?} are not a signed permutation of the coordinate axes; resample the scan to an axis-aligned grid first",
        path.display()
    )]
    Oblique {
        /// The file (or series folder).
        path: PathBuf,
        /// Direction of each voxel axis (rows are the coordinate axes).
        matrix: [[f64; 3]; 3],
    },
    /// DICOM slices are not evenly spaced along their normal.
    #[error(
        "{}: inconsistent slice spacing: {} to {} is {found} mm, expected {expected} mm (the first gap); the series has missing, duplicate or unevenly spaced slices",
        dir.display(),
        first.display(),
        second.display()
    )]
    SliceSpacing {
        /// The series folder.
        dir: PathBuf,
        /// The slice before the gap.
        first: PathBuf,
        /// The slice after the gap.
        second: PathBuf,
        /// The gap found, in mm.
        found: f64,
        /// The first gap of the series, in mm.
        expected: f64,
    },
    /// DICOM slices do not belong together (several series, or slices
    /// that differ in size, orientation or pixel format).
    #[error("{}: {message}", dir.display())]
    MixedSeries {
        /// The folder.
        dir: PathBuf,
        /// What differs, naming the files.
        message: String,
    },
    /// A feature of the file that this reader does not handle.
    #[error("{}: unsupported: {what}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is not supported, and what to do instead.
        what: String,
    },
    /// A sample is NaN or infinite where a field needs finite values.
    #[error("sample ({}, {}, {}) of the volume is {value}, not a finite number", index[0], index[1], index[2])]
    NotFinite {
        /// Voxel index (x, y, z).
        index: [usize; 3],
        /// The value found.
        value: f32,
    },
    /// The iso value does not cut the volume.
    #[error("iso value {iso} does not cut the volume: the samples range from {min} to {max}, so {}", if .iso > .max { "nothing is inside" } else { "everything is inside" })]
    NoSurface {
        /// The iso value.
        iso: f64,
        /// Smallest sample.
        min: f64,
        /// Largest sample.
        max: f64,
    },
    /// The core grid field refused the volume (too many samples, ...).
    #[error("{}: as a grid field: {source}", path.display())]
    Grid {
        /// The volume's source.
        path: PathBuf,
        /// The core error.
        #[source]
        source: microfrep_core::field::GridError,
    },
    /// An option or argument is out of range.
    #[error("{0}")]
    Invalid(String),
}

fn at(what: &str) -> String {
    if what.is_empty() {
        String::new()
    } else {
        format!(" ({what})")
    }
}

/// Bytes in a readable unit (KiB, MiB, GiB).
pub fn human(bytes: u64) -> String {
    let b = bytes as f64;
    if b >= (1u64 << 30) as f64 {
        format!("{:.2} GiB", b / (1u64 << 30) as f64)
    } else if b >= (1u64 << 20) as f64 {
        format!("{:.1} MiB", b / (1u64 << 20) as f64)
    } else if b >= 1024.0 {
        format!("{:.1} KiB", b / 1024.0)
    } else {
        format!("{bytes} B")
    }
}

/// Maps an `io::Error` on `path` into [`ScanError::Io`].
pub(crate) fn io_at(path: &std::path::Path) -> impl Fn(std::io::Error) -> ScanError + '_ {
    move |source| ScanError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// A [`ScanError::Header`].
pub(crate) fn header(
    path: &std::path::Path,
    location: impl Into<String>,
    message: impl Into<String>,
) -> ScanError {
    ScanError::Header {
        path: path.to_path_buf(),
        location: location.into(),
        message: message.into(),
    }
}

/// The error for a distance transform over the memory limit, with the
/// downsampling step that would fit.
pub(crate) fn too_large_field(vol: &crate::Volume, need: u64, limit: u64) -> ScanError {
    let n = vol.len().max(1) as f64;
    let per = need as f64 / n;
    let fit = (limit as f64 / per).floor();
    let mut step = 2u64;
    while n / (step as f64).powi(3) * per > limit as f64 && step < 256 {
        step += 1;
    }
    ScanError::TooLarge {
        what: format!(
            "the distance transform of {} x {} x {} voxels",
            vol.dims[0], vol.dims[1], vol.dims[2]
        ),
        need,
        limit,
        hint: format!(
            "{fit} voxels fit (about {}^3): read the scan with a crop or a downsampling step of {step} (ReadOptions::crop, ReadOptions::step), or raise the limit",
            fit.cbrt().floor()
        ),
    }
}
