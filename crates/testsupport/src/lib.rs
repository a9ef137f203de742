//! Support for microfrep's tests and benchmarks, kept out of the libraries'
//! APIs: the crates take it as a dev-dependency (the bench crate, which is
//! not published either, as a dependency). Not published.
//!
//! - [`pyvenv`]: a Python with given packages, for the optional
//!   cross-checks and the benchmarks against Python peers.

#![warn(missing_docs)]

pub mod pyvenv;
