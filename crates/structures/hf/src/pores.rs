//! Kou and Tan's irregular porous structures: `mfPores` (3D, octree cells,
//! Doo-Sabin pores) and `mfPores2` (2D in the xy plane, quadtree cells,
//! closed quadratic B-spline pores, extruded along z). Both return the part
//! `F >= 0` minus its pores; the structure is built when the model is
//! loaded, from the part's proven bounds.
//!
//! `mfPoresOpt` and `mfPores2Opt` are the same calls with a sixth
//! argument, an array of the paper's controls (the registry has no
//! optional arguments, hence the second names); see [`opts`].

use crate::args::three;
use microfrep_core::Expr;
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_pores::{part_bounds, Dim, HandSet, Options, Pores, SizeMeasure, Spec, Subdivision};

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

/// The names of the elements of the options array, in order.
const OPT_NAMES: [&str; 6] = [
    "irregularity",
    "parent_scale",
    "subdivision",
    "weight",
    "size_measure",
    "opening",
];

/// The options array of `mfPoresOpt` / `mfPores2Opt`: 1 to 6 constants,
/// `[irregularity, parent_scale, subdivision, weight, size_measure,
/// opening]`; elements left off keep their defaults.
///
/// - `irregularity` in [0, 0.5] (default 0.15): spread of the random
///   derived points; 0 gives identical regular pores.
/// - `parent_scale`: parent polygon / polyhedron over the cell (default 1
///   in 2D, in [1, 4/3); 1.6 in 3D, in [4/3, 2]).
/// - `subdivision`: 0 quadtree / octree (default), 1 T-mesh (cells cut in
///   two at half their longest side).
/// - `weight` (2D; default 1): corner weight of the rational quadratic
///   arcs of the pore curve, any number above 0; 3D takes only 1.
/// - `size_measure`: 0 (default) `size` is the cell edge, 1 it is the
///   paper's cell area (2D) / volume (3D) per pore, `m/P`.
/// - `opening` (3D; default 0.05) in [0, 0.25]: reach of opened pores past
///   the face centres (0: the plain Doo-Sabin pores, closed below 0.6274).
///
/// After all six, the derived points may be set by hand, the same in every
/// cell: in 2D three distances (fractions of the sides in (0, 1); Eq. 8
/// gives the fourth), in 3D the 24 Eq. 9 parameters `t[s][k]` (vertex by
/// vertex, axis by axis; they fix the shape, and its scale meets the
/// porosity). `irregularity` is then not used.
fn opts(a: &Arg, dim: Dim) -> Result<Options, Output> {
    let v = a.array();
    // After the six controls, the hand-set derived points: three
    // distances in 2D, the 24 t values in 3D.
    let hand = match dim {
        Dim::Two => 3,
        Dim::Three => 24,
    };
    if v.is_empty() || (v.len() > OPT_NAMES.len() && v.len() != OPT_NAMES.len() + hand) {
        return Err(Output::error(format!(
            "opts must be an array of 1 to 6 numbers [irregularity, parent_scale, \
             subdivision, weight, size_measure, opening], or those 6 and {hand} hand-set {}, \
             not {}",
            if hand == 3 { "distances" } else { "t values" },
            v.len()
        )));
    }
    let mut set = Vec::new();
    for (i, e) in v.iter().enumerate().skip(OPT_NAMES.len()) {
        set.push(e.as_const().ok_or_else(|| {
            Output::error(format!(
                "opts[{}] (a hand-set value) must be a constant known when the model is loaded",
                i + 1
            ))
        })?);
    }
    let mut o = match dim {
        Dim::Two => Options::two_d(),
        Dim::Three => Options::default(),
    };
    for (i, e) in v.iter().enumerate().take(OPT_NAMES.len()) {
        let name = OPT_NAMES[i];
        let Some(x) = e.as_const() else {
            return Err(Output::error(format!(
                "opts[{}] ({name}) must be a constant known when the model is loaded",
                i + 1
            )));
        };
        let bad = |why: &str| {
            Err(Output::error(format!(
                "opts[{}] ({name}) = {x}: {why}",
                i + 1
            )))
        };
        match i {
            0 => o.irregularity = x,
            1 => o.parent_scale = Some(x),
            2 => {
                o.subdivision = match x {
                    0.0 => Subdivision::Tree,
                    1.0 => Subdivision::TMesh { percent: 0.5 },
                    _ => return bad("must be 0 (quadtree / octree) or 1 (T-mesh)"),
                }
            }
            3 => o.weight = x,
            4 => {
                o.size_measure = match x {
                    0.0 => SizeMeasure::Edge,
                    1.0 => SizeMeasure::PerPore,
                    _ => {
                        return bad(
                            "must be 0 (size is the cell edge) or 1 (area / volume per pore)",
                        )
                    }
                }
            }
            _ => o.opening = x,
        }
    }
    if !set.is_empty() {
        o.hand_set = Some(match dim {
            Dim::Two => HandSet::Distances([set[0], set[1], set[2]]),
            Dim::Three => HandSet::T(std::array::from_fn(|v| {
                std::array::from_fn(|k| set[3 * v + k])
            })),
        });
    }
    Ok(o)
}

/// A build error; an option out of its range is named by its element of
/// the options array when there is one.
fn build_error(e: microfrep_pores::PoreError, with_opts: bool) -> Output {
    if let microfrep_pores::PoreError::Option { name, value, why } = &e {
        if let Some(i) = OPT_NAMES
            .iter()
            .position(|n| n == name)
            .filter(|_| with_opts)
        {
            return Output::error(format!("opts[{}] ({name}) = {value}: {why}", i + 1));
        }
    }
    Output::error(e.to_string())
}

fn build(a: &[Arg], dim: Dim) -> Output {
    crate::args::out(|| {
        let (x, part, seed) = common(a)?;
        let opts = match a.get(5) {
            Some(o) => opts(o, dim)?,
            None => match dim {
                Dim::Two => Options::two_d(),
                Dim::Three => Options::default(),
            },
        };
        let bounds = part_bounds(&part).map_err(|e| Output::error(e.to_string()))?;
        let built = Pores::build(
            &part,
            bounds,
            Spec::from(a[2].real()),
            Spec::from(a[3].real()),
            seed,
            &opts,
        )
        .map_err(|e| build_error(e, a.len() > 5))?;
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
        let options = match a.get(6) {
            Some(o) => opts(o, Dim::Three)?,
            None => Options::default(),
        };
        let built = Pores::build(
            &part,
            bounds,
            Spec::from(a[2].real()),
            Spec::from(a[3].real()),
            seed,
            &options,
        )
        .map_err(|e| build_error(e, a.len() > 6))?;
        Ok(Output::value(Expr::field_at(built.field, x)))
    })
}

/// `mfPoreFieldOpt(x, F, size, porosity, seed, box, opts)`: `mfPoreField`
/// with the options array of `mfPoresOpt` ([`opts`]), as `microfrep fill`
/// writes it when the paper's controls are set.
fn pore_field_opt(a: &[Arg]) -> Output {
    pore_field(a)
}

/// `mfPores(x, F, size, porosity, seed)`.
fn pores3(a: &[Arg]) -> Output {
    build(a, Dim::Three)
}

/// `mfPores2(x, F, size, porosity, seed)`.
fn pores2(a: &[Arg]) -> Output {
    build(a, Dim::Two)
}

/// `mfPoresOpt(x, F, size, porosity, seed, opts)`: `mfPores` with the
/// options array `opts` ([`opts`]), e.g.
/// `array o[4]; o = [0.3, 1.8, 1, 1]; my_model = mfPoresOpt(x, b, 0.5, 0.7, 1, o);`.
fn pores3_opt(a: &[Arg]) -> Output {
    build(a, Dim::Three)
}

/// `mfPores2Opt(x, F, size, porosity, seed, opts)`: `mfPores2` with the
/// options array `opts` ([`opts`]), e.g. rounder rational pores:
/// `array o[4]; o = [0.15, 1, 0, 0.7071]; my_model = mfPores2Opt(x, b, 0.5, 0.6, 1, o);`.
fn pores2_opt(a: &[Arg]) -> Output {
    build(a, Dim::Two)
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mfpores", &[A, R, R, R, R], pores3);
    r.register("mfpores2", &[A, R, R, R, R], pores2);
    r.register("mfporesopt", &[A, R, R, R, R, A], pores3_opt);
    r.register("mfpores2opt", &[A, R, R, R, R, A], pores2_opt);
    r.register("mfporefield", &[A, R, R, R, R, A], pore_field);
    r.register("mfporefieldopt", &[A, R, R, R, R, A, A], pore_field_opt);
}
