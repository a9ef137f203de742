//! What 32-bit sampling can represent: the one rule every sampling grid
//! (meshing, slicing, voxels, analysis) applies to its box and cell size
//! before it starts, and a probe that compares a model's f32 batch values
//! with its f64 reference values.
//!
//! The hot evaluators work in f32: coordinates carry 24 significant bits,
//! so far from the origin neighbouring samples collapse onto one value (at
//! 1e6 mm, f32 steps are 0.0625 mm), and tiny or huge models underflow or
//! overflow in f32 while f64 is right. [`check_grid`] refuses a box or cell
//! the f32 coordinates cannot resolve; [`check_agreement`] refuses a model
//! whose f32 signs disagree with its f64 signs at many probe points.
//!
//! ```
//! use microfrep_io::precision::{check_grid, f32_step};
//! assert!(check_grid([-1.0; 3], [1.0; 3], 0.01).is_ok());
//! // A unit part a million millimetres from the origin.
//! let e = check_grid([1e6 - 1.0, -1.0, -1.0], [1e6 + 1.0, 1.0, 1.0], 0.03).unwrap_err();
//! assert!(e.to_string().contains("origin"), "{e}");
//! assert_eq!(f32_step(1e6), 0.0625);
//! ```

/// Largest coordinate a sampling box may reach (its square still fits f32
/// with room to spare).
pub const MAX_COORDINATE: f64 = 1e15;

/// f32 steps a cell must span at the box's largest coordinate: positions
/// inside a cell (vertices, roots, sub-samples) are then placed to 1/64 of
/// a cell or better.
pub const MIN_STEPS_PER_CELL: f64 = 64.0;

/// Why a grid or a model cannot be sampled in f32.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct PrecisionError(pub String);

/// The distance from `|x|` (as f32) to the next larger f32.
pub fn f32_step(x: f64) -> f64 {
    let f = (x.abs() as f32).min(f32::MAX / 2.0);
    (f32::from_bits(f.to_bits() + 1) - f) as f64
}

/// Checks that a grid over the box `lo..hi` with cells of side `cell` (the
/// smallest cell side) can be sampled with f32 coordinates: every bound
/// finite and within [`MAX_COORDINATE`], `lo < hi`, and the cell at least
/// [`MIN_STEPS_PER_CELL`] f32 steps wide at the largest coordinate of the
/// box (plus two cells of padding) and a normal f32. The message says
/// which limit is broken and what to change.
pub fn check_grid(lo: [f64; 3], hi: [f64; 3], cell: f64) -> Result<(), PrecisionError> {
    for a in 0..3 {
        let name = ["x", "y", "z"][a];
        for v in [lo[a], hi[a]] {
            if !v.is_finite() {
                return Err(PrecisionError(format!(
                    "the box's {name} bound {v} is not a finite number"
                )));
            }
            if v.abs() > MAX_COORDINATE {
                return Err(PrecisionError(format!(
                    "the box's {name} bound {v:e} is beyond what the sampling grids represent \
                     (|v| <= {MAX_COORDINATE:e})"
                )));
            }
        }
        if lo[a] >= hi[a] {
            return Err(PrecisionError(format!(
                "the box's {name} range {} .. {} is empty (min must be below max)",
                lo[a], hi[a]
            )));
        }
    }
    if !(cell.is_finite() && cell > 0.0) {
        return Err(PrecisionError(format!(
            "cell size {cell} must be a positive number"
        )));
    }
    let tiny = MIN_STEPS_PER_CELL * f32::MIN_POSITIVE as f64;
    if cell < tiny {
        return Err(PrecisionError(format!(
            "cells of {cell:e} are below what 32-bit floats resolve (at least {tiny:.1e}); \
             scale the model up (e.g. to millimetres)"
        )));
    }
    let far = (0..3)
        .map(|a| lo[a].abs().max(hi[a].abs()))
        .fold(0.0, f64::max)
        + 2.0 * cell;
    let step = f32_step(far);
    if cell < MIN_STEPS_PER_CELL * step {
        let centre: [f64; 3] = std::array::from_fn(|a| 0.5 * (lo[a] + hi[a]));
        let c = centre.map(|v| crate::text::sig(v, 6)).join(", ");
        return Err(PrecisionError(format!(
            "cells of {} are too fine for 32-bit coordinates {} from the origin (steps of {} \
             there; cells must be at least {}): the box is centred at ({c}); move the model \
             nearer the origin, or use coarser cells",
            crate::text::sig(cell, 4),
            crate::text::sig(far, 4),
            crate::text::sig(step, 4),
            crate::text::sig(MIN_STEPS_PER_CELL * step, 4),
        )));
    }
    Ok(())
}

/// `n` probe points spread evenly over the box (a quasi-random R3
/// sequence, so they line up with no grid or plane of the model).
pub fn probe_points(lo: [f64; 3], hi: [f64; 3], n: usize) -> Vec<[f64; 3]> {
    // The plastic number's powers give the R3 low-discrepancy sequence.
    let g = 1.220_744_084_605_759_5_f64;
    let alpha = [1.0 / g, 1.0 / (g * g), 1.0 / (g * g * g)];
    (0..n)
        .map(|i| {
            std::array::from_fn(|a| {
                let t = (0.5 + alpha[a] * (i as f64 + 1.0)).fract();
                lo[a] + t * (hi[a] - lo[a])
            })
        })
        .collect()
}

/// Probe points per check of [`check_agreement`] (callers evaluate them
/// twice: f32 batch and f64 point).
pub const PROBE_POINTS: usize = 4096;

/// Compares a model's f32 batch values `v32` with its f64 values `v64` at
/// the same probe points: inside (`>= 0`), outside and NaN must agree,
/// except where the f64 value is within rounding of zero (below 1e-4 of the
/// median magnitude). More than 1 % of the points (and at least 3)
/// disagreeing means f32 cannot resolve the model (values that underflow or
/// overflow in f32): an error that says so, with an example point.
pub fn check_agreement(
    points: &[[f64; 3]],
    v32: &[f32],
    v64: &[f64],
) -> Result<(), PrecisionError> {
    let mut mags: Vec<f64> = v64
        .iter()
        .filter(|v| v.is_finite() && **v != 0.0)
        .map(|v| v.abs())
        .collect();
    if mags.is_empty() {
        return Ok(());
    }
    let mid = mags.len() / 2;
    let median = *mags.select_nth_unstable_by(mid, f64::total_cmp).1;
    let tol = 1e-4 * median;
    let class = |v: f64| -> u8 {
        if v.is_nan() {
            2
        } else {
            (v >= 0.0) as u8
        }
    };
    let mut bad = 0usize;
    let mut first = None;
    for (i, (&a, &b)) in v32.iter().zip(v64).enumerate() {
        let disagree = class(a as f64) != class(b) && !(b.is_finite() && b.abs() <= tol);
        if disagree {
            bad += 1;
            first.get_or_insert(i);
        }
    }
    let n = v32.len().min(v64.len());
    if bad >= 3 && bad as f64 > 0.01 * n as f64 {
        let i = first.unwrap_or(0);
        let p = points.get(i).copied().unwrap_or([f64::NAN; 3]);
        let p = p.map(|v| crate::text::sig(v, 6)).join(", ");
        return Err(PrecisionError(format!(
            "32-bit evaluation cannot resolve this model: its inside/outside differs from the \
             64-bit reference at {bad} of {n} probe points (e.g. at ({p}): f32 gives {}, f64 \
             gives {}); the values (typically {}) underflow or overflow in f32; rescale the \
             model (e.g. to millimetres)",
            crate::text::sig(v32[i] as f64, 4),
            crate::text::sig(v64[i], 4),
            crate::text::sig(median, 3)
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boxes_near_the_origin_pass_and_far_or_huge_ones_fail() {
        assert!(check_grid([-1.0; 3], [1.0; 3], 1e-4).is_ok());
        // A 300 mm build plate in 25 micrometre pixels.
        assert!(check_grid([0.0; 3], [300.0; 3], 0.025).is_ok());
        let far = check_grid([1e6 - 1.0, -1.0, -1.0], [1e6 + 1.0, 1.0, 1.0], 2.0 / 64.0);
        assert!(far
            .unwrap_err()
            .0
            .contains("move the model nearer the origin"));
        let huge = check_grid([-1e300; 3], [1e300; 3], 1e298).unwrap_err();
        assert!(huge.0.contains("beyond"), "{huge}");
        let tiny = check_grid([-1e-50; 3], [1e-50; 3], 1e-52).unwrap_err();
        assert!(tiny.0.contains("scale the model up"), "{tiny}");
        assert!(check_grid([0.0; 3], [f64::NAN; 3], 0.1).is_err());
        assert!(check_grid([0.0; 3], [1.0, 0.0, 1.0], 0.1).is_err());
        assert!(check_grid([0.0; 3], [1.0; 3], 0.0).is_err());
    }

    #[test]
    fn f32_steps_are_powers_of_two() {
        assert_eq!(f32_step(1.0), f32::EPSILON as f64);
        assert_eq!(f32_step(1e6), 0.0625);
        assert_eq!(f32_step(-1e6), 0.0625);
    }

    #[test]
    fn probe_points_fill_the_box() {
        let p = probe_points([0.0, -2.0, 10.0], [1.0, 2.0, 11.0], 1000);
        for a in 0..3 {
            let lo = p.iter().map(|q| q[a]).fold(f64::INFINITY, f64::min);
            let hi = p.iter().map(|q| q[a]).fold(f64::NEG_INFINITY, f64::max);
            let (l, h) = ([0.0, -2.0, 10.0][a], [1.0, 2.0, 11.0][a]);
            assert!(lo >= l && hi <= h && lo < l + 0.01 * (h - l) && hi > h - 0.01 * (h - l));
        }
    }

    #[test]
    fn agreement_tolerates_rounding_near_zero_and_refuses_underflow() {
        let pts = probe_points([-1.0; 3], [1.0; 3], 1000);
        // A sphere: f32 and f64 agree.
        let f = |p: &[f64; 3]| 0.5 - (p[0] * p[0] + p[1] * p[1] + p[2] * p[2]);
        let v64: Vec<f64> = pts.iter().map(f).collect();
        let v32: Vec<f32> = v64.iter().map(|&v| v as f32).collect();
        assert!(check_agreement(&pts, &v32, &v64).is_ok());
        // The same sphere scaled by 1e-25: f32 values underflow to zero.
        let tiny: Vec<f64> = v64.iter().map(|v| v * 1e-50).collect();
        let zero = vec![0.0f32; tiny.len()];
        let e = check_agreement(&pts, &zero, &tiny).unwrap_err();
        assert!(e.0.contains("underflow"), "{e}");
        // NaN in both is agreement; NaN in f32 only is not.
        let nan64 = vec![f64::NAN; 1000];
        let nan32 = vec![f32::NAN; 1000];
        assert!(check_agreement(&pts, &nan32, &nan64).is_ok());
        assert!(check_agreement(&pts, &nan32, &v64).is_err());
    }
}
