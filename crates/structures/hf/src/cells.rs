//! Fryazinov et al.: replicating functions (Eqs. 1-3, 10-11), unit-cell
//! replication in place, metamorphosis, transfinite interpolation between
//! space partitions, and surficial structures (Eqs. 12-14).

use crate::args::{code, out, three, value};
use microfrep_core::frep::{intersection, sawtooth, triangle};
use microfrep_core::Expr;
use microfrep_hyperfun::library::{Arg, Kind::*, Output, Registry};
use microfrep_structures::infill::Depth;
use microfrep_structures::replicate::{replicate_box, Wave};
use microfrep_structures::surficial::shell;
use microfrep_structures::variable::{
    metamorphosis, partition_distance, transfinite, transfinite_weights,
};

fn saw(a: &[Arg]) -> Output {
    Output::value(sawtooth(&a[0].real(), a[1].real()))
}

fn tri(a: &[Arg]) -> Output {
    Output::value(triangle(&a[0].real(), a[1].real()))
}

/// Maps the point `x` into the box `lo`, `hi` with one wave per axis; the
/// result is written back into `x` (argument 0), as HyperFun's space
/// mappings do.
fn map_into(x: &Arg, lo: &Arg, hi: &Arg, waves: [Wave; 3]) -> Result<Output, Output> {
    let x = three(x, "x")?;
    let lo = three(lo, "bmin")?;
    let hi = three(hi, "bmax")?;
    let q = replicate_box(&x, &waves, &lo, &hi);
    Ok(Output::writes(Expr::constant(1.0), vec![(0, q.to_vec())]))
}

/// `mfSawtoothMap(x, a, bmin, bmax)`.
fn saw_map(a: &[Arg]) -> Output {
    let p = a[1].real();
    let waves = std::array::from_fn(|_| Wave::Sawtooth(p.clone()));
    out(|| map_into(&a[0], &a[2], &a[3], waves))
}

/// `mfTriangleMap(x, a, bmin, bmax)`.
fn tri_map(a: &[Arg]) -> Output {
    let p = a[1].real();
    let waves = std::array::from_fn(|_| Wave::Triangle(p.clone()));
    out(|| map_into(&a[0], &a[2], &a[3], waves))
}

/// `mfReplicate(x, kind, a, bmin, bmax)`: per-axis kind codes (0 none,
/// 1 sawtooth, 2 triangle) and periods.
fn replicate(a: &[Arg]) -> Output {
    out(|| {
        let kinds = a[1].array();
        if kinds.len() != 3 {
            return Err(Output::error(format!(
                "kind must be an array of 3 elements, not {}",
                kinds.len()
            )));
        }
        let periods = three(&a[2], "a")?;
        let mut waves = Vec::new();
        for (k, p) in kinds.iter().zip(periods) {
            waves.push(
                match code(&Arg::Real(k.clone()), "replication kind", 0, 2)? {
                    0 => Wave::Identity,
                    1 => Wave::Sawtooth(p),
                    _ => Wave::Triangle(p),
                },
            );
        }
        let waves: [Wave; 3] = waves.try_into().expect("three waves");
        map_into(&a[0], &a[3], &a[4], waves)
    })
}

/// `mfMorph(f1, f2, t)`.
fn morph(a: &[Arg]) -> Output {
    Output::value(metamorphosis(&a[0].real(), &a[1].real(), &a[2].real()))
}

fn same_length(u: &[Expr], d: &[Expr]) -> Result<(), Output> {
    if d.is_empty() || u.len() != d.len() {
        return Err(Output::error(format!(
            "value and distance arrays must have the same, non-zero length ({} and {})",
            u.len(),
            d.len()
        )));
    }
    Ok(())
}

/// `mfTransfinite(u, d)`.
fn tf(a: &[Arg]) -> Output {
    out(|| {
        let (u, d) = (a[0].array(), a[1].array());
        same_length(u, d)?;
        value(transfinite(u, d))
    })
}

/// `mfTfWeight(d, i)`, `i` 1-based.
fn tf_weight(a: &[Arg]) -> Output {
    out(|| {
        let d = a[0].array();
        same_length(d, d)?;
        let i = code(&a[1], "partition index", 1, d.len() as i64)?;
        value(transfinite_weights(d)[i as usize - 1].clone())
    })
}

/// `mfPartDist(f)`: `max(-f, 0)`.
fn part_dist(a: &[Arg]) -> Output {
    Output::value(partition_distance(&a[0].real(), Depth::Function))
}

/// `mfCurve(f1, f2, alpha)`: Eq. 12, `(-f1^2) &alpha (-f2^2)`.
fn curve(a: &[Arg]) -> Output {
    let (f1, f2) = (a[0].real(), a[1].real());
    Output::value(intersection(
        &f1.square().neg(),
        &f2.square().neg(),
        a[2].real(),
    ))
}

/// `mfShell(f, t, alpha)`: `f \ (f - t)`.
fn shell_fn(a: &[Arg]) -> Output {
    Output::value(shell(
        &a[0].real(),
        a[1].real(),
        Depth::Function,
        a[2].real(),
    ))
}

pub(crate) fn register(r: &mut Registry) {
    r.register("mfsawtooth", &[R, R], saw);
    r.register("mftriangle", &[R, R], tri);
    r.register("mfsawtoothmap", &[A, R, A, A], saw_map);
    r.register("mftrianglemap", &[A, R, A, A], tri_map);
    r.register("mfreplicate", &[A, A, A, A, A], replicate);
    r.register("mfmorph", &[R, R, R], morph);
    r.register("mftransfinite", &[A, A], tf);
    r.register("mftfweight", &[A, R], tf_weight);
    r.register("mfpartdist", &[R], part_dist);
    r.register("mfcurve", &[R, R, R], curve);
    r.register("mfshell", &[R, R, R], shell_fn);
}
