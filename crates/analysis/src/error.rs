//! The error type of the analysis crate.

use thiserror::Error;

#[derive(Debug, Error)]
pub enum AnalysisError {
    /// Bad bounds, resolution, voxel size or other input.
    #[error("{0}")]
    Input(String),
    /// The job would need more memory than allowed or available.
    #[error("{0}")]
    Memory(String),
}

pub type Result<T, E = AnalysisError> = std::result::Result<T, E>;
