//! Counting run-time errors over the sample points of a mesher or slicer.
//!
//! The value output is NaN wherever the model raises a run-time error, so
//! such points are outside for every consumer (the reference polygonizer
//! silently reused the previous sample's value instead). The counting itself
//! is the core's ([`microfrep_core::Shape::error_census`]).

use super::Model;
pub use microfrep_core::ErrorCensus;

impl Model {
    /// Counts run-time errors at the points `xs x ys x zs` (every
    /// combination), evaluated like `eval` does (f64).
    pub fn error_census(&self, xs: &[f64], ys: &[f64], zs: &[f64]) -> ErrorCensus {
        self.shape()
            .error_census(xs, ys, zs)
            .unwrap_or_else(|| ErrorCensus {
                samples: [xs, ys, zs].iter().map(|a| a.len() as u64).product(),
                ..Default::default()
            })
    }
}
