//! Moving vertices from their grid edges onto the surface: regula falsi
//! (Illinois variant) along each edge, a block of edges at a time on the
//! f32 batch evaluator (one evaluation per step for the whole block; the
//! f64 point evaluator was 5x slower than the rest of the mesher together).

use crate::lanes::select;
use microfrep_core::{BatchEval, BLOCK};

/// Regula falsi steps; Illinois converges superlinearly, so a few steps
/// reach f32 precision on smooth surfaces.
const STEPS: usize = 5;
/// Vertices stay this fraction of the edge away from its ends, so vertices
/// on different edges of a tet never coincide (no degenerate triangles).
const T_MIN: f32 = 1e-3;
/// ... and at least this many f32 steps of the coordinates away, so they
/// stay distinct after rounding far from the origin.
const MIN_ULPS: f64 = 4.0;

/// One edge to refine: from its inside end `p0` (sample `g0 >= 0`) to its
/// outside end `p1` (sample `g1 < 0`).
#[derive(Clone, Copy)]
pub struct Edge {
    p0: [f32; 3],
    d: [f32; 3],
    g0: f32,
    g1: f32,
    /// The least distance from either end, as a fraction of the edge.
    t_min: f32,
}

/// The `t_min` that [`Edge::new`] gives every edge at least `h` long whose
/// ends lie within `far` of the origin on every axis, where that is the
/// same for all of them (the f32 steps there are small against the edge):
/// bricks then skip the per-edge length and precision work.
pub fn common_t_min(far: f64, h: f64) -> Option<f32> {
    // A little shorter than `h`, for edges whose rounded length is.
    let ulps = MIN_ULPS * microfrep_io::precision::f32_step(far) / (0.999 * h);
    ((ulps as f32) <= T_MIN).then_some(T_MIN)
}

impl Edge {
    /// [`Edge::new`] for an edge whose `t_min` is known to be `t_min`
    /// (from [`common_t_min`]).
    pub fn with_t_min(p0: [f64; 3], p1: [f64; 3], g0: f32, g1: f32, t_min: f32) -> Edge {
        Edge {
            p0: p0.map(|v| v as f32),
            d: std::array::from_fn(|k| (p1[k] - p0[k]) as f32),
            g0,
            g1,
            t_min,
        }
    }

    pub fn new(p0: [f64; 3], p1: [f64; 3], g0: f32, g1: f32) -> Edge {
        let d: [f64; 3] = std::array::from_fn(|k| p1[k] - p0[k]);
        let len = d.iter().map(|v| v * v).sum::<f64>().sqrt();
        let far = (0..3)
            .map(|k| p0[k].abs().max(p1[k].abs()))
            .fold(0.0, f64::max);
        let ulps = MIN_ULPS * microfrep_io::precision::f32_step(far) / len;
        Edge {
            p0: p0.map(|v| v as f32),
            d: d.map(|v| v as f32),
            g0,
            g1,
            t_min: (ulps as f32).clamp(T_MIN, 0.25),
        }
    }
}

/// Appends the refined position of every edge to `out`, in order: the
/// last probe of the search, or the first probe exactly on the surface,
/// unless the last probe's |value| exceeds 1e-4 of the edge's sample span:
/// then the probe with the least |value| (where the secant step lands on
/// the end of the bracket it has converged to, the bisection step taken
/// instead moves away from the root, which left vertices of a mesh part's
/// flat faces 0.09 cells off);
/// where the inside end was sampled exactly zero and no probe after it is
/// inside, the end itself (a face through a node: the root is the node,
/// not a probe a bisection step away from it). Positions stay `t_min`
/// away from the ends.
pub fn refine_edges(ev: &mut BatchEval, edges: &[Edge], out: &mut Vec<[f32; 3]>) {
    // In columns, with 32-bit lane masks and selects instead of branches
    // (the signs of the probes are random), so every loop vectorises.
    let mut p0 = [[0.0f32; BLOCK]; 3];
    let mut d = [[0.0f32; BLOCK]; 3];
    for chunk in edges.chunks(BLOCK) {
        let n = chunk.len();
        let mut lo = [0.0f32; BLOCK];
        let mut hi = [1.0f32; BLOCK];
        let mut glo = [0.0f32; BLOCK];
        let mut ghi = [0.0f32; BLOCK];
        let mut t = [0.5f32; BLOCK];
        // The probe nearest the surface so far, and its |value|.
        let mut best = [0.5f32; BLOCK];
        let mut best_g = [f32::INFINITY; BLOCK];
        let mut last_g = [0.0f32; BLOCK];
        // Edges whose samples do not bracket a root (their sign was set by
        // interval proof or the padding) keep the midpoint.
        let mut live = [0u32; BLOCK];
        // Which end the last step replaced (+1 inside, -1 outside, 0 none):
        // Illinois halves the value kept at the other end only when the
        // same end is replaced twice running.
        let mut side = [0i32; BLOCK];
        for (i, e) in chunk.iter().enumerate() {
            for k in 0..3 {
                p0[k][i] = e.p0[k];
                d[k][i] = e.d[k];
            }
            glo[i] = e.g0;
            ghi[i] = e.g1;
            live[i] = (e.g0 >= 0.0 && e.g1 < 0.0) as u32;
        }
        for _ in 0..STEPS {
            if live[..n].iter().all(|&l| l == 0) {
                break;
            }
            // Slices of the block's length, so no index is checked.
            let (lo, hi, glo, ghi) = (&mut lo[..n], &mut hi[..n], &mut glo[..n], &mut ghi[..n]);
            let (t, live, side) = (&mut t[..n], &mut live[..n], &mut side[..n]);
            let (best, best_g) = (&mut best[..n], &mut best_g[..n]);
            for i in 0..n {
                let s = (lo[i] * ghi[i] - hi[i] * glo[i]) / (ghi[i] - glo[i]);
                let inner = (s > lo[i]) as u32 & (s < hi[i]) as u32;
                let next = select(inner, s, 0.5 * (lo[i] + hi[i]));
                t[i] = select(live[i], next, t[i]);
            }
            {
                let (x, y, z) = ev.coords_mut();
                let (x, y, z) = (&mut x[..n], &mut y[..n], &mut z[..n]);
                let (px, py, pz) = (&p0[0][..n], &p0[1][..n], &p0[2][..n]);
                let (dx, dy, dz) = (&d[0][..n], &d[1][..n], &d[2][..n]);
                for i in 0..n {
                    x[i] = px[i] + t[i] * dx[i];
                    y[i] = py[i] + t[i] * dy[i];
                    z[i] = pz[i] + t[i] * dz[i];
                }
            }
            let g = &ev.eval_loaded(n)[..n];
            for i in 0..n {
                let gi = g[i];
                // An inside probe replaces the inside end, an outside one
                // the outside end; one exactly on the surface, or NaN,
                // stops the search there. (0/1 lane flags and bit selects:
                // the compiler keeps `if` chains scalar.)
                let nearer = (gi.abs() < best_g[i]) as u32 & live[i];
                best[i] = select(nearer, t[i], best[i]);
                best_g[i] = select(nearer, gi.abs(), best_g[i]);
                last_g[i] = select(live[i], gi.abs(), last_g[i]);
                let up = (gi > 0.0) as u32 & live[i];
                let dn = (gi < 0.0) as u32 & live[i];
                let halve_hi = up & (side[i] == 1) as u32;
                let halve_lo = dn & (side[i] == -1) as u32;
                lo[i] = select(up, t[i], lo[i]);
                hi[i] = select(dn, t[i], hi[i]);
                glo[i] = select(up, gi, select(halve_lo, glo[i] * 0.5, glo[i]));
                ghi[i] = select(dn, gi, select(halve_hi, ghi[i] * 0.5, ghi[i]));
                let moved = up | dn;
                side[i] = up as i32 - dn as i32 + side[i] * (1 - moved as i32);
                live[i] = moved;
            }
        }
        for (i, e) in chunk.iter().enumerate() {
            let root_at_start = e.g0 == 0.0 && e.g1 < 0.0 && lo[i] == 0.0 && live[i] != 0;
            let tol = 1e-4 * (e.g0.abs() + e.g1.abs());
            let ti = if root_at_start {
                0.0
            } else if last_g[i] > tol {
                best[i]
            } else {
                t[i]
            };
            out.push(lerp(e, ti.clamp(e.t_min, 1.0 - e.t_min)));
        }
    }
}

fn lerp(e: &Edge, t: f32) -> [f32; 3] {
    std::array::from_fn(|k| e.p0[k] + t * e.d[k])
}

#[cfg(test)]
mod tests {
    use super::*;
    use microfrep_core::Expr;

    fn refine(f: &Expr, p0: [f64; 3], p1: [f64; 3]) -> [f32; 3] {
        let tape = microfrep_core::Shape::from(f).tape().clone();
        let mut ev = BatchEval::new(&tape);
        let mut pe = microfrep_core::PointEval::new(&tape);
        let (g0, g1) = (pe.eval(p0) as f32, pe.eval(p1) as f32);
        let mut out = Vec::new();
        refine_edges(&mut ev, &[Edge::new(p0, p1, g0, g1)], &mut out);
        out[0]
    }

    #[test]
    fn an_end_exactly_on_the_surface_is_the_root() {
        // The face x = -1 of a box through a grid node: f(-1) = 0 exactly.
        let f = Expr::x() + 1.0;
        let p = refine(&f, [-1.0, 0.2, 0.3], [-1.05, 0.2, 0.3]);
        assert!((p[0] + 1.0).abs() <= 1e-3 * 0.05 + 1e-7, "{p:?}");
    }

    #[test]
    fn a_secant_step_that_lands_on_its_bracket_keeps_the_root() {
        // Planes crossing an edge at many places, with the ends' samples as
        // the f32 sampler has them: where the first secant probe comes out
        // a hair outside, the second lands on that bracket end, and the
        // bisection step taken then moves away; the root found stays the
        // best probe. (Taking the last probe left some 0.1 of the edge off.)
        let x = Expr::x();
        let mut worst = 0.0f64;
        for k in 1..400 {
            let c = 0.1 + 0.8 * k as f64 / 400.0 + 1e-4 * (k as f64).sin();
            let f = 0.37 * (c - &x);
            let p = refine(&f, [0.0, 0.3, 0.1], [1.0, 0.3, 0.1]);
            worst = worst.max((p[0] as f64 - c).abs());
        }
        assert!(worst < 1e-6, "{worst}");
    }

    #[test]
    fn roots_are_found_to_f32_precision_on_curved_and_flat_fields() {
        let x = Expr::x();
        // Root of 0.3 - x^2 at sqrt(0.3) to a few f32 steps (halving the
        // kept end's value after every step, not only after the same end
        // was replaced twice, left it 1e-4 off), and of a plane at 0.1234
        // (exact in one).
        let p = refine(&(0.3 - &x * &x), [0.5, 0.0, 0.0], [0.6, 0.0, 0.0]);
        assert!((p[0] as f64 - 0.3f64.sqrt()).abs() < 3e-7, "{p:?}");
        let p = refine(&(0.1234 - &x), [0.1, 0.0, 0.0], [0.2, 0.0, 0.0]);
        assert!((p[0] as f64 - 0.1234).abs() < 1e-6, "{p:?}");
    }

    #[test]
    fn the_common_t_min_is_what_every_edge_would_get() {
        // Where a common value is offered, each edge's own computation
        // agrees, axis and diagonal edges alike; where it is declined,
        // edges that far out do need their own.
        for (h, far, offer) in [
            (0.01, 1.0, true),
            (2.0 / 128.0, 1.1, true),
            (0.1, 100.0, true),
            (0.01, 1000.0, false),
            (1e-4, 10.0, false),
        ] {
            let Some(t) = common_t_min(far, h) else {
                assert!(!offer, "{h} {far}");
                let e = Edge::new([far, 0.0, 0.0], [far - h, 0.0, 0.0], 1.0, -1.0);
                assert!(e.t_min > T_MIN, "{h} {far}");
                continue;
            };
            assert!(offer, "{h} {far}");
            for i in 0..200 {
                let x = far - h * (i as f64);
                let p0 = [x, -x + 0.5 * h, 0.3 * x];
                for d in [[h, 0.0, 0.0], [0.0, -h, 0.0], [h, h, 0.0], [h, h, h]] {
                    let p1 = std::array::from_fn(|k| p0[k] + d[k]);
                    let a = Edge::new(p0, p1, 1.0, -1.0);
                    let b = Edge::with_t_min(p0, p1, 1.0, -1.0, t);
                    assert_eq!((a.p0, a.d, a.t_min), (b.p0, b.d, b.t_min), "{h} {p0:?}");
                }
            }
        }
    }

    #[test]
    fn vertices_stay_distinct_from_the_ends_far_from_the_origin() {
        // At 1000, f32 steps are 6.1e-5: a thousandth of a 0.01 edge would
        // round onto its end.
        let x = Expr::x();
        let f = 1000.0 - &x;
        let p = refine(&f, [1000.0, 0.0, 0.0], [1000.01, 0.0, 0.0]);
        assert!(p[0] > 1000.0f32, "{p:?}");
    }
}
