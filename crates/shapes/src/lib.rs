//! Primitives with HyperFun's exact formulas (`LIBRARY.md` sections 1, 2, 5)
//! plus half-spaces. Each takes the (possibly already mapped) point `p`;
//! every scalar parameter is an [`Expr`], so it may be a field.
//!
//! HyperFun's sentinel values and point-array length checks are left to the
//! HyperFun front end; each function names the `hf*` call it implements.
//! List arguments are slices of triples (`[Expr; 3]`) or of scalars; a list
//! too short for the primitive count gives a [`PrimError`].
//!
//! ```
//! use microfrep_core::{Expr, PointEval, Tape};
//! let ball = microfrep_shapes::sphere(&Expr::xyz(), &microfrep_shapes::v3([0.0; 3]), 1.0);
//! assert_eq!(PointEval::new(&Tape::new(&ball)).eval([0.0, 0.0, 0.5]), 0.75);
//! ```

#![warn(missing_docs)]

mod basic;
mod blobs;
mod conv;
mod conv_arc;
mod dellipsoid;
mod distance;

pub use basic::*;
pub use blobs::*;
pub use conv::*;
pub use conv_arc::*;
pub use dellipsoid::*;
pub use distance::*;

use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// HyperFun's `EPS`, used by several primitives' guards.
pub const HF_EPS: f64 = 1e-6;

/// Bad list arguments of a primitive.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PrimError {
    /// A list argument is shorter than the primitive count needs.
    #[error("{prim}: list `{arg}` has {got} entries, {need} needed")]
    TooFew {
        /// The HyperFun function, e.g. `hfConvLine`.
        prim: &'static str,
        /// The argument's name in that function.
        arg: &'static str,
        /// Entries needed.
        need: usize,
        /// Entries given.
        got: usize,
    },
    /// A mesh triangle names a vertex that does not exist.
    #[error("{prim}: triangle {tri} refers to vertex {index}, only {count} given")]
    BadIndex {
        /// The HyperFun function.
        prim: &'static str,
        /// 0-based triangle number.
        tri: usize,
        /// The 0-based vertex index found.
        index: usize,
        /// Number of vertices.
        count: usize,
    },
    /// A segment with constant, equal ends (HyperFun stops the program
    /// there).
    #[error("{prim}: segment {index} has zero length")]
    ZeroSegment {
        /// The HyperFun function.
        prim: &'static str,
        /// 0-based segment number.
        index: usize,
    },
}

/// A constant vector as expressions.
pub fn v3(a: [f64; 3]) -> P3 {
    [
        Expr::constant(a[0]),
        Expr::constant(a[1]),
        Expr::constant(a[2]),
    ]
}

/// The other two axes of `axis`, in increasing order.
pub fn others(axis: usize) -> (usize, usize) {
    match axis {
        0 => (1, 2),
        1 => (0, 2),
        _ => (0, 1),
    }
}

fn sub(a: &P3, b: &P3) -> P3 {
    [&a[0] - &b[0], &a[1] - &b[1], &a[2] - &b[2]]
}

fn dot(a: &P3, b: &P3) -> Expr {
    &a[0] * &b[0] + &a[1] * &b[1] + &a[2] * &b[2]
}

fn norm2(a: &P3) -> Expr {
    a[0].square() + a[1].square() + a[2].square()
}

/// Errors unless `list` has at least `need` entries.
fn need<T>(
    prim: &'static str,
    arg: &'static str,
    list: &[T],
    need: usize,
) -> Result<(), PrimError> {
    if list.len() < need {
        return Err(PrimError::TooFew {
            prim,
            arg,
            need,
            got: list.len(),
        });
    }
    Ok(())
}
