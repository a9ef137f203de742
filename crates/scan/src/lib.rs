//! CT scans and other volume images as signed distance fields.
#![warn(missing_docs)]

pub mod dcm;
pub mod error;
mod field;
mod grid;
pub mod nii;
pub mod nrrd;
pub mod raw;
mod sdf;
mod smooth;
pub mod tif;
pub mod volume;

pub use error::{Result, ScanError};
pub use field::{plan_bytes, surface_bytes, IntensityField, ScanField, ScanOptions};
pub use volume::{
    Format, Progress, ReadOptions, SampleType, Samples, Volume, DEFAULT_MEMORY_LIMIT,
};
