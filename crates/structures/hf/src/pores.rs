//! Kou and Tan's irregular porous structures: `mfPores` (3D, octree cells,
//! Doo-Sabin pores) and `mfPores2` (2D in the xy plane, quadtree cells,
//! closed quadratic B-spline pores, extruded along z). Both return the part
//! `F >= 0` minus its pores; the structure is built when the model is
//! loaded, from the part's proven bounds.

use crate::args::three;
use microfrep_core::Expr;
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_pores::{part_bounds, Dim, Options, Pores, Spec};

/// The seed argument: a constant integer in [0, 2^53).
fn seed(a: &Arg) -> Result<u64, Output> {
    match a.real().as_const() {
        Some(v) if v.fract() == 0.0 && (0.0..9_007_199_254_740_992.0).contains(&v) => Ok(v as u64),
        Some(v) => Err(Output::error(format!(
            "seed must be a whole number from 0 to 2^53, not {v}"
        ))),
        None => Err(Output::error(
            "seed must be a constant (the same seed gives the same structure)",
        )),
    }
}

/// The point, the part and the seed of a pore call.
fn common(a: &[Arg]) -> Result<([Expr; 3], Expr, u64), Output> {
    let x = three(&a[0], "x")?;
    let part = a[1].real();
    if part.as_const().is_some() {
        return Err(Output::error(
            "the part F must be an expression of the coordinates (the model must lower \
             to a graph; `microfrep check` says which path it takes)",
        ));
    }
    Ok((x, part, seed(&a[4])?))
}

fn build(a: &[Arg], dim: Dim) -> Output {
    crate::args::out(|| {
        let (x, part, seed) = common(a)?;
        let bounds = part_bounds(&part).map_err(|e| Output::error(e.to_string()))?;
        let opts = match dim {
            Dim::Two => Options::two_d(),
            Dim::Three => Options::default(),
        };
        let built = Pores::build(
            &part,
            bounds,
            Spec::from(a[2].real()),
            Spec::from(a[3].real()),
            seed,
            &opts,
        )
        .map_err(|e| Output::error(e.to_string()))?;
        Ok(Output::value(part.min(Expr::field_at(built.field, x))))
    })
}

/// `mfPoreField(x, F, size, porosity, seed, box)`: the pore field alone
/// (positive in the solid, negative in the pores) of the 3D structure built
/// for the part `F` with its cells laid on `box = [x0, y0, z0, x1, y1, z1]`
/// (the part's exact box, as `microfrep fill` writes it), not on the
/// part's proven bounds.
fn pore_field(a: &[Arg]) -> Output {
    crate::args::out(|| {
        let (x, part, seed) = common(a)?;
        let b = a[5].array();
        if b.len() != 6 {
            return Err(Output::error(format!(
                "box must be an array of 6 numbers [x0, y0, z0, x1, y1, z1], not {}",
                b.len()
            )));
        }
        let mut v = [0.0; 6];
        for (i, e) in b.iter().enumerate() {
            v[i] = e.as_const().ok_or_else(Output::needs_constants)?;
        }
        let bounds = [[v[0], v[1], v[2]], [v[3], v[4], v[5]]];
        let built = Pores::build(
            &part,
            bounds,
            Spec::from(a[2].real()),
            Spec::from(a[3].real()),
            seed,
            &Options::default(),
        )
        .map_err(|e| Output::error(e.to_string()))?;
        Ok(Output::value(Expr::field_at(built.field, x)))
    })
}

/// `mfPores(x, F, size, porosity, seed)`.
fn pores3(a: &[Arg]) -> Output {
    build(a, Dim::Three)
}

/// `mfPores2(x, F, size, porosity, seed)`.
fn pores2(a: &[Arg]) -> Output {
    build(a, Dim::Two)
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mfpores", &[A, R, R, R, R], pores3);
    r.register("mfpores2", &[A, R, R, R, R], pores2);
    r.register("mfporefield", &[A, R, R, R, R, A], pore_field);
}
