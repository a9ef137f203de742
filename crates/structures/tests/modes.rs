//! Every kind of structure agrees across the evaluation modes: batch (f32)
//! matches point (f64), and interval bounds enclose sampled values.
mod common;
use common::*;
use microfrep_core::{Expr, PointEval, Tape};
use microfrep_shapes::{sphere, v3};
use microfrep_structures::examples::{shell_lattice, toriball, unit_sphere};
use microfrep_structures::infill::Depth;
use microfrep_structures::porous::{pores, porous, PeriodicMap};
use microfrep_structures::struts::{strut_lattice, StrutLattice};
use microfrep_structures::surficial::intersection_curve;
use microfrep_structures::tpms::{tpms, Solid, Tpms};

fn models() -> Vec<(&'static str, Expr)> {
    let p = Expr::xyz();
    let mut m = vec![
        ("toriball", toriball()),
        ("shell_lattice", shell_lattice()),
        (
            "porous",
            porous(
                &unit_sphere(),
                &pores(&p, &PeriodicMap::uniform(1.0, 9.0), |q| {
                    sphere(q, &v3([0.0; 3]), 0.6)
                }),
                0.0,
            ),
        ),
        (
            "curve",
            intersection_curve(
                &unit_sphere(),
                &(Expr::z() - 0.2),
                0.1,
                Depth::Normalized,
                0.0,
            ),
        ),
    ];
    for k in Tpms::ALL {
        m.push((k.name(), tpms(k, Solid::Sheet, &p, 0.7, 0.4)));
    }
    for k in StrutLattice::ALL {
        m.push((
            k.name(),
            strut_lattice(k, &p, 0.5, 0.05 + Expr::x().abs() * 0.02),
        ));
    }
    m
}

#[test]
fn batch_matches_point_and_intervals_enclose() {
    let pts = spread(-1.0, 1.0, 256);
    for (name, e) in models() {
        let tape = Tape::new(&e);
        let mut pe = PointEval::new(&tape);
        let b = batch(&e, &pts);
        for (p, v) in pts.iter().zip(b) {
            let r = pe.eval(*p);
            assert!(
                (r - v as f64).abs() < 2e-4 * (1.0 + r.abs()),
                "{name} {p:?}: {r} {v}"
            );
        }
        // Small boxes around some points enclose the values at their corners.
        for p in pts.iter().take(24) {
            let h = 0.01;
            let (lo, hi) = interval(&e, p.map(|c| c - h), p.map(|c| c + h));
            for c in 0..8 {
                let q: [f64; 3] =
                    std::array::from_fn(|i| p[i] + if c >> i & 1 == 1 { h } else { -h });
                let v = pe.eval(q);
                assert!(
                    lo <= v + 1e-9 && v <= hi + 1e-9,
                    "{name} {q:?}: {v} not in [{lo}, {hi}]"
                );
            }
        }
    }
}
