//! Run-time errors of a model: their codes, what they mean, and how many
//! sample points of a job hit them.

use crate::{Expr, Interval, IntervalEval, PointEval, Tape};
use std::fmt;

/// A run-time error: what went wrong and where in the model's source
/// (line and column from 1; 0 where unknown).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct RuntimeError {
    /// What went wrong, e.g. "Negative value for square root".
    pub message: String,
    /// Source line, from 1 (0: unknown).
    pub line: u32,
    /// Source column, from 1 (0: unknown).
    pub col: u32,
}

impl RuntimeError {
    /// The error of a code no source knows.
    pub fn unknown() -> RuntimeError {
        RuntimeError {
            message: "evaluation failed".into(),
            line: 0,
            col: 0,
        }
    }
}

impl fmt::Display for RuntimeError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line == 0 {
            write!(f, "{}", self.message)
        } else {
            write!(f, "{} at {}:{}", self.message, self.line, self.col)
        }
    }
}

/// Decodes the codes of a shape's error output (see [`crate::Shape`]).
pub trait ErrorSource: Send + Sync + fmt::Debug {
    /// The error a nonzero code stands for; `None` if the code is unknown.
    fn decode(&self, code: f64) -> Option<RuntimeError>;
}

/// Run-time errors on a grid of sample points.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ErrorCensus {
    /// Points looked at.
    pub samples: u64,
    /// Points where the model raised a run-time error.
    pub errors: u64,
    /// Per error site (message and position), how many points hit it, in
    /// order of their codes.
    pub sites: Vec<(RuntimeError, u64)>,
}

impl fmt::Display for ErrorCensus {
    /// `N of M samples` plus the most frequent site, for a summary line.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} of {} samples", self.errors, self.samples)?;
        if let Some((e, n)) = self.sites.iter().max_by_key(|(_, n)| *n) {
            write!(f, " (most: {e}, {n} times)")?;
        }
        Ok(())
    }
}

/// Boxes of at most this many points are sampled point by point.
const LEAF: usize = 4096;

struct Walk<'a> {
    axes: [&'a [f64]; 3],
    ie: IntervalEval,
    pe: PointEval,
    codes: Vec<u64>,
    unknown: u64,
}

impl Walk<'_> {
    /// Visits the index box `lo..hi` (per axis), halving it until intervals
    /// prove the code 0 or it is small enough to sample. An explicit stack
    /// keeps the depth independent of the grid size.
    fn run(&mut self, lo: [usize; 3], hi: [usize; 3]) {
        let mut stack = vec![(lo, hi)];
        while let Some((lo, hi)) = stack.pop() {
            let n: [usize; 3] = std::array::from_fn(|a| hi[a] - lo[a]);
            if n.contains(&0) {
                continue;
            }
            let b: [Interval; 3] = std::array::from_fn(|a| span(&self.axes[a][lo[a]..hi[a]]));
            let r = self.ie.eval(b[0], b[1], b[2]);
            if !r.may_be_nan() && r.lo == 0.0 && r.hi == 0.0 {
                continue;
            }
            if n[0] * n[1] * n[2] <= LEAF {
                for k in lo[2]..hi[2] {
                    for j in lo[1]..hi[1] {
                        for i in lo[0]..hi[0] {
                            let p = [self.axes[0][i], self.axes[1][j], self.axes[2][k]];
                            let code = self.pe.eval(p);
                            self.count(code);
                        }
                    }
                }
                continue;
            }
            let a = (0..3).max_by_key(|&a| n[a]).unwrap_or(0);
            let mid = lo[a] + n[a] / 2;
            let (mut hi1, mut lo2) = (hi, lo);
            hi1[a] = mid;
            lo2[a] = mid;
            stack.push((lo2, hi));
            stack.push((lo, hi1));
        }
    }

    fn count(&mut self, code: f64) {
        if code == 0.0 {
            return;
        }
        if code.is_nan() || code < 1.0 || code > 1e9 {
            self.unknown += 1;
            return;
        }
        let k = code.round() as usize - 1;
        if self.codes.len() <= k {
            self.codes.resize(k + 1, 0);
        }
        self.codes[k] += 1;
    }
}

/// Bounds of a list of coordinates (NaN-free lists; empty gives ENTIRE).
fn span(v: &[f64]) -> Interval {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    if lo <= hi {
        Interval::new(lo, hi)
    } else {
        Interval::ENTIRE
    }
}

/// The census of error expression `code` (codes 1, 2, ... decoded by
/// `source`) over the grid `axes[0] x axes[1] x axes[2]`.
pub(super) fn census(code: &Expr, source: &dyn ErrorSource, axes: [&[f64]; 3]) -> ErrorCensus {
    let samples = axes.iter().map(|a| a.len() as u64).product();
    let tape = Tape::new(code);
    let mut w = Walk {
        axes,
        ie: IntervalEval::new(&tape),
        pe: PointEval::new(&tape),
        codes: Vec::new(),
        unknown: 0,
    };
    w.run([0; 3], [axes[0].len(), axes[1].len(), axes[2].len()]);
    let mut sites = Vec::new();
    for (k, &n) in w.codes.iter().enumerate() {
        if n > 0 {
            let e = source
                .decode((k + 1) as f64)
                .unwrap_or_else(RuntimeError::unknown);
            sites.push((e, n));
        }
    }
    if w.unknown > 0 {
        sites.push((RuntimeError::unknown(), w.unknown));
    }
    let errors = sites.iter().map(|(_, n)| n).sum();
    ErrorCensus {
        samples,
        errors,
        sites,
    }
}
