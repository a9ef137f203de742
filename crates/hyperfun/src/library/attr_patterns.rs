//! Procedural attribute patterns (LIBRARY.md section 7): concentric
//! circles, "crackles", normalised Gardner noise, Perlin-style noise and
//! turbulence.
//!
//! `hfA_NoiseP` and `hfA_Turbulence` use the reference's Perlin tables,
//! which it fills from an unseeded (time-seeded) random generator, so their
//! values differ from run to run there. Here they use the core's seeded
//! gradient noise with a fixed seed: deterministic, same character
//! (lattice gradient noise, zero at lattice points), different values.

use super::attr_arrays::overwrite;
use super::{el, Arg, Kind::*, Output, Registry};
use microfrep_core::{noise, Expr};
use std::f64::consts::PI;

/// Seed of the gradient noise behind `hfA_NoiseP` and `hfA_Turbulence`.
pub const NOISE_SEED: u64 = 1;

fn c(v: f64) -> Expr {
    Expr::constant(v)
}

/// Gardner's series with amplitude 1 at `(x, y, z)`, mapped to [0, 1] by
/// its extreme values `-+(2.17/1.17)^3`.
fn gardner01(x: &Expr, y: &Expr, z: &Expr, freq: &Expr, phase: &Expr) -> Expr {
    let (ax, ay, az) = (freq * x, freq * y, freq * z);
    let (sx, sy, sz) = (ax.sin(), ay.sin(), az.sin());
    let amp2 = 1.0 / 1.17;
    let serx = &sx + amp2 * (&ax / 1.35 + phase * &sz).sin();
    let sery = &sy + amp2 * (&ay / 1.35 + phase * &sx).sin();
    let serz = &sz + amp2 * (&az / 1.35 + phase * &sy).sin();
    let cmin = (-(2.17f64 / 1.17)).powf(3.0);
    let cmax = -cmin;
    (serx * sery * serz - cmin) / (cmax - cmin)
}

/// `hfA_NoiseG(p, freq, phase)`.
fn noise_g(a: &[Arg]) -> Output {
    let p = a[0].array();
    let (freq, phase) = (a[1].real(), a[2].real());
    Output::value(gardner01(&el(p, 0), &el(p, 1), &el(p, 2), &freq, &phase))
}

fn point(p: &[Expr]) -> [Expr; 3] {
    [el(p, 0), el(p, 1), el(p, 2)]
}

/// `hfA_NoiseP(p)`: gradient noise at p (see the module note).
fn noise_p(a: &[Arg]) -> Output {
    Output::value(noise::gradient_noise(&point(a[0].array()), NOISE_SEED))
}

/// Octaves of turbulence are unrolled: at most this many.
const MAX_OCTAVES: usize = 64;

/// `hfA_Turbulence(p, freq)`: `sum |2 noise(p f) - 1| / f` for
/// `f = freq, freq/2, ...` while `f >= 1`. The octave count comes from
/// `freq`, so it must be known when the model is built.
fn turbulence(a: &[Arg]) -> Output {
    let Some(mut f) = a[1].real().as_const() else {
        return Output::needs_constants();
    };
    let p = point(a[0].array());
    let mut sum = c(0.0);
    let mut octaves = 0;
    while f >= 1.0 && octaves < MAX_OCTAVES {
        let q = [&p[0] * f, &p[1] * f, &p[2] * f];
        sum = sum + (2.0 * noise::gradient_noise(&q, NOISE_SEED) - 1.0).abs() / f;
        f /= 2.0;
        octaves += 1;
    }
    Output::value(sum)
}

/// Picks the attribute group of the table interval that `v` falls into
/// (`[map[i], map[i+1])`). `first_wins`: the C loop stops at the first
/// match; otherwise later matches overwrite earlier ones. With no match the
/// output keeps its old value.
fn table_pick(v: &Expr, out: &[Expr], attrs: &[Expr], map: &[Expr], first_wins: bool) -> Vec<Expr> {
    let dim = out.len();
    let n = map.len();
    overwrite(out, |j| {
        let hits: Vec<(Expr, Expr)> = (0..n.saturating_sub(1))
            .map(|i| {
                let hit = v.ge(&map[i]).and(v.lt(&map[i + 1]));
                (hit, el(attrs, dim * i + j))
            })
            .collect();
        let fold =
            |acc: Expr, (hit, val): &(Expr, Expr)| Expr::select(hit.clone(), val.clone(), acc);
        Some(if first_wins {
            hits.iter().rev().fold(out[j].clone(), fold)
        } else {
            hits.iter().fold(out[j].clone(), fold)
        })
    })
}

/// The reference writes `1.1` into the attribute array just past the part
/// the table uses (index = table length), before the lookup reads it.
fn mark_attrs(attrs: &[Expr], map_len: usize) -> Vec<Expr> {
    overwrite(attrs, |i| (i == map_len).then(|| c(1.1)))
}

/// `hfA_Circles(p, out, attrs, map)`: `fmod(|p|, 1)` looked up in `map`.
fn circles(a: &[Arg]) -> Output {
    let [x, y, z] = point(a[0].array());
    let (out, attrs, map) = (a[1].array(), a[2].array(), a[3].array());
    let v = (x.square() + y.square() + z.square()).sqrt().rem(1.0);
    let attrs = mark_attrs(attrs, map.len());
    let new = table_pick(&v, out, &attrs, map, true);
    Output::writes(c(1.0), vec![(1, new), (2, attrs)])
}

/// `cycle(v)` of the reference: `(1 + sin(2 pi i / 1000)) / 2` with
/// `i = trunc(1000 fract(v))`.
fn cycle(v: &Expr) -> Expr {
    let i = ((v - v.floor()) * 1000.0).trunc();
    (1.0 + (i * 2.0 * PI / 1000.0).sin()) / 2.0
}

/// `hfA_Crackles(p, out, freq, attrs, map)`.
fn crackles(a: &[Arg]) -> Output {
    let [x, y, z] = point(a[0].array());
    let (out, freq) = (a[1].array(), a[2].real());
    let (attrs, map) = (a[3].array(), a[4].array());
    let phase = ((&x * &x).sqrt() + (&y * &y).sqrt() + (&z * &z).sqrt()) / 3.0;
    // The reference passes each coordinate twice (its own call order).
    let nx = -1.0 + gardner01(&x, &x, &z, &freq, &phase) * 2.0;
    let ny = -1.0 + gardner01(&y, &y, &x, &freq, &phase) * 2.0;
    let nz = -1.0 + gardner01(&z, &z, &y, &freq, &phase) * 2.0;
    let v = cycle(&(nx + ny + nz));
    let attrs = mark_attrs(attrs, map.len());
    let new = table_pick(&v, out, &attrs, map, false);
    Output::writes(c(1.0), vec![(1, new), (3, attrs)])
}

pub(super) fn register(r: &mut Registry) {
    r.register("hfa_noiseg", &[A, R, R], noise_g);
    r.register("hfa_noisep", &[A], noise_p);
    r.register("hfa_turbulence", &[A, R], turbulence);
    r.register("hfa_circles", &[A, A, A, A], circles);
    r.register("hfa_crackles", &[A, A, R, A, A], crackles);
}
