//! Errors for bad input to the structure builders and analyses.

use thiserror::Error;

/// What the structure builders and analyses reject.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum Error {
    /// A box with a non-positive or non-finite extent on some axis.
    #[error("box is empty or not finite on axis {axis}: [{min}, {max}]")]
    BadBox {
        /// The axis, 0, 1, 2 for x, y, z.
        axis: usize,
        /// Lower end given on that axis.
        min: f64,
        /// Upper end given on that axis.
        max: f64,
    },
    /// A sampling resolution outside what the analysis supports.
    #[error("{what}: resolution {n} outside [{lo}, {hi}]")]
    BadResolution {
        /// Which resolution.
        what: &'static str,
        /// The value given.
        n: usize,
        /// Smallest accepted.
        lo: usize,
        /// Largest accepted.
        hi: usize,
    },
    /// A numeric argument out of its allowed range.
    #[error("{what} = {value} is out of range ({expected})")]
    OutOfRange {
        /// Which argument.
        what: &'static str,
        /// The value given.
        value: f64,
        /// The range or rule it breaks, in words.
        expected: &'static str,
    },
    /// The function is NaN or infinite at a sample point.
    #[error("function is not finite ({value}) at ({x}, {y}, {z})")]
    NotFinite {
        /// The value found.
        value: f64,
        /// x of the sample point.
        x: f64,
        /// y of the sample point.
        y: f64,
        /// z of the sample point.
        z: f64,
    },
    /// A target volume fraction the parameter range cannot reach.
    #[error("target volume fraction {target} is outside the reachable range [{lo}, {hi}]")]
    Unreachable {
        /// The fraction asked for.
        target: f64,
        /// Smallest fraction the parameter range gives.
        lo: f64,
        /// Largest fraction the parameter range gives.
        hi: f64,
    },
    /// The model lacks a parameter the solver needs.
    #[error("model has no parameter named `{0}`")]
    NoParam(String),
}

/// Results of this crate.
pub type Result<T> = std::result::Result<T, Error>;

/// Checks that `[min, max]` is a finite box with positive extent on every axis.
pub fn check_box(min: [f64; 3], max: [f64; 3]) -> Result<()> {
    for axis in 0..3 {
        let (lo, hi) = (min[axis], max[axis]);
        if !(lo.is_finite() && hi.is_finite() && hi > lo) {
            return Err(Error::BadBox {
                axis,
                min: lo,
                max: hi,
            });
        }
    }
    Ok(())
}

/// Checks a grid resolution.
pub fn check_resolution(what: &'static str, n: usize, lo: usize, hi: usize) -> Result<()> {
    if n < lo || n > hi {
        return Err(Error::BadResolution { what, n, lo, hi });
    }
    Ok(())
}
