//! Pasko et al. 2009: rod lattices (Eqs. 4-7), shell with infill (Eq. 8),
//! depth grading, porous media (Eq. 9) and noise, plus the R-functions with
//! a selectable `alpha` that those equations use.

use crate::args::{code, out, three, value, Built};
use microfrep_core::frep::{
    blend_intersection, blend_union, intersection, normalize, subtraction, union, Blend,
};
use microfrep_core::noise::gradient_noise;
use microfrep_core::Expr;
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_structures::infill::{graded_by_depth, shell_with_infill, Depth, Join};
use microfrep_structures::lattice::{
    blended_rod_lattice, rod_lattice, rod_lattice_blended_rods, Slabs,
};
use microfrep_structures::porous::PeriodicMap;
use microfrep_structures::variable::ramp;

/// Slabs from `(x, q, p, l)` with scalar (same on every axis) parameters.
fn slabs_uniform(a: &[Arg]) -> Slabs {
    let (q, p, l) = (a[1].real(), a[2].real(), a[3].real());
    Slabs {
        q: [q.clone(), q.clone(), q],
        p: [p.clone(), p.clone(), p],
        l: [l.clone(), l.clone(), l],
    }
}

fn blend(a: &[Arg], first: usize) -> Blend {
    Blend::new(a[first].real(), a[first + 1].real(), a[first + 2].real())
}

/// `mfLattice(x, q, p, l, alpha)`.
fn lattice(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        value(rod_lattice(&x, &slabs_uniform(a), a[4].real()))
    })
}

/// `mfLattice3(x, q, p, l, alpha)` with per-axis arrays.
fn lattice3(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let s = Slabs {
            q: three(&a[1], "q")?,
            p: three(&a[2], "p")?,
            l: three(&a[3], "l")?,
        };
        value(rod_lattice(&x, &s, a[4].real()))
    })
}

/// `mfLatticeBlend(x, q, p, l, alpha, a0, a1, a2)`: rods are blended
/// intersections (Fig. 2d).
fn lattice_blend(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let e = rod_lattice_blended_rods(&x, &slabs_uniform(a), a[4].real(), &blend(a, 5));
        value(e)
    })
}

/// `mfLatticeFillet(x, q, p, l, alpha, a0, a1, a2)`: rods joined by the
/// blended union (fillets at the junctions, Fig. 3b).
fn lattice_fillet(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        value(blended_rod_lattice(
            &x,
            &slabs_uniform(a),
            a[4].real(),
            &blend(a, 5),
        ))
    })
}

/// `mfShellInfill(F, lo, g, alpha)`.
fn shell_infill(a: &[Arg]) -> Output {
    let (f, lo, g) = (a[0].real(), a[1].real(), a[2].real());
    Output::value(shell_with_infill(&f, lo, &g, a[3].real(), &Join::Plain))
}

/// `mfShellInfillBlend(F, lo, g, alpha, a0, a1, a2)`.
fn shell_infill_blend(a: &[Arg]) -> Output {
    let (f, lo, g) = (a[0].real(), a[1].real(), a[2].real());
    let join = Join::Blended(blend(a, 4));
    Output::value(shell_with_infill(&f, lo, &g, a[3].real(), &join))
}

fn normalize_fn(a: &[Arg]) -> Output {
    Output::value(normalize(&a[0].real()))
}

/// `mfOffsetN(f, d)`: Fryazinov Eq. 14.
fn offset_n(a: &[Arg]) -> Output {
    Output::value(normalize(&a[0].real()) + a[1].real())
}

/// `mfGrade(depth, d, at_surface, at_depth)`.
fn grade(a: &[Arg]) -> Output {
    Output::value(graded_by_depth(
        &a[0].real(),
        Depth::Function,
        a[1].real(),
        a[2].real(),
        a[3].real(),
    ))
}

/// `mfRamp(t, t0, t1)`.
fn ramp_fn(a: &[Arg]) -> Output {
    Output::value(ramp(&a[0].real(), a[1].real(), a[2].real()))
}

fn pore_map_with(a: &[Arg], map: PeriodicMap) -> Built {
    let x = three(&a[0], "x")?;
    Ok(Output::writes(
        Expr::constant(1.0),
        vec![(0, map.map(&x).to_vec())],
    ))
}

/// `mfPoreMap(x, p, q)`: x_i <- p sin(q x_i) in place.
fn pore_map(a: &[Arg]) -> Output {
    out(|| pore_map_with(a, PeriodicMap::uniform(a[1].real(), a[2].real())))
}

/// `mfPoreMap3(x, p, q)` with per-axis arrays.
fn pore_map3(a: &[Arg]) -> Output {
    out(|| {
        let map = PeriodicMap {
            amp: three(&a[1], "p")?,
            freq: three(&a[2], "q")?,
        };
        pore_map_with(a, map)
    })
}

/// `mfNoise(x, amp, freq, seed)`: seeded gradient noise in [-2 amp, 2 amp].
fn noise(a: &[Arg]) -> Output {
    out(|| {
        let x = three(&a[0], "x")?;
        let seed = code(&a[3], "seed", 0, 1 << 31)?;
        let f = a[2].real();
        let p = x.map(|c| c * &f);
        value(a[1].real() * gradient_noise(&p, seed as u64))
    })
}

fn uni(a: &[Arg]) -> Output {
    Output::value(union(&a[0].real(), &a[1].real(), a[2].real()))
}

fn int(a: &[Arg]) -> Output {
    Output::value(intersection(&a[0].real(), &a[1].real(), a[2].real()))
}

fn sub(a: &[Arg]) -> Output {
    Output::value(subtraction(&a[0].real(), &a[1].real(), a[2].real()))
}

fn blend_uni(a: &[Arg]) -> Output {
    let b = blend(a, 3);
    Output::value(blend_union(&a[0].real(), &a[1].real(), &b, a[2].real()))
}

fn blend_int(a: &[Arg]) -> Output {
    let b = blend(a, 3);
    Output::value(blend_intersection(
        &a[0].real(),
        &a[1].real(),
        &b,
        a[2].real(),
    ))
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mflattice", &[A, R, R, R, R], lattice);
    r.register("mflattice3", &[A, A, A, A, R], lattice3);
    r.register("mflatticeblend", &[A, R, R, R, R, R, R, R], lattice_blend);
    r.register("mflatticefillet", &[A, R, R, R, R, R, R, R], lattice_fillet);
    r.register("mfshellinfill", &[R, R, R, R], shell_infill);
    r.register(
        "mfshellinfillblend",
        &[R, R, R, R, R, R, R],
        shell_infill_blend,
    );
    r.register("mfnormalize", &[R], normalize_fn);
    r.register("mfoffsetn", &[R, R], offset_n);
    r.register("mfgrade", &[R, R, R, R], grade);
    r.register("mframp", &[R, R, R], ramp_fn);
    r.register("mfporemap", &[A, R, R], pore_map);
    r.register("mfporemap3", &[A, A, A], pore_map3);
    r.register("mfnoise", &[A, R, R, R], noise);
    r.register("mfunion", &[R, R, R], uni);
    r.register("mfintersect", &[R, R, R], int);
    r.register("mfsubtract", &[R, R, R], sub);
    r.register("mfblendunion", &[R, R, R, R, R, R], blend_uni);
    r.register("mfblendintersect", &[R, R, R, R, R, R], blend_int);
}
