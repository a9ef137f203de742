//! CT scans and other volume images as signed distance fields, so a scanned
//! part (a bone, a sample) becomes an FRep model that composes with
//! everything else: fill it with a lattice, shell it, intersect it.
//!
//! Two steps:
//!
//! 1. **Read** a scan into a [`Volume`] (dims, spacing and origin in mm,
//!    compact samples with a slope and intercept): [`Volume::open`] picks
//!    the reader from the path.
//!    - NRRD ([`nrrd`]): `.nrrd` and detached `.nhdr`, `raw`/`gzip`/`text`
//!      encodings, both byte orders, `space directions`/`space origin` or
//!      `spacings`; what `microfrep voxels -o x.nrrd` writes.
//!    - NIfTI-1 ([`nii`]): `.nii`, `.nii.gz`, `.hdr`/`.img`; sform, qform or
//!      pixdim; `scl_slope`/`scl_inter`; spatial units.
//!    - TIFF stacks ([`tif`]): one multi-page file, or a folder of slices in
//!      natural name order; 8/16/32-bit grey; the spacing comes from
//!      [`ReadOptions::spacing`].
//!    - DICOM series ([`dcm`]): a folder of slices, one series, sorted by
//!      ImagePositionPatient along the slice normal, rescaled to Hounsfield
//!      units; uneven spacing, mixed series and gantry tilt are errors.
//!    - Raw + JSON sidecar ([`raw`]): what `microfrep voxels -o x.raw`
//!      writes (occupancy bytes or f32 field values).
//!
//!    Axes are flipped and permuted to run along +x, +y, +z of the file's
//!    frame (LPS for DICOM, RAS for NIfTI, NRRD's `space`), or of the
//!    frame [`ReadOptions::frame`] asks for ([`Frame`]: LPS, RAS, or the
//!    voxel grid in mm); oblique volumes are refused. Every reader predicts its memory
//!    before allocating and refuses over [`ReadOptions::memory_limit`]
//!    with a crop or downsampling step that would fit; [`ReadOptions::crop`]
//!    and [`ReadOptions::step`] apply while the slices stream in.
//!
//! 2. **Build** a [`ScanField`] at an iso value (inside is `value >= iso`),
//!    optionally after Gaussian smoothing in mm: an exact Euclidean feature
//!    transform (anisotropic spacing) to surface elements placed on the
//!    linearly interpolated iso surface, so distances are sub-voxel (a
//!    smooth ball comes back within a few hundredths of a voxel near its
//!    surface). The field interpolates the distance grid trilinearly, is
//!    cut by the voxels' box (negative outside, never overestimating the
//!    distance there), and answers intervals from a min/max pyramid.
//!    [`IntensityField`] is the scan's own values as a field.
//!
//! ```
//! use microfrep_core::{Expr, Field, PointEval, Tape};
//! use microfrep_scan::{ReadOptions, Samples, ScanField, ScanOptions, Volume};
//!
//! // A scan would come from `Volume::open(path, &ReadOptions::default())`;
//! // here a 16-bit "CT" of a ball of radius 2 mm: +1000 HU inside, -1000
//! // outside, stored with intercept -1024 as a scanner does.
//! let n = 24;
//! let h = 0.25;
//! let mut v = Vec::new();
//! for k in 0..n {
//!     for j in 0..n {
//!         for i in 0..n {
//!             let p = [i, j, k].map(|c| c as f64 * h - 3.0);
//!             let d = (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]).sqrt();
//!             let hu = (1000.0 * (2.0 - d)).clamp(-1000.0, 1000.0);
//!             v.push((hu + 1024.0) as i16);
//!         }
//!     }
//! }
//! let mut vol = Volume::new([n; 3], [h; 3], [-3.0; 3], Samples::I16(v)).unwrap();
//! vol.intercept = -1024.0;
//!
//! // Bone at 300 HU: the surface sits 0.3 mm inside the 0 HU radius.
//! let field = ScanField::build(&vol, &ScanOptions::new(300.0)).unwrap();
//! assert!((field.eval([0.0, 0.0, 0.0]) - 1.7).abs() < 0.15);
//! assert!(field.eval([1.7, 0.0, 0.0]).abs() < 0.02);
//!
//! // As a node of a model: the scanned ball hollowed to a 0.4 mm shell.
//! let f = Expr::field(field.into_field());
//! let shell = f.min(Expr::constant(0.4) - f.clone());
//! let tape = Tape::new(&shell);
//! assert!(PointEval::new(&tape).eval([1.5, 0.0, 0.0]) > 0.0);
//! assert!(PointEval::new(&tape).eval([0.0, 0.0, 0.0]) < 0.0);
//! ```
//!
//! Dependencies: `nifti` parses NIfTI headers, `tiff` decodes TIFF pages,
//! `dicom-object` / `dicom-core` / `dicom-dictionary-std` parse DICOM files,
//! `flate2` decodes gzip, `serde_json` reads the raw sidecar; the NRRD
//! header, the voxel streaming, the distance transform, smoothing and the
//! fields are our own (they are the product, and must be memory-bounded).
#![warn(missing_docs)]
// `!(x > t)` is meant: it is also true for NaN. Axis loops index several
// 3-arrays at once.
#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::needless_range_loop)]

pub mod dcm;
pub mod error;
mod field;
mod grid;
pub mod nii;
pub mod nrrd;
pub mod raw;
mod sdf;
mod smooth;
pub mod stats;
pub mod tif;
pub mod volume;

pub use error::{Result, ScanError};
pub use field::{plan_bytes, surface_bytes, IntensityField, ScanField, ScanOptions};
pub use stats::Histogram;
pub use volume::{
    no_progress, Format, Frame, Progress, ReadOptions, SampleType, Samples, Volume,
    DEFAULT_MEMORY_LIMIT,
};
