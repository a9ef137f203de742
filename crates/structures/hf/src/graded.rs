//! Functionally graded materials (Park, Crawford, Beaman; `microfrep-graded`):
//! density modulation, Park's smooth n-ary set operations, depth below a
//! surface and Bernstein-Bezier data fields.

use crate::args::{code, out, three, value, Built};
use microfrep_core::Expr;
use microfrep_graded::bezier::{tet_weight_count, BezierBox, BezierTet};
use microfrep_graded::subspace::Subspace;
use microfrep_graded::{depth, dmf, smooth};
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use std::sync::Arc;

/// The numbers of an array argument that must be constants.
fn constants(a: &Arg, what: &str, len: Option<usize>) -> Result<Vec<f64>, Output> {
    let v = a.array();
    if let Some(n) = len {
        if v.len() != n {
            return Err(Output::error(format!(
                "{what} must be an array of {n} elements, not {}",
                v.len()
            )));
        }
    }
    v.iter()
        .map(|e| e.as_const().ok_or_else(Output::needs_constants))
        .collect()
}

/// `mfBias(t, b)`.
fn bias(a: &[Arg]) -> Output {
    Output::value(dmf::bias(&a[0].real(), a[1].real()))
}

/// `mfGain(t, g)`.
fn gain(a: &[Arg]) -> Output {
    Output::value(dmf::gain(&a[0].real(), a[1].real()))
}

/// `mfBiasGain(t, b, g)`: Park's cascade `gain(bias(t, b), g)`.
fn bias_gain(a: &[Arg]) -> Output {
    Output::value(dmf::sketch(&a[0].real(), a[1].real(), a[2].real()))
}

fn operands(a: &Arg, what: &str) -> Result<Vec<Expr>, Output> {
    let f = a.array().to_vec();
    if f.is_empty() {
        return Err(Output::error(format!("{what} needs at least one function")));
    }
    Ok(f)
}

/// `mfUnionA(f, a)` over the array `f`.
fn union_a(a: &[Arg]) -> Output {
    out(|| value(smooth::union_a(&operands(&a[0], "mfUnionA")?, a[1].real())))
}

/// `mfIntersectA(f, a)` over the array `f`.
fn intersect_a(a: &[Arg]) -> Output {
    out(|| {
        value(smooth::intersect_a(
            &operands(&a[0], "mfIntersectA")?,
            a[1].real(),
        ))
    })
}

/// `mfDepth(F)`: the normalised function as a depth below `F = 0`.
fn depth_fn(a: &[Arg]) -> Output {
    Output::value(depth::depth(&a[0].real()))
}

/// The box `[x0, y0, z0, x1, y1, z1]`.
fn boxed(a: &Arg) -> Result<([f64; 3], [f64; 3]), Output> {
    let b = constants(a, "box", Some(6))?;
    Ok(([b[0], b[1], b[2]], [b[3], b[4], b[5]]))
}

fn degrees(a: &[Arg]) -> Result<[usize; 3], Output> {
    let d = |i: usize, what: &str| {
        code(&a[i], what, 0, microfrep_graded::bezier::MAX_DEGREE as i64).map(|v| v as usize)
    };
    Ok([d(2, "degree l")?, d(3, "degree m")?, d(4, "degree n")?])
}

/// `mfBezier3(x, box, l, m, n, w)` with control weights.
fn bezier3(a: &[Arg]) -> Output {
    out(|| -> Built {
        let x = three(&a[0], "x")?;
        let (min, max) = boxed(&a[1])?;
        let deg = degrees(a)?;
        let w = constants(&a[5], "w", None)?;
        let f = BezierBox::new("mfBezier3", min, max, deg, w)
            .map_err(|e| Output::error(e.to_string()))?;
        value(Expr::field_at(Arc::new(f), x))
    })
}

/// `mfBezier3Fit(x, box, l, m, n, s)` through samples on the grid.
fn bezier3_fit(a: &[Arg]) -> Output {
    out(|| -> Built {
        let x = three(&a[0], "x")?;
        let (min, max) = boxed(&a[1])?;
        let deg = degrees(a)?;
        let s = constants(&a[5], "s", None)?;
        let f = BezierBox::interpolate("mfBezier3Fit", min, max, deg, &s)
            .map_err(|e| Output::error(e.to_string()))?;
        value(Expr::field_at(Arc::new(f), x))
    })
}

/// `mfBezierTet(x, v, m, w)`: `v` the 12 vertex coordinates.
fn bezier_tet(a: &[Arg]) -> Output {
    out(|| -> Built {
        let x = three(&a[0], "x")?;
        let v = constants(&a[1], "v", Some(12))?;
        let m = code(
            &a[2],
            "degree m",
            0,
            microfrep_graded::bezier::MAX_DEGREE as i64,
        )? as usize;
        let w = constants(&a[3], "w", Some(tet_weight_count(m)))?;
        let verts = std::array::from_fn(|r| [v[3 * r], v[3 * r + 1], v[3 * r + 2]]);
        let f =
            BezierTet::new("mfBezierTet", verts, m, w).map_err(|e| Output::error(e.to_string()))?;
        value(Expr::field_at(Arc::new(f), x))
    })
}

/// `mfSubspace(s, region, fraction, material, base)`: a material subspace
/// (Park et al. Sec. 2.3, 3.1; `microfrep_graded::subspace::Subspace`) laid
/// over the composition in the attribute array `s`. Where `region >= 0`,
/// `s[material]` becomes `fraction` clamped to [0, 1], `s[base]` the rest
/// and every other element 0; elsewhere `s` keeps its values. `material`
/// and `base` are 1-based *constants*, different, within `s`. Returns 1.
fn subspace(a: &[Arg]) -> Output {
    out(|| -> Built {
        let prior = a[0].array().to_vec();
        let n = prior.len() as i64;
        if n < 2 {
            return Err(Output::error(format!(
                "the material array s must have at least 2 elements \
                 (one per material), not {n}"
            )));
        }
        let material = code(&a[3], "material", 1, n)? as usize - 1;
        let base = code(&a[4], "base", 1, n)? as usize - 1;
        if material == base {
            return Err(Output::error(format!(
                "material and base are both {} (the base material takes \
                 the rest of the graded one, so they must differ)",
                material + 1
            )));
        }
        let sub = Subspace::new(a[1].real(), Expr::xyz(), a[2].real(), material).with_base(base);
        let comp = sub.over(&prior, base);
        Ok(Output::writes(Expr::constant(1.0), vec![(0, comp)]))
    })
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mfbias", &[R, R], bias);
    r.register("mfgain", &[R, R], gain);
    r.register("mfbiasgain", &[R, R, R], bias_gain);
    r.register("mfuniona", &[A, R], union_a);
    r.register("mfintersecta", &[A, R], intersect_a);
    r.register("mfdepth", &[R], depth_fn);
    r.register("mfbezier3", &[A, A, R, R, R, A], bezier3);
    r.register("mfbezier3fit", &[A, A, R, R, R, A], bezier3_fit);
    r.register("mfbeziertet", &[A, A, R, A], bezier_tet);
    r.register("mfsubspace", &[A, R, R, R, R], subspace);
}
