//! The error type of the analysis crate.

use thiserror::Error;

/// Why an analysis was refused. Every variant carries a message for people
/// that names the offending value (bounds, resolution, voxel size, or the
/// predicted and allowed bytes); nothing is computed when one is returned.
#[derive(Debug, Error)]
pub enum AnalysisError {
    /// Bad bounds, resolution, voxel size or other input.
    #[error("{0}")]
    Input(String),
    /// The job would need more memory than allowed or available.
    #[error("{0}")]
    Memory(String),
}

/// The crate's result type, [`AnalysisError`] by default.
pub type Result<T, E = AnalysisError> = std::result::Result<T, E>;
