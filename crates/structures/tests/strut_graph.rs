//! The public strut graph against the lattice FRep, tiling, clipping and
//! the graph's own field in all four evaluation modes.

mod common;
use common::*;
use microfrep_core::field_check::{check_field, FieldCheck};
use microfrep_core::{Expr, Field};
use microfrep_shapes as prims;
use microfrep_structures::strut_graph::StrutGraph;
use microfrep_structures::struts::*;
use std::sync::Arc;

/// Distance from `p` to the segment `a b`.
fn seg_dist(p: [f64; 3], a: [f64; 3], b: [f64; 3]) -> f64 {
    let e: [f64; 3] = std::array::from_fn(|i| b[i] - a[i]);
    let d: [f64; 3] = std::array::from_fn(|i| p[i] - a[i]);
    let e2: f64 = e.iter().map(|c| c * c).sum();
    let t = ((0..3).map(|i| d[i] * e[i]).sum::<f64>() / e2).clamp(0.0, 1.0);
    (0..3)
        .map(|i| (d[i] - t * e[i]).powi(2))
        .sum::<f64>()
        .sqrt()
}

/// Union of capsules of the graph, computed directly from its public data.
fn capsules(g: &StrutGraph, p: [f64; 3]) -> f64 {
    g.beams
        .iter()
        .zip(&g.radii)
        .map(|(&(a, b), r)| {
            assert_eq!(r[0], r[1]);
            r[0] - seg_dist(p, g.nodes[a as usize], g.nodes[b as usize])
        })
        .fold(f64::NEG_INFINITY, f64::max)
}

#[test]
fn unit_cell_frep_is_the_union_of_the_graph_capsules() {
    for kind in StrutLattice::ALL {
        let r = 0.07;
        let cell = strut_cell(kind, &Expr::xyz(), r);
        let g = kind.cell_graph(r);
        assert_eq!(g.beams.len(), kind.struts().len());
        g.validate().unwrap();
        for p in spread(0.0, 1.0, 400) {
            let (a, b) = (at(&cell, p), capsules(&g, p));
            assert!(
                (a - b).abs() < 1e-12,
                "{} {p:?}: frep {a} graph {b}",
                kind.name()
            );
        }
    }
}

#[test]
fn tiled_graph_field_is_the_lattice_frep_in_the_box() {
    for kind in StrutLattice::ALL {
        let (cell, r) = (0.5, 0.06);
        let (lo, hi) = ([0.1, -0.3, 0.0], [1.3, 0.7, 0.9]);
        let g = StrutGraph::tile(kind, lo, hi, cell, |_| r).unwrap();
        g.validate().unwrap();
        let f = g.field().unwrap();
        let lattice = strut_lattice(kind, &Expr::xyz(), cell, r);
        let mut inside = 0;
        for p in spread(0.0, 1.0, 600) {
            let p: [f64; 3] = std::array::from_fn(|i| lo[i] + (hi[i] - lo[i]) * p[i]);
            let want = at(&lattice, p).max(-f.cutoff());
            let got = f.eval(p);
            // Inside the solid the nearest strut reaches the box, so it is
            // in the graph and the values agree; outside, the graph lacks the
            // struts beyond the box, so its value can only be lower.
            let ok = if want >= 0.0 {
                (want - got).abs() < 1e-9
            } else {
                got < 0.0 && got <= want + 1e-9
            };
            assert!(ok, "{} {p:?}: lattice {want} graph {got}", kind.name());
            inside += (got >= 0.0) as usize;
        }
        assert!(inside > 10, "{}: only {inside} points inside", kind.name());
    }
}

#[test]
fn graded_radius_is_sampled_at_beam_ends() {
    let g = StrutGraph::tile(StrutLattice::Bcc, [0.0; 3], [2.0; 3], 1.0, |p| {
        0.02 + 0.01 * p[0]
    })
    .unwrap();
    for (&(a, b), r) in g.beams.iter().zip(&g.radii) {
        assert_eq!(r[0], 0.02 + 0.01 * g.nodes[a as usize][0]);
        assert_eq!(r[1], 0.02 + 0.01 * g.nodes[b as usize][0]);
    }
    // Thicker struts on the +x side: more solid there.
    let f = g.field().unwrap();
    let frac = |x0: f64| {
        let pts = spread(0.0, 1.0, 4000);
        pts.iter()
            .filter(|p| f.eval([x0 + 0.5 * p[0], 2.0 * p[1], 2.0 * p[2]]) >= 0.0)
            .count()
    };
    assert!(frac(1.5) > 2 * frac(0.0), "{} {}", frac(1.5), frac(0.0));
}

#[test]
fn clip_to_a_part_keeps_every_beam_that_touches_it() {
    let g = StrutGraph::tile(StrutLattice::Octet, [-1.5; 3], [1.5; 3], 0.5, |_| 0.05).unwrap();
    let ball = prims::sphere(&Expr::xyz(), &prims::v3([0.0; 3]), 1.0);
    let c = g.clip(&ball);
    c.validate().unwrap();
    assert!(
        c.len() < g.len() && c.len() > g.len() / 8,
        "{} of {}",
        c.len(),
        g.len()
    );
    // Kept beams are those within the ball grown by the radius (up to the
    // interval slack); every beam reaching the ball is kept.
    let reach = |a: [f64; 3], b: [f64; 3]| seg_dist([0.0; 3], a, b) - 0.05;
    let kept: std::collections::HashSet<[u64; 6]> = c
        .beams
        .iter()
        .map(|&(a, b)| {
            let (p, q) = (c.nodes[a as usize], c.nodes[b as usize]);
            [p[0], p[1], p[2], q[0], q[1], q[2]].map(f64::to_bits)
        })
        .collect();
    let mut dropped = 0;
    for &(a, b) in &g.beams {
        let (p, q) = (g.nodes[a as usize], g.nodes[b as usize]);
        let key = [p[0], p[1], p[2], q[0], q[1], q[2]].map(f64::to_bits);
        if reach(p, q) <= 1.0 {
            assert!(
                kept.contains(&key),
                "beam {p:?}-{q:?} touches the ball but was dropped"
            );
        } else if !kept.contains(&key) {
            dropped += 1;
        }
    }
    assert!(dropped > 0);
}

#[test]
fn tapered_graph_field_passes_the_four_mode_check() {
    let g = StrutGraph {
        nodes: vec![[0.0; 3], [1.0, 0.2, 0.1], [0.3, 1.0, 0.8], [1.2, 1.1, -0.2]],
        beams: vec![(0, 1), (1, 2), (2, 0), (1, 3)],
        radii: vec![[0.1, 0.25], [0.2, 0.2], [0.05, 0.15], [0.3, 0.1]],
    };
    let f: Arc<dyn Field> = Arc::new(g.field().unwrap());
    let report = check_field(&f, &FieldCheck::new([[-0.5; 3], [1.6; 3]])).unwrap();
    assert!(report.points > 0 && report.boxes > 0);
    // Inside a ball end that is larger than the frustum near it.
    assert!((f.eval([1.0, 0.2, 0.1]) - 0.3).abs() < 1e-12);
    assert!(f.eval([3.0, 3.0, 3.0]) < 0.0);
}

#[test]
fn bad_graphs_and_tilings_are_errors() {
    let ok = StrutGraph {
        nodes: vec![[0.0; 3], [1.0, 0.0, 0.0]],
        beams: vec![(0, 1)],
        radii: vec![[0.1, 0.1]],
    };
    ok.validate().unwrap();
    let mut bad = ok.clone();
    bad.beams[0] = (0, 2);
    assert!(bad.validate().is_err() && bad.field().is_err());
    let mut bad = ok.clone();
    bad.nodes[1][2] = f64::NAN;
    assert!(bad.validate().is_err());
    let mut bad = ok.clone();
    bad.radii[0][1] = 0.0;
    assert!(bad.validate().is_err());
    let mut bad = ok.clone();
    bad.radii.clear();
    assert!(bad.validate().is_err());
    assert!(StrutGraph::tile(StrutLattice::Bcc, [0.0; 3], [1.0; 3], 0.0, |_| 0.1).is_err());
    assert!(StrutGraph::tile(StrutLattice::Bcc, [0.0; 3], [1.0; 3], 1.0, |_| f64::NAN).is_err());
    // A billion cells: refused before any allocation.
    assert!(StrutGraph::tile(StrutLattice::Octet, [0.0; 3], [1e3; 3], 1e-3, |_| 1e-4).is_err());
    assert!(StrutGraph::tile(StrutLattice::Bcc, [1.0; 3], [0.0; 3], 1.0, |_| 0.1).is_err());
}
