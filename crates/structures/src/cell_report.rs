//! Checks a unit cell before replication (Fryazinov et al. Eqs. 4-6): its
//! opposite faces are sampled on an `n x n` grid and compared.
//!
//! - geometric connectivity: the zero sets agree, tested as sign agreement
//!   (`f >= 0` on both faces or on neither, or values within `tol`) at every
//!   sample;
//! - full connectivity: the values agree within `tol`, so the sawtooth wave
//!   gives a continuous (C0) field;
//! - symmetry about the centre on an axis: `f(c + d) = f(c - d)` within `tol`
//!   on an `n^3` grid, so the triangle wave (which mirrors every second cell)
//!   reproduces the cell pattern unchanged.

use crate::error::{check_box, check_resolution, Error, Result};
use microfrep_core::Expr;
use microfrep_core::{PointEval, Tape};

/// What one axis of the cell allows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxisReport {
    /// The zero sets on the two faces agree: sawtooth replication joins up.
    pub geometric: bool,
    /// The values on the two faces agree within the tolerance: sawtooth
    /// replication gives a continuous field.
    pub full: bool,
    /// The cell is mirror-symmetric about its centre on this axis within the
    /// tolerance: triangle replication reproduces it.
    pub symmetric: bool,
    /// Largest `|f(face min) - f(face max)|` over the samples.
    pub max_face_diff: f64,
    /// Largest `|f(c + d) - f(c - d)|` over the samples.
    pub max_symmetry_diff: f64,
}

impl AxisReport {
    /// Sawtooth replication gives a connected shape (it may still have a
    /// jump in value, so offsets and blends can crack).
    pub fn sawtooth_connected(&self) -> bool {
        self.geometric
    }
    /// Sawtooth replication gives a continuous field.
    pub fn sawtooth_safe(&self) -> bool {
        self.full
    }
    /// Triangle replication reproduces the cell pattern (always continuous,
    /// but an asymmetric cell comes out mirrored in every second cell).
    pub fn triangle_safe(&self) -> bool {
        self.symmetric
    }
}

/// What each axis of a unit cell allows, from [`cell_report`].
#[derive(Clone, Debug, PartialEq)]
pub struct CellReport {
    /// The reports for x, y and z.
    pub axes: [AxisReport; 3],
    /// The tolerance the value comparisons used.
    pub tol: f64,
    /// Samples per face edge.
    pub n: usize,
}

impl CellReport {
    /// Geometric connectivity on all three axes.
    pub fn geometric(&self) -> bool {
        self.axes.iter().all(|a| a.geometric)
    }
    /// Full connectivity on all three axes.
    pub fn full(&self) -> bool {
        self.axes.iter().all(|a| a.full)
    }
    /// Symmetry on all three axes.
    pub fn symmetric(&self) -> bool {
        self.axes.iter().all(|a| a.symmetric)
    }
}

/// Samples `cell` on the box `[min, max]` with `n` (2..=128) samples per face
/// edge and compares values with the absolute tolerance `tol`.
pub fn cell_report(
    cell: &Expr,
    min: [f64; 3],
    max: [f64; 3],
    n: usize,
    tol: f64,
) -> Result<CellReport> {
    check_box(min, max)?;
    check_resolution("cell report face grid", n, 2, 128)?;
    if !(tol >= 0.0 && tol.is_finite()) {
        return Err(Error::OutOfRange {
            what: "tolerance",
            value: tol,
            expected: "finite, >= 0",
        });
    }
    let tape = Tape::new(cell);
    let mut ev = PointEval::new(&tape);
    let mut eval = |p: [f64; 3]| -> Result<f64> {
        let v = ev.eval(p);
        if v.is_finite() {
            Ok(v)
        } else {
            Err(Error::NotFinite {
                value: v,
                x: p[0],
                y: p[1],
                z: p[2],
            })
        }
    };
    let at = |i: usize, k: usize| min[i] + (max[i] - min[i]) * k as f64 / (n - 1) as f64;
    let mut axes = [AxisReport {
        geometric: true,
        full: true,
        symmetric: true,
        max_face_diff: 0.0,
        max_symmetry_diff: 0.0,
    }; 3];
    for (axis, rep) in axes.iter_mut().enumerate() {
        let (u, v) = microfrep_shapes::others(axis);
        for a in 0..n {
            for b in 0..n {
                let mut p = [0.0; 3];
                p[u] = at(u, a);
                p[v] = at(v, b);
                p[axis] = min[axis];
                let lo = eval(p)?;
                p[axis] = max[axis];
                let hi = eval(p)?;
                // Values within the tolerance agree even across the sign
                // (a boundary through the sample on both faces), so full
                // connectivity always implies geometric connectivity.
                rep.geometric &= (lo >= 0.0) == (hi >= 0.0) || (lo - hi).abs() <= tol;
                rep.max_face_diff = rep.max_face_diff.max((lo - hi).abs());
                // Mirror pairs through the whole box: c + d and c - d.
                for c in 0..n / 2 {
                    p[axis] = at(axis, c);
                    let f1 = eval(p)?;
                    p[axis] = at(axis, n - 1 - c);
                    let f2 = eval(p)?;
                    rep.max_symmetry_diff = rep.max_symmetry_diff.max((f1 - f2).abs());
                }
            }
        }
        rep.full = rep.max_face_diff <= tol;
        rep.symmetric = rep.max_symmetry_diff <= tol;
    }
    Ok(CellReport { axes, tol, n })
}

// Reports for people and programs (the `microfrep cell` verb prints them).

const AXES: [&str; 3] = ["x", "y", "z"];

/// One line of advice for an axis.
fn advice(a: &AxisReport) -> String {
    let saw = if a.sawtooth_safe() {
        "sawtooth safe (full connectivity: continuous field)"
    } else if a.sawtooth_connected() {
        "sawtooth: boundaries match at cell faces but the field jumps there (geometric connectivity only; offsets and blends may crack)"
    } else {
        "sawtooth unsafe (the shape differs on opposite faces: seams)"
    };
    let tri = if a.triangle_safe() {
        "triangle safe (symmetric)"
    } else {
        "triangle mirrors every second cell (not symmetric)"
    };
    format!("{saw}; {tri}")
}

fn yes(b: bool) -> &'static str {
    if b {
        "yes"
    } else {
        "no"
    }
}

fn axes_where(r: &CellReport, f: impl Fn(&AxisReport) -> bool) -> Vec<&'static str> {
    (0..3).filter(|&i| f(&r.axes[i])).map(|i| AXES[i]).collect()
}

/// The report as JSON (the keys of `microfrep cell --json`).
pub fn to_json(r: &CellReport, min: [f64; 3], max: [f64; 3]) -> serde_json::Value {
    let axes: Vec<serde_json::Value> = (0..3)
        .map(|i| {
            let a = &r.axes[i];
            serde_json::json!({
                "axis": AXES[i],
                "geometric": a.geometric,
                "full": a.full,
                "symmetric": a.symmetric,
                "max_face_diff": a.max_face_diff,
                "max_symmetry_diff": a.max_symmetry_diff,
                "sawtooth_safe": a.sawtooth_safe(),
                "sawtooth_connected": a.sawtooth_connected(),
                "triangle_safe": a.triangle_safe(),
            })
        })
        .collect();
    serde_json::json!({
        "box": [min, max],
        "samples": r.n,
        "tolerance": r.tol,
        "geometric": r.geometric(),
        "full": r.full(),
        "symmetric": r.symmetric(),
        "sawtooth_safe_axes": axes_where(r, AxisReport::sawtooth_safe),
        "triangle_safe_axes": axes_where(r, AxisReport::triangle_safe),
        "axes": axes,
    })
}

impl CellReport {
    /// The report as text: the table of face and symmetry checks and the
    /// replication advice per axis.
    pub fn to_text(&self, min: [f64; 3], max: [f64; 3]) -> String {
        use std::fmt::Write as _;
        let mut out = String::new();
        let _ = writeln!(
            out,
            "unit cell {min:?}..{max:?}: {n}x{n} samples per face, {n} per axis for symmetry, \
             absolute tolerance {t:e}",
            n = self.n,
            t = self.tol
        );
        let _ = writeln!(
            out,
            "axis  geometric  full  symmetric  max face diff  max symmetry diff"
        );
        for (i, ax) in self.axes.iter().enumerate() {
            let _ = writeln!(
                out,
                "{:<5} {:<10} {:<5} {:<10} {:<14.3e} {:.3e}",
                AXES[i],
                yes(ax.geometric),
                yes(ax.full),
                yes(ax.symmetric),
                ax.max_face_diff,
                ax.max_symmetry_diff
            );
        }
        for (i, ax) in self.axes.iter().enumerate() {
            let _ = writeln!(out, "{}: {}", AXES[i], advice(ax));
        }
        let list = |v: Vec<&str>| {
            if v.is_empty() {
                "none".to_string()
            } else {
                v.join(" ")
            }
        };
        let _ = writeln!(
            out,
            "connectivity: geometric {}, full {}; symmetric {}",
            yes(self.geometric()),
            yes(self.full()),
            yes(self.symmetric())
        );
        let _ = writeln!(
            out,
            "safe replication: sawtooth on {}; triangle on {}",
            list(axes_where(self, AxisReport::sawtooth_safe)),
            list(axes_where(self, AxisReport::triangle_safe))
        );
        out
    }
}
