//! Space mappings against their closed forms: a mapped shape takes at the
//! image of a point the value the original takes at the point.

use microfrep_core::transform::{
    affine, linear, rotate, rotate_x, rotate_y, rotate_z, scale, stretch, taper_z, translate,
    twist_z,
};
use microfrep_core::{Expr, PointEval, Tape};
use std::f64::consts::FRAC_PI_2;

type P = [f64; 3];

fn c3(v: P) -> [Expr; 3] {
    v.map(Expr::constant)
}

/// The value of `f` remapped by `map`, at `q`.
fn at(f: &Expr, map: &[Expr; 3], q: P) -> f64 {
    PointEval::new(&Tape::new(&f.remap(map))).eval(q)
}

/// A shape with no symmetry to hide mistakes: `x + 2y + 4z + x y z`.
fn probe() -> Expr {
    let [x, y, z] = Expr::xyz();
    &x + 2.0 * &y + 4.0 * &z + &x * &y * &z
}

fn probe_at(p: P) -> f64 {
    p[0] + 2.0 * p[1] + 4.0 * p[2] + p[0] * p[1] * p[2]
}

const POINTS: [P; 5] = [
    [0.3, 0.4, 0.5],
    [1.5, -0.7, 2.2],
    [-2.5, 1.25, -0.75],
    [0.0, 0.0, 0.0],
    [7.0, -3.0, 0.125],
];

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * (1.0 + b.abs())
}

#[test]
fn translate_scale_stretch_move_points_as_stated() {
    let p = Expr::xyz();
    let f = probe();
    for q in POINTS {
        // Moved by t: the value at q + t is the old value at q.
        let t = [1.0, -2.0, 0.5];
        let img = [q[0] + t[0], q[1] + t[1], q[2] + t[2]];
        assert!(close(at(&f, &translate(&p, c3(t)), img), probe_at(q)));
        let s = [2.0, -0.5, 4.0];
        let img = [q[0] * s[0], q[1] * s[1], q[2] * s[2]];
        assert!(close(at(&f, &scale(&p, c3(s)), img), probe_at(q)));
        // Stretch about c: c + s (q - c).
        let c = [1.0, 1.0, -1.0];
        let img: P = std::array::from_fn(|i| c[i] + s[i] * (q[i] - c[i]));
        assert!(close(at(&f, &stretch(&p, c, c3(s)), img), probe_at(q)));
    }
}

#[test]
fn quarter_turns_map_axes_right_handed() {
    let p = Expr::xyz();
    let f = probe();
    for q in POINTS {
        let [x, y, z] = q;
        // +90 degrees about x takes (x, y, z) to (x, -z, y).
        assert!(close(
            at(&f, &rotate_x(&p, FRAC_PI_2), [x, -z, y]),
            probe_at(q)
        ));
        // About y: (x, y, z) to (z, y, -x).
        assert!(close(
            at(&f, &rotate_y(&p, FRAC_PI_2), [z, y, -x]),
            probe_at(q)
        ));
        // About z: (x, y, z) to (-y, x, z).
        assert!(close(
            at(&f, &rotate_z(&p, FRAC_PI_2), [-y, x, z]),
            probe_at(q)
        ));
    }
}

#[test]
fn axis_rotation_agrees_with_the_axis_turns_and_keeps_distances() {
    let p = Expr::xyz();
    let f = probe();
    let ang = 0.7;
    for q in POINTS {
        for (axis, turn) in [
            ([1.0, 0.0, 0.0], rotate_x(&p, ang)),
            ([0.0, 2.0, 0.0], rotate_y(&p, ang)),
            ([0.0, 0.0, 0.5], rotate_z(&p, ang)),
        ] {
            let a = at(&f, &rotate(&p, axis, ang), q);
            assert!(close(a, at(&f, &turn, q)), "{axis:?} {q:?}");
        }
        // A rotation about any axis keeps the distance to the origin.
        let [x, y, z] = Expr::xyz();
        let r2 = x.square() + y.square() + z.square();
        let d = at(&r2, &rotate(&p, [1.0, -2.0, 0.3], 1.1), q);
        assert!(close(d, q[0] * q[0] + q[1] * q[1] + q[2] * q[2]));
    }
}

#[test]
fn affine_maps_shapes_and_rejects_singular_matrices() {
    let p = Expr::xyz();
    let f = probe();
    let m = [[2.0, 1.0, 0.0], [0.0, 1.0, -1.0], [1.0, 0.0, 3.0]];
    let t = [0.5, -1.0, 2.0];
    let mapped = affine(&p, m, t).expect("invertible");
    for q in POINTS {
        let img: P = std::array::from_fn(|i| (0..3).map(|j| m[i][j] * q[j]).sum::<f64>() + t[i]);
        assert!((at(&f, &mapped, img) - probe_at(q)).abs() < 1e-9 * (1.0 + probe_at(q).abs()));
        // `linear` is the raw point map: f(m q + t).
        assert!(close(at(&f, &linear(&p, m, t), q), probe_at(img)));
    }
    let singular = [[1.0, 2.0, 3.0], [2.0, 4.0, 6.0], [0.0, 1.0, 0.0]];
    assert!(affine(&p, singular, t).is_none());
}

#[test]
fn twist_interpolates_the_angle_and_taper_the_scale() {
    let p = Expr::xyz();
    let f = probe();
    let (z1, z2, th1, th2) = (-1.0, 1.0, 0.3, 1.3);
    for q in POINTS {
        let twisted = twist_z(&p, z1, z2, th1, th2);
        let zq = q[2];
        let th = th1 + (th2 - th1) * (zq - z1) / (z2 - z1);
        assert!(close(at(&f, &twisted, q), at(&f, &rotate_z(&p, th), q)));
    }
    // Taper: factor s1 below z1, s2 above z2, linear in between.
    let (s1, s2) = (0.5, 2.0);
    let tapered = taper_z(&p, z1, z2, s1, s2);
    for (z, k) in [(-3.0, s1), (-1.0, s1), (0.0, 1.25), (1.0, s2), (4.0, s2)] {
        let q = [0.6, -0.2, z];
        let img = [q[0] * k, q[1] * k, z];
        assert!(close(at(&f, &tapered, img), probe_at(q)), "z {z}");
    }
    // A factor that vanishes is replaced by 1.
    let zero = taper_z(&p, z1, z2, 0.0, 0.0);
    assert!(close(
        at(&f, &zero, [0.6, -0.2, -2.0]),
        probe_at([0.6, -0.2, -2.0])
    ));
}
