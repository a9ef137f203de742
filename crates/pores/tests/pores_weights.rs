//! Rational (weighted) 2D pores: the arcs' geometry against dense
//! polylines, the porosity still met, weight 1 unchanged; the new options'
//! checks; pore size given as area / volume per pore.

// Reference values are written with all the digits 40-digit arithmetic
// printed.
#![allow(clippy::excessive_precision)]

mod pores_common;
use microfrep_core::Field;
use microfrep_pores::curve::{
    alpha, chain_area, clipped_area, rational_bspline, segment_ratio, shoelace, signed_distance,
    Quad, P2,
};
use microfrep_pores::{Options, PoreError, PoreShape, Pores, SizeMeasure, Spec};
use pores_common::block;

const SQRT_HALF: f64 = std::f64::consts::FRAC_1_SQRT_2;

/// The chain as a closed polyline of `per_arc` points an arc.
fn dense(arcs: &[Quad], per_arc: usize) -> Vec<P2> {
    arcs.iter()
        .flat_map(|a| (0..per_arc).map(move |k| a.at(k as f64 / per_arc as f64)))
        .collect()
}

fn quadrilateral() -> [P2; 4] {
    [[0.1, -0.9], [1.2, 0.2], [-0.3, 1.1], [-1.0, -0.4]]
}

#[test]
fn segment_ratio_has_the_conic_values() {
    assert_eq!(segment_ratio(1.0), 2.0 / 3.0);
    assert!((segment_ratio(SQRT_HALF) - (std::f64::consts::FRAC_PI_2 - 1.0)).abs() < 1e-15);
    // Closed form (beyond 0.05 from 1) and quadrature (within) against
    // the closed form in 40-digit arithmetic (mpmath).
    for (w, exact) in [
        (0.5, 0.472_799_717_437_430_16),
        (0.94, 0.650_026_807_202_983_16),
        (0.96, 0.655_719_061_588_681_29),
        (0.999, 0.666_399_828_469_783_52),
        (1.001, 0.666_933_162_006_291_49),
        (1.04, 0.677_065_404_646_739_42),
        (1.06, 0.682_070_742_686_412_7),
        (2.0, 0.826_436_002_466_035_77),
    ] {
        let v = segment_ratio(w);
        assert!((v - exact).abs() < 1e-14, "{w}: {v} against {exact}");
    }
    // Against the shoelace area of a dense polyline, for weights from
    // nearly the chord to nearly the corner.
    for w in [0.05, 0.3, SQRT_HALF, 0.97, 1.01, 1.5, 4.0, 20.0] {
        let arc = Quad::rational([[0.0, 0.0], [1.0, 1.0], [2.0, 0.0]], w);
        let n = 200_000;
        let mut pts: Vec<P2> = (0..=n).map(|k| arc.at(k as f64 / n as f64)).collect();
        pts.reverse();
        let seg = shoelace(&pts);
        assert!(
            (segment_ratio(w) - seg).abs() < 1e-8,
            "{w}: {} against {seg}",
            segment_ratio(w)
        );
        // Increasing: heavier corners enclose more.
        assert!(segment_ratio(w * 1.1) > segment_ratio(w));
    }
}

#[test]
fn corner_weight_cos_45_on_a_square_is_the_inscribed_circle() {
    let sq = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];
    let arcs = rational_bspline(&sq, SQRT_HALF);
    for a in &arcs {
        for k in 0..=50 {
            let p = a.at(k as f64 / 50.0);
            assert!((p[0].hypot(p[1]) - 1.0).abs() < 1e-15, "{p:?}");
        }
    }
    assert!((chain_area(&arcs) - std::f64::consts::PI).abs() < 1e-14);
    assert!((alpha(SQRT_HALF) - std::f64::consts::FRAC_PI_4).abs() < 1e-15);
    // The distance to a circle is exact.
    for q in [[0.3, 0.2], [1.5, -0.7], [-0.1, 0.95], [2.0, 2.0]] {
        let d = signed_distance(&arcs, q).0;
        assert!((d - (1.0 - q[0].hypot(q[1]))).abs() < 1e-12, "{q:?}: {d}");
    }
}

#[test]
fn weighted_chains_enclose_alpha_of_their_polygon_and_clip_exactly() {
    let ctrl = quadrilateral();
    for w in [0.4, SQRT_HALF, 1.0, 1.3, 3.0] {
        let arcs = rational_bspline(&ctrl, w);
        let area = chain_area(&arcs);
        assert!(
            (area / shoelace(&ctrl) - alpha(w)).abs() < 1e-14,
            "{w}: {}",
            area / shoelace(&ctrl)
        );
        let poly = dense(&arcs, 20_000);
        assert!((shoelace(&poly) - area).abs() < 1e-7, "{w}");
        // Clipped to a box: against the polyline clipped by sampling.
        let (lo, hi) = ([-0.6, -0.5], [0.7, 0.45]);
        let exact = clipped_area(&arcs, lo, hi);
        let n = 900;
        let mut inside = 0usize;
        for i in 0..n {
            for j in 0..n {
                let q = [
                    lo[0] + (i as f64 + 0.5) / n as f64 * (hi[0] - lo[0]),
                    lo[1] + (j as f64 + 0.5) / n as f64 * (hi[1] - lo[1]),
                ];
                if signed_distance(&arcs, q).0 > 0.0 {
                    inside += 1;
                }
            }
        }
        let sampled = inside as f64 / (n * n) as f64 * (hi[0] - lo[0]) * (hi[1] - lo[1]);
        assert!(
            (exact - sampled).abs() < 2e-4,
            "{w}: {exact} against {sampled}"
        );
        assert!(exact < area && exact > 0.3 * area);
    }
}

#[test]
fn rational_distance_and_parts_match_a_dense_polyline() {
    let ctrl = quadrilateral();
    for w in [0.3, 1.7] {
        let arcs = rational_bspline(&ctrl, w);
        let poly = dense(&arcs, 4000);
        for i in 0..400 {
            let q = [
                -1.5 + 3.0 * (i as f64 * 0.618_034).fract(),
                -1.5 + 3.0 * (i as f64 * 0.754_878).fract(),
            ];
            let d = signed_distance(&arcs, q).0;
            // Distance to the polyline's segments, and inside by winding.
            let mut near = f64::INFINITY;
            let mut winding = 0.0;
            for k in 0..poly.len() {
                let (a, b) = (poly[k], poly[(k + 1) % poly.len()]);
                let e = [b[0] - a[0], b[1] - a[1]];
                let t = (((q[0] - a[0]) * e[0] + (q[1] - a[1]) * e[1])
                    / (e[0] * e[0] + e[1] * e[1]))
                    .clamp(0.0, 1.0);
                near = near.min((a[0] + t * e[0] - q[0]).hypot(a[1] + t * e[1] - q[1]));
                let (u, v) = ([a[0] - q[0], a[1] - q[1]], [b[0] - q[0], b[1] - q[1]]);
                winding += (u[0] * v[1] - u[1] * v[0]).atan2(u[0] * v[0] + u[1] * v[1]);
            }
            assert!(
                (d.abs() - near).abs() < 1e-6,
                "{w} {q:?}: {d} against {near}"
            );
            if near > 1e-5 {
                let inside = winding.abs() > std::f64::consts::PI;
                assert_eq!(d > 0.0, inside, "{w} {q:?}: {d}");
            }
        }
        // A part of an arc lies on the arc and keeps its area.
        let a = arcs[1];
        let parts = [a.sub(0.0, 0.3), a.sub(0.3, 0.8), a.sub(0.8, 1.0)];
        let whole = a.area_term();
        let sum: f64 = parts.iter().map(Quad::area_term).sum();
        assert!((whole - sum).abs() < 1e-14, "{whole} {sum}");
        for p in &parts {
            for k in 0..=10 {
                let x = p.at(k as f64 / 10.0);
                assert!(a.closest(x).1.sqrt() < 1e-12, "{x:?}");
            }
        }
    }
}

/// 2D plate of 4 x 4 cells.
const PLATE: [[f64; 3]; 2] = [[0.0, 0.0, 0.0], [2.0, 2.0, 0.25]];

fn plate(target: f64, weight: f64, seed: u64) -> microfrep_pores::Built {
    let part = block(PLATE[0], PLATE[1]);
    Pores::build(
        &part,
        PLATE,
        Spec::Constant(0.5),
        Spec::Constant(target),
        seed,
        &Options {
            weight,
            ..Options::two_d()
        },
    )
    .unwrap()
}

/// Pore share of the plate by an independent pixel count of the field.
fn pixel_porosity(b: &microfrep_pores::Built, n: usize) -> f64 {
    let mut pore = 0usize;
    for i in 0..n {
        for j in 0..n {
            let q = [
                (i as f64 + 0.5) / n as f64 * 2.0,
                (j as f64 + 0.5) / n as f64 * 2.0,
                0.125,
            ];
            if b.field.eval(q) < 0.0 {
                pore += 1;
            }
        }
    }
    pore as f64 / (n * n) as f64
}

#[test]
fn weighted_pores_meet_their_porosity() {
    for (target, weight) in [(0.4, 0.5), (0.6, SQRT_HALF), (0.7, 1.6), (0.5, 4.0)] {
        let b = plate(target, weight, 7);
        assert_eq!(b.pores, 16);
        let w1 = plate(target, 1.0, 7);
        let mut moved = 0.0f64;
        for (c, d) in b.cells.iter().zip(&w1.cells) {
            assert!((c.porosity - target).abs() < 1e-9, "{weight}: {c:?}");
            let (PoreShape::Two { arcs, .. }, PoreShape::Two { arcs: a1, .. }) =
                (&c.shape, &d.shape)
            else {
                panic!()
            };
            assert!(arcs.iter().all(|a| a.w == weight));
            // The curve is another one: its arcs' middle points moved.
            for (a, b) in arcs.iter().zip(a1) {
                let (p, q) = (a.at(0.5), b.at(0.5));
                moved = moved.max((p[0] - q[0]).hypot(p[1] - q[1]));
            }
        }
        assert!(moved > 5e-3, "{weight}: {moved}");
        let p = pixel_porosity(&b, 1200);
        println!(
            "2D weight {weight}, target {target}: pixel count {p:.5}, largest shift {moved:.4}"
        );
        assert!((p - target).abs() < 1e-3 * target, "{weight}: {p}");
    }
}

#[test]
fn weight_one_is_todays_curve_bit_for_bit() {
    // Digest of the cells' fractions, arcs and porosities and of 3000
    // field values of three 2D builds, taken with the code before weights
    // were added.
    let d = digest(&Options::two_d());
    assert_eq!(d, TODAY, "{d:#018x}");
    let explicit = digest(&Options {
        weight: 1.0,
        ..Options::two_d()
    });
    assert_eq!(explicit, TODAY);
    assert_ne!(
        digest(&Options {
            weight: 1.0 + 1e-9,
            ..Options::two_d()
        }),
        TODAY
    );
}

const TODAY: u64 = 0x7d8de782128a23bb;

fn digest(opts: &Options) -> u64 {
    let part = block(PLATE[0], PLATE[1]);
    let mut h: u64 = 0xcbf29ce484222325;
    let mut eat = |v: f64| {
        for b in v.to_bits().to_le_bytes() {
            h ^= b as u64;
            h = h.wrapping_mul(0x100000001b3);
        }
    };
    for (target, kappa, seed) in [(0.4, 1.0, 1u64), (0.7, 1.0, 2), (0.9, 1.2, 3)] {
        let b = Pores::build(
            &part,
            PLATE,
            Spec::Constant(0.5),
            Spec::Constant(target),
            seed,
            &Options {
                parent_scale: Some(kappa),
                ..opts.clone()
            },
        )
        .unwrap();
        for c in &b.cells {
            eat(c.porosity);
            if let PoreShape::Two { r, arcs, .. } = &c.shape {
                r.iter().for_each(|&v| eat(v));
                for a in arcs {
                    for p in a.p {
                        eat(p[0]);
                        eat(p[1]);
                    }
                }
            }
        }
        for i in 0..3000 {
            let q = [
                (i as f64 * 0.618_033_988_7).fract() * 2.0,
                (i as f64 * 0.754_877_666_2).fract() * 2.0,
                0.1,
            ];
            eat(b.field.eval(q));
        }
    }
    h
}

#[test]
fn bad_weights_and_openings_are_option_errors() {
    let part = block(PLATE[0], PLATE[1]);
    let try_build = |o: Options| {
        Pores::build(
            &part,
            PLATE,
            Spec::Constant(0.5),
            Spec::Constant(0.6),
            1,
            &o,
        )
    };
    for w in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        match try_build(Options {
            weight: w,
            ..Options::two_d()
        }) {
            Err(PoreError::Option { name, why, .. }) => {
                assert_eq!(name, "weight");
                assert!(why.contains("above 0"), "{why}");
            }
            r => panic!("{w}: {:?}", r.map(|b| b.pores)),
        }
    }
    match try_build(Options {
        weight: 1.5,
        ..Options::default()
    }) {
        Err(e @ PoreError::Option { name: "weight", .. }) => {
            assert!(e.to_string().contains("3D pores take only weight 1"), "{e}")
        }
        r => panic!("{:?}", r.map(|b| b.pores)),
    }
    for v in [-0.01, 0.3, f64::NAN] {
        match try_build(Options {
            opening: v,
            ..Options::default()
        }) {
            Err(PoreError::Option { name, .. }) => assert_eq!(name, "opening"),
            r => panic!("{v}: {:?}", r.map(|b| b.pores)),
        }
    }
}

#[test]
fn size_as_area_or_volume_per_pore() {
    let cube = [[0.0; 3], [1.0; 3]];
    let part = block(cube[0], cube[1]);
    let per_pore = |dim3: bool, m: f64| {
        let o = if dim3 {
            Options::default()
        } else {
            Options::two_d()
        };
        Pores::build(
            &part,
            cube,
            Spec::Constant(m),
            Spec::Constant(0.6),
            1,
            &Options {
                size_measure: SizeMeasure::PerPore,
                ..o
            },
        )
        .unwrap()
    };
    // m / P: volume 1 over 64 pores, area 1 over 16.
    assert_eq!(per_pore(true, 1.0 / 64.0).pores, 64);
    assert_eq!(per_pore(false, 1.0 / 16.0).pores, 16);
    for c in &per_pore(true, 1.0 / 64.0).cells {
        assert!((c.cell.hi[0] - c.cell.lo[0] - 0.25).abs() < 1e-12);
    }
    // The same as the edge given directly.
    let edge = Pores::build(
        &part,
        cube,
        Spec::Constant(0.25),
        Spec::Constant(0.6),
        1,
        &Options::default(),
    )
    .unwrap();
    assert_eq!(edge.pores, 64);
    assert!(matches!(
        Pores::build(
            &part,
            cube,
            Spec::Constant(-0.1),
            Spec::Constant(0.6),
            1,
            &Options {
                size_measure: SizeMeasure::PerPore,
                ..Options::default()
            },
        ),
        Err(PoreError::Size { .. })
    ));
}
