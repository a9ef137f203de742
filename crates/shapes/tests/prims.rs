//! Primitives against independent plain-f64 formulas and HyperFun's own
//! values (`reference/probes.csv`), in every evaluation mode: point values,
//! batch agreement, interval soundness over random boxes, gradients against
//! central differences; plus closed-form facts.

// Expected values are the reference interpreter's, printed with 17
// significant digits so they round-trip; axis numbers index arrays and are
// primitive arguments at once.
#![allow(clippy::excessive_precision, clippy::needless_range_loop)]

use microfrep_core::{BatchEval, Expr, GradEval, Interval, IntervalEval, PointEval, Tape};
use microfrep_shapes::{self as prims, v3, PrimError};

type P = [f64; 3];

/// HyperFun's truncated pi in `hfConvArc` (the value its C code uses).
#[allow(clippy::approx_constant)]
const HF_PI: f64 = 3.141592;

/// Deterministic uniform numbers (splitmix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
    }
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next()
    }
    fn point(&mut self, h: f64) -> P {
        [self.range(-h, h), self.range(-h, h), self.range(-h, h)]
    }
}

fn sq(v: f64) -> f64 {
    v * v
}
fn dsub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn ddot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn dnorm(a: P) -> f64 {
    ddot(a, a).sqrt()
}

/// The four HyperFun probe points.
const PROBES: [P; 4] = [
    [0.3, 0.4, 0.5],
    [1.5, -0.7, 2.2],
    [-2.5, 1.25, -0.75],
    [1.8, 2.1, 0.0],
];

fn assert_probes(name: &str, e: &Expr, want: [f64; 4]) {
    let tape = Tape::new(e);
    let mut pe = PointEval::new(&tape);
    for (p, w) in PROBES.iter().zip(want) {
        let v = pe.eval(*p);
        assert!(
            (v - w).abs() <= 1e-12 * (1.0 + w.abs()),
            "{name} at {p:?}: {v} vs HyperFun {w}"
        );
    }
}

/// All modes of `e` against the reference `f` over the cube of half size `h`.
fn check(name: &str, e: &Expr, f: impl Fn(P) -> f64, h: f64) {
    let tape = Tape::new(e);
    let mut pe = PointEval::new(&tape);
    let mut rng = Rng(name.len() as u64 * 7919);
    // Point values against the independent formula.
    let pts: Vec<P> = (0..64).map(|_| rng.point(h)).collect();
    let mut finite = 0;
    for p in &pts {
        let (v, w) = (pe.eval(*p), f(*p));
        if w.is_finite() {
            finite += 1;
            assert!(
                (v - w).abs() <= 1e-9 * (1.0 + w.abs()),
                "{name} at {p:?}: {v} vs {w}"
            );
        }
    }
    assert!(finite > 32, "{name}: reference mostly not finite");
    // Batch (f32) agrees with the f64 reference where well conditioned.
    let cols: [Vec<f32>; 3] = std::array::from_fn(|a| pts.iter().map(|p| p[a] as f32).collect());
    let mut out = vec![0.0f32; pts.len()];
    BatchEval::new(&tape).eval(&cols[0], &cols[1], &cols[2], &mut out);
    for (i, p) in pts.iter().enumerate() {
        let pf = [cols[0][i] as f64, cols[1][i] as f64, cols[2][i] as f64];
        let v = pe.eval(pf);
        if v.is_finite() {
            let tol = 2e-3 * (1.0 + v.abs());
            assert!(
                (out[i] as f64 - v).abs() <= tol,
                "{name} batch at {p:?}: {} vs {v}",
                out[i]
            );
        }
    }
    // Interval bounds contain every sampled value of random boxes.
    let mut ie = IntervalEval::new(&tape);
    for _ in 0..40 {
        let c = rng.point(h);
        let w = rng.range(0.0, h);
        let b: [Interval; 3] = std::array::from_fn(|a| {
            let r = w * rng.next();
            Interval::new(c[a] - r, c[a] + r)
        });
        let iv = ie.eval(b[0], b[1], b[2]);
        for _ in 0..20 {
            let q: P = std::array::from_fn(|a| rng.range(b[a].lo, b[a].hi));
            let v = pe.eval(q);
            assert!(
                v.is_nan() || iv.contains(v),
                "{name}: {v} at {q:?} outside {iv:?} over {b:?}"
            );
        }
    }
    // Gradient against central differences where the function is smooth
    // (the differences at two step sizes agree).
    let mut ge = GradEval::new(&tape);
    let mut checked = 0;
    for _ in 0..40 {
        let p = rng.point(h);
        let (v, g) = ge.eval(p);
        if !v.is_finite() {
            continue;
        }
        let mut fd = |hh: f64, a: usize| {
            let (mut lo, mut hi) = (p, p);
            lo[a] -= hh;
            hi[a] += hh;
            (pe.eval(hi) - pe.eval(lo)) / (2.0 * hh)
        };
        for a in 0..3 {
            let (d1, d2) = (fd(1e-4, a), fd(1e-5, a));
            if !d1.is_finite() || (d1 - d2).abs() > 1e-5 * (1.0 + d1.abs()) {
                continue;
            }
            checked += 1;
            assert!(
                (g[a] - d2).abs() <= 1e-4 * (1.0 + d2.abs()),
                "{name} d/d{a} at {p:?}: {} vs {d2}",
                g[a]
            );
        }
    }
    assert!(checked > 60, "{name}: only {checked} gradient checks");
}

fn p() -> [Expr; 3] {
    Expr::xyz()
}

#[test]
fn quadrics_match_formulas_and_hyperfun() {
    let c = [1.0, 0.0, 0.0];
    let e = prims::sphere(&p(), &v3(c), 2.0);
    check("sphere", &e, |q| 4.0 - sq(dnorm(dsub(q, c))), 3.0);
    assert_probes(
        "sphere",
        &e,
        [
            3.1000000000000001,
            -1.5800000000000005,
            -10.375,
            -1.0500000000000003,
        ],
    );

    let e = prims::ellipsoid(&p(), &v3([0.0; 3]), &v3([1.0, 2.0, 3.0]));
    check(
        "ellipsoid",
        &e,
        |q| 1.0 - sq(q[0]) - sq(q[1] / 2.0) - sq(q[2] / 3.0),
        3.0,
    );
    assert_probes(
        "ellipsoid",
        &e,
        [
            0.84222222222222221,
            -1.910277777777778,
            -5.703125,
            -3.3425000000000002,
        ],
    );

    let c = [0.0, 1.0, 0.0];
    let want = [
        [3.3900000000000001, -3.7300000000000004, 3.375, 2.79],
        [
            3.6600000000000001,
            -3.0900000000000007,
            -2.8125,
            0.75999999999999979,
        ],
        [
            3.5500000000000003,
            -1.1399999999999997,
            -2.3125,
            -0.4500000000000004,
        ],
    ];
    for axis in 0..3 {
        let e = prims::cylinder(&p(), &v3(c), axis, 2.0);
        let f = move |q: P| {
            let d = dsub(q, c);
            4.0 - (0..3).filter(|&i| i != axis).map(|i| sq(d[i])).sum::<f64>()
        };
        check("cylinder", &e, f, 3.0);
        assert_probes("cylinder", &e, want[axis]);
    }
    let want = [
        [
            0.93222222222222217,
            0.33972222222222215,
            0.546875,
            -0.10250000000000004,
        ],
        [
            0.94972222222222225,
            -0.10027777777777791,
            -0.625,
            0.18999999999999995,
        ],
        [
            0.95972222222222225,
            0.38305555555555559,
            -0.73611111111111116,
            -0.30000000000000016,
        ],
    ];
    for axis in 0..3 {
        let e = prims::ell_cylinder(&p(), &v3([0.0; 3]), axis, 2.0, 3.0);
        let (u, v) = prims::others(axis);
        check(
            "ell_cylinder",
            &e,
            move |q| 1.0 - sq(q[u] / 2.0) - sq(q[v] / 3.0),
            3.0,
        );
        assert_probes("ell_cylinder", &e, want[axis]);
    }
}

#[test]
fn cones_match_formulas_and_hyperfun() {
    let want = [
        [-1.5500000000000003, -19.070000000000004, -2.25, -14.4],
        [-1.2, -27.870000000000005, -25.6875, -8.5500000000000007],
        [
            -0.75000000000000011,
            -6.1199999999999992,
            -30.6875,
            -30.600000000000001,
        ],
    ];
    let want_ell = [
        [-0.61250000000000016, -0.91999999999999993, -0.140625, -14.4],
        [
            -0.26249999999999996,
            -9.7200000000000006,
            -23.578125,
            -8.5500000000000007,
        ],
        [
            -0.14999999999999999,
            -4.2824999999999989,
            -24.828125,
            -14.0625,
        ],
    ];
    for axis in 0..3 {
        let (u, v) = prims::others(axis);
        let e = prims::cone(&p(), &v3([0.0; 3]), axis, 0.5);
        check(
            "cone",
            &e,
            move |q| sq(q[axis]) - sq(q[u] / 0.5) - sq(q[v] / 0.5),
            3.0,
        );
        assert_probes("cone", &e, want[axis]);
        let e = prims::ell_cone(&p(), &v3([0.0; 3]), axis, 0.5, 2.0);
        check(
            "ell_cone",
            &e,
            move |q| sq(q[axis]) - sq(q[u] / 0.5) - sq(q[v] / 2.0),
            3.0,
        );
        assert_probes("ell_cone", &e, want_ell[axis]);
    }
}

#[test]
fn tori_match_formulas_and_hyperfun() {
    let want = [
        [
            -4.6581254575402902,
            -1.7279243432617655,
            -7.628572157732048,
            -3.0499999999999989,
        ],
        [
            -5.0014288630928201,
            0.39623234683321584,
            -0.71454023663417487,
            -4.8499999999999996,
        ],
        [
            -5.5,
            -5.6482327856518921,
            0.39550983124842531,
            0.94518002312719851,
        ],
    ];
    for axis in 0..3 {
        let (u, v) = prims::others(axis);
        let e = prims::torus(&p(), &v3([0.0; 3]), axis, 3.0, 1.0);
        // r0^2 - (rho - R)^2 - d_axis^2, the same polynomial.
        check(
            "torus",
            &e,
            move |q| 1.0 - sq(q[u].hypot(q[v]) - 3.0) - sq(q[axis]),
            4.0,
        );
        assert_probes("torus", &e, want[axis]);
    }
}

#[test]
fn block_and_superellipsoid_match_formulas_and_hyperfun() {
    let (v, w) = ([-1.0, -2.0, -3.0], [2.0, 4.0, 6.0]);
    let e = prims::block(&p(), &v3(v), &v3(w));
    let f = move |q: P| {
        let s: Vec<f64> = (0..3)
            .map(|i| (q[i] - v[i]) * (v[i] + w[i] - q[i]))
            .collect();
        let r0 = |a: f64, b: f64| a + b - (a * a + b * b).sqrt();
        r0(r0(s[0], s[1]), s[2])
    };
    check("block", &e, f, 4.0);
    assert_probes(
        "block",
        &e,
        [
            0.76681910516078666,
            -1.7166694779272165,
            -12.211675211059406,
            -6.1876922432354693,
        ],
    );

    let e = prims::superellipsoid(&p(), &v3([0.0; 3]), &v3([4.0, 5.0, 6.0]), 0.5, 1.5);
    let f = |q: P| {
        let (u, v, w) = ((q[0] / 4.0).abs(), (q[1] / 5.0).abs(), (q[2] / 6.0).abs());
        1.0 - (u.powf(2.0 / 1.5) + v.powf(2.0 / 1.5)).powf(1.5 / 0.5) - w.powf(2.0 / 0.5)
    };
    check("superellipsoid", &e, f, 4.0);
    assert_probes(
        "superellipsoid",
        &e,
        [
            0.99966297410491922,
            0.94152987723940773,
            0.668586479054748,
            0.71332403997180172,
        ],
    );
}

#[test]
fn half_space_is_signed_plane_distance() {
    let n = [0.0, 0.6, 0.8];
    let e = prims::half_space(&p(), [1.0, 1.0, 1.0], n);
    check("half_space", &e, move |q| -ddot(dsub(q, [1.0; 3]), n), 3.0);
}

fn centres() -> Vec<[Expr; 3]> {
    vec![v3([0.0, 0.0, 0.0]), v3([2.0, 0.0, 1.0])]
}
fn consts(v: &[f64]) -> Vec<Expr> {
    v.iter().map(|&c| Expr::constant(c)).collect()
}
const C: [P; 2] = [[0.0, 0.0, 0.0], [2.0, 0.0, 1.0]];

#[test]
fn blobby_metaball_soft_match_formulas_and_hyperfun() {
    let e = prims::blobby(
        &p(),
        &centres(),
        &consts(&[1.0, 0.5]),
        &consts(&[2.0, 3.0]),
        0.5,
    )
    .unwrap();
    let f = |q: P| {
        2.0 * (-sq(dnorm(dsub(q, C[0])))).exp() + 3.0 * (-0.5 * sq(dnorm(dsub(q, C[1])))).exp()
            - 0.5
    };
    check("blobby", &e, f, 3.0);
    assert_probes(
        "blobby",
        &e,
        [
            1.2892110452875292,
            0.50967060356622862,
            -0.49952697925985917,
            -0.30240930358788243,
        ],
    );

    let e = prims::metaball(
        &p(),
        &centres(),
        &consts(&[2.0, 3.0]),
        &consts(&[4.0, 6.0]),
        0.5,
    )
    .unwrap();
    let f = |q: P| {
        let mut s = -0.5;
        for (i, (b, d)) in [(2.0, 4.0), (3.0, 6.0)].into_iter().enumerate() {
            let r = dnorm(dsub(q, C[i]));
            s += if r <= d / 3.0 {
                b * (1.0 - 3.0 * r * r / (d * d))
            } else if r < d {
                1.5 * b * sq(1.0 - r / d)
            } else {
                0.0
            };
        }
        s
    };
    check("metaball", &e, f, 5.0);
    assert_probes(
        "metaball",
        &e,
        [
            3.4875000000000003,
            2.2464800306191384,
            -0.14247784226883586,
            1.4650447352395748,
        ],
    );

    let e = prims::soft(&p(), &centres(), &consts(&[4.0, 6.0]), 0.5).unwrap();
    let f = |q: P| {
        let mut s = -0.5;
        for (i, d) in [4.0f64, 6.0].into_iter().enumerate() {
            let r = dnorm(dsub(q, C[i]));
            if r <= d {
                s += 1.0 - 22.0 * r.powi(2) / (9.0 * d.powi(2))
                    + 17.0 * r.powi(4) / (9.0 * d.powi(4))
                    - 4.0 * r.powi(6) / (9.0 * d.powi(6));
            }
        }
        s
    };
    check("soft", &e, f, 5.0);
    assert_probes(
        "soft",
        &e,
        [
            1.2168976699138376,
            0.57743113046434424,
            -0.25955242609908658,
            0.38616529222676488,
        ],
    );
}

#[test]
fn one_centre_blobby_is_its_formula_and_metaball_skips_nonpositive_d() {
    let e = prims::blobby(
        &p(),
        &[v3([1.0, 2.0, 3.0])],
        &consts(&[0.7]),
        &consts(&[1.5]),
        0.25,
    )
    .unwrap();
    let tape_pe = Tape::new(&e);
    let mut pe = PointEval::new(&tape_pe);
    // At the centre: b - T; at distance 1: b e^-a - T.
    assert!((pe.eval([1.0, 2.0, 3.0]) - 1.25).abs() < 1e-15);
    assert!((pe.eval([1.0, 3.0, 3.0]) - (1.5 * (-0.7f64).exp() - 0.25)).abs() < 1e-15);

    let e = prims::metaball(
        &p(),
        &[v3([0.0; 3])],
        &consts(&[2.0]),
        &consts(&[-1.0]),
        0.5,
    )
    .unwrap();
    assert_eq!(PointEval::new(&Tape::new(&e)).eval([0.0; 3]), -0.5);
}

/// HyperFun's segment kernel integral, from LIBRARY.md.
fn line_ref(q: P, b: P, e: P, s: f64) -> f64 {
    let l = dnorm(dsub(e, b));
    let dir = dsub(e, b).map(|c| c / l);
    let d = dsub(q, b);
    let t = ddot(d, dir);
    let p2 = 1.0 + s * s * (ddot(d, d) - t * t);
    let q2 = 1.0 + s * s * (ddot(d, d) + l * l - 2.0 * l * t);
    let pp = p2.sqrt();
    t / (2.0 * p2 * (p2 + s * s * t * t))
        + (l - t) / (2.0 * p2 * q2)
        + ((s * t / pp).atan() + (s * (l - t) / pp).atan()) / (2.0 * s * pp.powi(3))
}

#[test]
fn conv_point_line_curve_match_formulas_and_hyperfun() {
    let pts = vec![v3([0.0; 3]), v3([1.0, 1.0, 0.0])];
    let e = prims::conv_point(&p(), &pts, &consts(&[1.0, 0.5]), 0.1).unwrap();
    let f = |q: P| {
        1.0 / sq(1.0 + sq(dnorm(q))) + 1.0 / sq(1.0 + 0.25 * sq(dnorm(dsub(q, [1.0, 1.0, 0.0]))))
            - 0.1
    };
    check("conv_point", &e, f, 3.0);
    assert_probes(
        "conv_point",
        &e,
        [
            0.95959246443675517,
            0.025066339137161581,
            -0.032435665294924559,
            0.38089363640441354,
        ],
    );

    let e = prims::conv_line(
        &p(),
        &[v3([0.0; 3])],
        &[v3([2.0, 0.0, 0.0])],
        &consts(&[1.0]),
        0.1,
    )
    .unwrap();
    check(
        "conv_line",
        &e,
        |q| line_ref(q, [0.0; 3], [2.0, 0.0, 0.0], 1.0) - 0.1,
        3.0,
    );
    assert_probes(
        "conv_line",
        &e,
        [
            0.47203278689232275,
            -0.057150864163018428,
            -0.09003690335788557,
            -0.047797942791183753,
        ],
    );

    let verts = vec![v3([0.0; 3]), v3([1.0, 0.0, 0.0]), v3([1.0, 1.0, 0.0])];
    let e = prims::conv_curve(&p(), &verts, &consts(&[1.0, 1.0]), 0.1).unwrap();
    let f = |q: P| {
        line_ref(q, [0.0; 3], [1.0, 0.0, 0.0], 1.0)
            + line_ref(q, [1.0, 0.0, 0.0], [1.0, 1.0, 0.0], 1.0)
            - 0.1
    };
    check("conv_curve", &e, f, 3.0);
    assert_probes(
        "conv_curve",
        &e,
        [
            0.63427546566655313,
            -0.063791566475688261,
            -0.088071695343665199,
            -0.01719008215067766,
        ],
    );
}

#[test]
fn conv_line_r_clamps_and_uses_last_threshold() {
    let e = prims::conv_line_r(&p(), &[v3([0.0; 3])], &[v3([2.0, 0.0, 0.0])], 0.5).unwrap();
    assert_probes(
        "conv_line_r",
        &e,
        [
            -0.0087831498982583467,
            -0.13319123888297352,
            -0.13587762575851767,
            -0.1323208201744217,
        ],
    );
    // Two segments of different lengths, R = 0.5 so S = 2.
    let (b, en) = (
        [[0.0; 3], [0.0, 1.0, 0.0]],
        [[2.0, 0.0, 0.0], [0.0, 1.0, 0.5]],
    );
    let e = prims::conv_line_r(&p(), &b.map(v3), &en.map(v3), 0.5).unwrap();
    let f = move |q: P| {
        let s = 2.0;
        let mut sum: f64 = 0.0;
        let mut thr = 0.0;
        for i in 0..2 {
            let l = dnorm(dsub(en[i], b[i]));
            let pt2 = 1.0 + s * s * 0.25;
            let qt2 = 1.0 + s * s * (0.25 + l * l);
            thr = l / (2.0 * pt2 * qt2) + (s * l / pt2.sqrt()).atan() / (2.0 * s * pt2.powf(1.5));
            if sum < 1.0 {
                sum = (sum + line_ref(q, b[i], en[i], s)).min(1.0);
            }
        }
        sum - thr
    };
    check("conv_line_r", &e, f, 2.0);
    // With R >= 1 (S = 1), near the middle of a long first segment its term
    // alone passes 1: the sum saturates and the value is 1 minus the second
    // (last) segment's threshold.
    let (b, en) = (
        [[-2.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[2.0, 0.0, 0.0], [0.0, 1.0, 0.5]],
    );
    let e = prims::conv_line_r(&p(), &b.map(v3), &en.map(v3), 1.5).unwrap();
    let tape_pe = Tape::new(&e);
    let mut pe = PointEval::new(&tape_pe);
    assert!(line_ref([0.0, 0.0, 0.1], b[0], en[0], 1.0) > 1.0);
    let (l, r) = (0.5f64, 1.5f64);
    let (pt2, qt2) = (1.0 + r * r, 1.0 + r * r + l * l);
    let thr = l / (2.0 * pt2 * qt2) + (l / pt2.sqrt()).atan() / (2.0 * pt2.powf(1.5));
    assert!((pe.eval([0.0, 0.0, 0.1]) - (1.0 - thr)).abs() < 1e-14);
}

/// HyperFun's triangle kernel integral, transcribed from LIBRARY.md.
fn triangle_ref(q: P, mut a1: P, mut a2: P, mut a3: P, s: f64) -> f64 {
    let (l0, l1, l2) = (
        dnorm(dsub(a2, a1)),
        dnorm(dsub(a3, a2)),
        dnorm(dsub(a1, a3)),
    );
    if l1 >= l2 && l1 > l0 {
        (a1, a2, a3) = (a2, a3, a1);
    } else if l2 >= l1 && l2 > l0 {
        (a1, a2, a3) = (a3, a1, a2);
    }
    let a21 = dsub(a2, a1);
    let t = -ddot(a21, dsub(a1, a3)) / ddot(a21, a21);
    let b = [a1[0] + t * a21[0], a1[1] + t * a21[1], a1[2] + t * a21[2]];
    let (e1, e2, h) = (dnorm(dsub(a1, b)), dnorm(dsub(a2, b)), dnorm(dsub(a3, b)));
    let u = dsub(a2, b).map(|c| c / e2);
    let v = dsub(a3, b).map(|c| c / h);
    let d = dsub(q, b);
    let (uc, vc) = (ddot(d, u), ddot(d, v));
    let g = vc - h;
    let m = e2 * g + uc * h;
    let k = uc * h - e1 * g;
    let c2 = 1.0 / (s * s) + ddot(d, d) - uc * uc;
    let qq = c2 - vc * vc;
    let w = c2 - 2.0 * vc * h + h * h;
    let a2s = e1 * e1 * w + h * h * (qq + uc * uc) - 2.0 * e1 * h * uc * g;
    let b2s = e2 * e2 * w + h * h * (qq + uc * uc) + 2.0 * e2 * h * uc * g;
    let (aa, bb, cc) = (a2s.sqrt(), b2s.sqrt(), c2.sqrt());
    let (n1, n2) = (e1 + uc, e2 - uc);
    let (n3, n4) = (e1 * n1 + vc * h, -e1 * uc - g * h);
    let (n5, n6) = (-e2 * n2 - vc * h, -e2 * uc + g * h);
    (k * ((n3 / aa).atan() + (n4 / aa).atan()) / aa
        + m * ((n5 / bb).atan() + (n6 / bb).atan()) / bb
        + vc * ((n1 / cc).atan() + (n2 / cc).atan()) / cc)
        / (2.0 * qq * s)
}

#[test]
fn conv_triangle_and_mesh_match_formulas_and_hyperfun() {
    let tri = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let e = prims::conv_triangle(&p(), &tri.map(v3), &consts(&[1.0]), 0.1).unwrap();
    check(
        "conv_triangle",
        &e,
        move |q| triangle_ref(q, tri[0], tri[1], tri[2], 1.0) - 0.1,
        3.0,
    );
    assert_probes(
        "conv_triangle",
        &e,
        [
            0.3345293002173696,
            -0.08305084490376996,
            -0.092571759867603548,
            -0.066758981703861409,
        ],
    );
    // Every labelling of a scalene triangle takes a relabelling branch.
    let t2 = [[0.5, 0.2, 0.1], [0.0, 1.5, -0.5], [2.0, 0.5, 1.0]];
    for r in 0..3 {
        let (x, y, z) = (t2[r], t2[(r + 1) % 3], t2[(r + 2) % 3]);
        let e = prims::conv_triangle(&p(), &[x, y, z].map(v3), &consts(&[0.8]), 0.0).unwrap();
        check(
            "conv_triangle_relabel",
            &e,
            move |q| triangle_ref(q, x, y, z, 0.8),
            3.0,
        );
    }

    let verts = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(v3);
    let e = prims::conv_mesh(
        &p(),
        &verts,
        &[[0, 1, 2], [0, 1, 3]],
        &consts(&[1.0, 1.0]),
        0.1,
    )
    .unwrap();
    let vs = [[0.0; 3], [2.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let f = move |q: P| {
        triangle_ref(q, vs[0], vs[1], vs[2], 1.0) + triangle_ref(q, vs[0], vs[1], vs[3], 1.0) - 0.1
    };
    check("conv_mesh", &e, f, 3.0);
    assert_probes(
        "conv_mesh",
        &e,
        [
            0.82110393833929329,
            -0.053233892364439102,
            -0.08688987727328408,
            -0.045377526750356209,
        ],
    );
    let err = prims::conv_mesh(&p(), &verts, &[[0, 1, 4]], &consts(&[1.0]), 0.1).unwrap_err();
    assert_eq!(
        err,
        PrimError::BadIndex {
            prim: "hfConvMesh",
            tri: 0,
            index: 4,
            count: 4
        }
    );
}

/// HyperFun's arc kernel integral at a local point, from hfConvArc.
fn arc_ref(x: f64, y: f64, z: f64, r: f64, s: f64, th: f64) -> f64 {
    let a = 2.0 * r * s * s;
    let d2 = x * x + y * y + z * z;
    let b = 1.0 + r * r * s * s + s * s * d2;
    let p2 = -r.powi(4) * s.powi(4) + 2.0 * r * r * s * s * (s * s * (d2 - 2.0 * z * z) - 1.0)
        - sq(1.0 + s * s * d2);
    let p1 = p2.abs().sqrt();
    let f1 = b * y / (x * p2 * (a * x - b))
        + (a * (x * x + y * y) * th.sin() - b * y)
            / (x * p2 * (a * (x * th.cos() + y * th.sin()) - b));
    let tail = (a * x + b) * (th / 2.0).tan();
    let f2 = if p2 < 0.0 {
        2.0 * b * ((-a * y / p1).atan() + ((a * y - tail) / p1).atan()) / (p1 * p2)
    } else {
        2.0 * b * ((a * y / p1).atanh() + ((tail - a * y) / p1).atanh()) / (p1 * p2)
    };
    f1 + f2
}

#[test]
fn conv_arc_matches_hyperfun_and_its_split_above_180() {
    let arc = |th: f64| {
        prims::conv_arc(
            &p(),
            &[v3([0.0; 3])],
            &consts(&[2.0]),
            &consts(&[th]),
            &[v3([0.0, 0.0, 1.0])],
            &consts(&[0.0]),
            &consts(&[1.0]),
            0.1,
        )
        .unwrap()
    };
    assert_probes(
        "conv_arc",
        &arc(90.0),
        [
            0.014703324520620481,
            -0.082817214934704078,
            -0.092487221835386768,
            0.20735891364651884,
        ],
    );
    // Axis (0,0,1) + EPS and angle EPS: a rotation by about 1e-6 degrees, so
    // the reference on the unrotated point agrees to ~1e-7.
    let rd = HF_PI / 180.0;
    let e = arc(90.0);
    let tape_pe = Tape::new(&e);
    let mut pe = PointEval::new(&tape_pe);
    let mut rng = Rng(5);
    for _ in 0..50 {
        let q = rng.point(3.0);
        let w = arc_ref(q[0], q[1], q[2], 2.0, 1.0, 90.0 * rd) - 0.1;
        assert!((pe.eval(q) - w).abs() < 1e-5 * (1.0 + w.abs()), "{q:?}");
    }
    // 270 degrees: a 90-degree arc at the point turned by -180 (HyperFun's
    // pi) about z, plus a 180-degree arc; 400 is clamped to 360.
    for (th, extra) in [(270.0, 90.0), (400.0, 180.0)] {
        let e = arc(th);
        let tape_pe = Tape::new(&e);
        let mut pe = PointEval::new(&tape_pe);
        for _ in 0..30 {
            let q = rng.point(3.0);
            let (c, s) = ((-180.0 * rd).cos(), (-180.0 * rd).sin());
            let (x2, y2) = (c * q[0] - s * q[1], s * q[0] + c * q[1]);
            let w = arc_ref(x2, y2, q[2], 2.0, 1.0, extra * rd)
                + arc_ref(q[0], q[1], q[2], 2.0, 1.0, 180.0 * rd)
                - 0.1;
            assert!(
                (pe.eval(q) - w).abs() < 1e-5 * (1.0 + w.abs()),
                "theta {th} at {q:?}"
            );
        }
    }
    // A full circle (360) is symmetric under the half turn about its axis.
    let tape_pe = Tape::new(&arc(360.0));
    let mut pe = PointEval::new(&tape_pe);
    let (a, b) = (pe.eval([0.7, 1.9, 0.3]), pe.eval([-0.7, -1.9, 0.3]));
    assert!((a - b).abs() < 1e-4 * a.abs(), "{a} {b}");
    // Rotating the arc about x by 90 degrees is the same as rotating the point.
    let turned = prims::conv_arc(
        &p(),
        &[v3([0.0; 3])],
        &consts(&[2.0]),
        &consts(&[90.0]),
        &[v3([1.0, 0.0, 0.0])],
        &consts(&[90.0]),
        &consts(&[1.0]),
        0.1,
    )
    .unwrap();
    let tape_pt = Tape::new(&turned);
    let mut pt = PointEval::new(&tape_pt);
    let tape_pa = Tape::new(&arc(90.0));
    let mut pa = PointEval::new(&tape_pa);
    for q in [[0.5, 0.3, 1.2], [1.5, -0.4, 0.9]] {
        // Turning the point by -90 degrees about x: (x, y, z) -> (x, z, -y).
        let local = [q[0], q[2], -q[1]];
        let (v, w) = (pt.eval(q), pa.eval(local));
        assert!((v - w).abs() < 1e-4 * (1.0 + w.abs()), "{v} vs {w}");
    }
    // All modes against the reference including HyperFun's EPS rotation.
    for th in [150.0f64, 270.0] {
        let f = move |q: P| {
            let l = rotate_back_ref(q, [HF_EPS, HF_EPS, 1.0 + HF_EPS], HF_EPS);
            let mut v = arc_ref(l[0], l[1], l[2], 2.0, 1.0, th.min(180.0) * rd) - 0.1;
            if th > 180.0 {
                let (c, s) = ((-180.0 * rd).cos(), (-180.0 * rd).sin());
                v += arc_ref(
                    c * l[0] - s * l[1],
                    s * l[0] + c * l[1],
                    l[2],
                    2.0,
                    1.0,
                    (th - 180.0) * rd,
                );
            }
            v
        };
        check("conv_arc", &arc(th), f, 3.0);
    }
}

const HF_EPS: f64 = 1e-6;

/// Rodrigues rotation by `-angle` degrees (HyperFun's pi) about the unit `axis`.
fn rotate_back_ref(d: P, axis: P, angle: f64) -> P {
    let n = dnorm(axis);
    let [i, j, k] = axis.map(|c| c / n);
    let a = -angle * HF_PI / 180.0;
    let (c, s) = (a.cos(), a.sin());
    let o = 1.0 - c;
    [
        (c + i * i * o) * d[0] + (-k * s + i * j * o) * d[1] + (j * s + k * i * o) * d[2],
        (k * s + i * j * o) * d[0] + (c + j * j * o) * d[1] + (-i * s + j * k * o) * d[2],
        (-j * s + k * i * o) * d[0] + (i * s + j * k * o) * d[1] + (c + k * k * o) * d[2],
    ]
}

#[test]
fn distance_primitives_are_exact_distances() {
    let want = [
        [
            -0.43854876388106678,
            -1.3941251266125119,
            -0.18580649229063484,
            -1.0733126291998989,
        ],
        [f64::NAN; 4],
        [
            -0.22360679774997896,
            -0.4966705317658322,
            -2.1645898033750317,
            -2.4738633753705965,
        ],
    ];
    for axis in 0..3 {
        let (u, v) = prims::others(axis);
        let e = prims::d_cone(&p(), &v3([0.0; 3]), axis, 0.5);
        let t = 0.5f64.atan();
        check(
            "d_cone",
            &e,
            move |q| -(q[u].hypot(q[v]) * t.cos() - q[axis].abs() * t.sin()),
            3.0,
        );
        if axis != 1 {
            assert_probes("d_cone", &e, want[axis]);
        }
    }
    // DCylinder: exact distance to the line minus R.
    let e = prims::d_cylinder(&p(), &v3([0.0; 3]), &v3([1.0, 1.0, 0.0]), 2.0);
    let f = |q: P| {
        let u = [1.0 / 2f64.sqrt(), 1.0 / 2f64.sqrt(), 0.0];
        let t = ddot(q, u);
        2.0 - dnorm(dsub(q, u.map(|c| c * t)))
    };
    check("d_cylinder", &e, f, 3.0);
    assert_probes(
        "d_cylinder",
        &e,
        [
            1.4950247530818961,
            -0.69443871706149629,
            -0.75567596063107523,
            1.7878679656440357,
        ],
    );
    let want = [
        [
            -1.3786814535663012,
            -0.65164292244472888,
            -1.9374431326805372,
            -1.0124611797498106,
        ],
        [f64::NAN; 4],
        [
            -1.5495097567963922,
            -1.5784167207129052,
            0.22251034170763584,
            0.76586333718786648,
        ],
    ];
    for axis in 0..3 {
        let e = prims::d_torus(&p(), &v3([0.0; 3]), axis, 3.0, 1.0);
        // Exact distance: against the nearest of many points on the core circle.
        let (u, v) = prims::others(axis);
        let f = move |q: P| {
            let mut best = f64::INFINITY;
            for k in 0..20000 {
                let a = k as f64 * std::f64::consts::TAU / 20000.0;
                let mut c = [0.0; 3];
                c[u] = 3.0 * a.cos();
                c[v] = 3.0 * a.sin();
                best = best.min(dnorm(dsub(q, c)));
            }
            1.0 - best
        };
        let tape_pe = Tape::new(&e);
        let mut pe = PointEval::new(&tape_pe);
        let mut rng = Rng(11 + axis as u64);
        for _ in 0..10 {
            let q = rng.point(4.0);
            assert!((pe.eval(q) - f(q)).abs() < 1e-5, "d_torus at {q:?}");
        }
        let (u2, v2) = (u, v);
        check(
            "d_torus",
            &e,
            move |q| 1.0 - (sq(q[u2].hypot(q[v2]) - 3.0) + sq(q[axis])).sqrt(),
            4.0,
        );
        if axis != 1 {
            assert_probes("d_torus", &e, want[axis]);
        }
    }
}

#[test]
fn d_ellipsoid_matches_hyperfun_and_sphere_distance() {
    let e = prims::d_ellipsoid(&p(), &v3([0.0; 3]), [1.0, 2.0, 3.0]).unwrap();
    let tape = Tape::new(&e);
    let mut pe = PointEval::new(&tape);
    for (q, w) in PROBES.iter().zip([
        0.66002195090029536,
        -0.84351607242045856,
        -1.6724446880336488,
        -1.2866294175531094,
    ]) {
        assert!(
            (pe.eval(*q) - w).abs() < 1e-9,
            "{q:?}: {} vs {w}",
            pe.eval(*q)
        );
    }
    // Against a brute-force nearest point on the surface (outside points).
    let mut rng = Rng(3);
    for _ in 0..10 {
        let q = rng.point(4.0);
        if sq(q[0]) + sq(q[1] / 2.0) + sq(q[2] / 3.0) <= 1.2 {
            continue;
        }
        let mut best = f64::INFINITY;
        for i in 0..=300 {
            let th = std::f64::consts::PI * i as f64 / 300.0;
            for j in 0..600 {
                let ph = std::f64::consts::TAU * j as f64 / 600.0;
                let s = [
                    th.sin() * ph.cos(),
                    2.0 * th.sin() * ph.sin(),
                    3.0 * th.cos(),
                ];
                best = best.min(dnorm(dsub(q, s)));
            }
        }
        assert!(
            (pe.eval(q) + best).abs() < 2e-2,
            "{q:?}: {} vs {}",
            pe.eval(q),
            -best
        );
    }
    // A sphere (a = b = c = r) gives r - |p - c| away from the centre.
    let c = [0.5, -1.0, 2.0];
    let e = prims::d_ellipsoid(&p(), &v3(c), [1.5; 3]).unwrap();
    check(
        "d_ellipsoid_sphere",
        &e,
        move |q| 1.5 - dnorm(dsub(q, c)),
        3.0,
    );
    let e = prims::d_ellipsoid(&p(), &v3([0.0; 3]), [1.0, 2.0, 3.0]).unwrap();
    let tape = Tape::new(&e);
    let (mut pe, mut ge, mut ie) = (
        PointEval::new(&tape),
        GradEval::new(&tape),
        IntervalEval::new(&tape),
    );
    // Gradient: unit length and matching central differences.
    for _ in 0..40 {
        let q = rng.point(4.0);
        let (_, g) = ge.eval(q);
        assert!((dnorm(g) - 1.0).abs() < 1e-9);
        for a in 0..3 {
            let (mut lo, mut hi) = (q, q);
            lo[a] -= 1e-5;
            hi[a] += 1e-5;
            let fd = (pe.eval(hi) - pe.eval(lo)) / 2e-5;
            assert!((fd - g[a]).abs() < 1e-4, "{q:?} d{a}: {fd} vs {}", g[a]);
        }
    }
    // Intervals contain sampled values.
    for _ in 0..40 {
        let c = rng.point(4.0);
        let w = rng.range(0.0, 2.0);
        let b: [Interval; 3] =
            std::array::from_fn(|a| Interval::new(c[a] - w, c[a] + w * rng.next()));
        let iv = ie.eval(b[0], b[1], b[2]);
        for _ in 0..20 {
            let q: P = std::array::from_fn(|a| rng.range(b[a].lo, b[a].hi));
            assert!(iv.contains(pe.eval(q)));
        }
    }
    assert!(prims::d_ellipsoid(&p(), &v3([0.0; 3]), [1.0, 0.0, 1.0]).is_err());
    assert!(prims::d_ellipsoid(&p(), &v3([0.0; 3]), [1.0, f64::NAN, 1.0]).is_err());
}

#[test]
fn sphere_is_zero_at_its_radius_and_short_lists_are_errors() {
    let e = prims::sphere(&p(), &v3([1.0, 2.0, 3.0]), 2.5);
    let tape_pe = Tape::new(&e);
    let mut pe = PointEval::new(&tape_pe);
    for d in [[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [-0.48, 0.6, 0.64]] {
        let q = [1.0 + 2.5 * d[0], 2.0 + 2.5 * d[1], 3.0 + 2.5 * d[2]];
        assert!(pe.eval(q).abs() < 1e-12);
    }
    let err =
        prims::blobby(&p(), &centres(), &consts(&[1.0]), &consts(&[1.0, 2.0]), 0.5).unwrap_err();
    assert_eq!(
        err,
        PrimError::TooFew {
            prim: "hfBlobby",
            arg: "a",
            need: 2,
            got: 1
        }
    );
    let err =
        prims::conv_line(&p(), &[v3([1.0; 3])], &[v3([1.0; 3])], &consts(&[1.0]), 0.1).unwrap_err();
    assert_eq!(
        err,
        PrimError::ZeroSegment {
            prim: "hfConvLine",
            index: 0
        }
    );
    assert!(prims::conv_curve(&p(), &[v3([0.0; 3])], &consts(&[1.0]), 0.1).is_err());
    assert!(prims::conv_line_r(&p(), &[], &[], 0.5).is_err());
}
