//! hfConvArc: circular arcs under the Cauchy kernel, with the quirks of the
//! HyperFun code that change values.

use crate::{need, sub, PrimError, HF_EPS};
use microfrep_core::transform::P3;
use microfrep_core::Expr;

/// HyperFun's value of pi in this file (`#define PI 3.141592`); kept, as it
/// changes values.
#[allow(clippy::approx_constant)]
const HF_PI: f64 = 3.141592;
const RD: f64 = HF_PI / 180.0;

/// `atanh(v)` as `ln((1 + v)/(1 - v))/2` (no atanh op in the graph).
fn atanh(v: &Expr) -> Expr {
    0.5 * ((1.0 + v) / (1.0 - v)).ln()
}

/// Kernel integral of an arc of radius `r` and opening `th` (radians) lying
/// in the local xy plane from the +x axis, at the local point `(x, y, z)`.
/// Shared with the HyperFun library, which adds the reference's write-back
/// of its arguments around it.
pub fn arc_term(q: &P3, r: &Expr, s: &Expr, th: &Expr) -> Expr {
    let [x, y, z] = q;
    let s2 = s.square();
    let a = 2.0 * r * &s2;
    let d2 = x.square() + y.square() + z.square();
    let b = 1.0 + r.square() * &s2 + &s2 * &d2;
    let p2 = -(r.square().square() * s2.square())
        + 2.0 * r.square() * &s2 * (&s2 * (&d2 - 2.0 * z.square()) - 1.0)
        - (1.0 + &s2 * &d2).square();
    let p1 = p2.abs().sqrt();
    let p3 = &p1 * &p2;
    let f1 = &b * y / (x * &p2 * (&a * x - &b))
        + (&a * (x.square() + y.square()) * th.sin() - &b * y)
            / (x * &p2 * (&a * (x * th.cos() + y * th.sin()) - &b));
    let ay = &a * y;
    let tail = (&a * x + &b) * (th / 2.0).tan();
    let neg = ((-&ay) / &p1).atan() + ((&ay - &tail) / &p1).atan();
    let pos = atanh(&(&ay / &p1)) + atanh(&((&tail - &ay) / &p1));
    f1 + 2.0 * &b * Expr::select(p2.lt(0.0), neg, pos) / p3
}

/// Arcs (hfConvArc): arc `n` has centre `centre[n]`, radius `radius[n]`,
/// opening `theta[n]` degrees starting on the local +x axis, and is turned by
/// `angle[n]` degrees about `axis[n]`; kernel width `s[n]`, threshold `t`.
///
/// As in HyperFun: `EPS` is added to each axis component and to the angle
/// (axis length floored at `EPS`), the point is mapped by the Rodrigues
/// rotation by `-angle` with degrees converted by `pi = 3.141592`; `theta` is
/// clamped to 360 and, above 180, split into a `theta - 180` arc evaluated at
/// the point turned by -180 degrees about z plus a 180-degree arc.
/// HyperFun also writes the incremented angle and the 180 back into the
/// caller's arrays, so its later calls see other values; that state is not
/// reproduced: every point gets the values of HyperFun's first call.
#[allow(clippy::too_many_arguments)]
pub fn conv_arc(
    p: &P3,
    centre: &[P3],
    radius: &[Expr],
    theta: &[Expr],
    axis: &[P3],
    angle: &[Expr],
    s: &[Expr],
    t: impl Into<Expr>,
) -> Result<Expr, PrimError> {
    let n = s.len();
    need("hfConvArc", "center", centre, n)?;
    need("hfConvArc", "radius", radius, n)?;
    need("hfConvArc", "theta", theta, n)?;
    need("hfConvArc", "axis", axis, n)?;
    need("hfConvArc", "angle", angle, n)?;
    let mut sum = Expr::constant(0.0);
    for k in 0..n {
        let local = rotate_back(&sub(p, &centre[k]), &axis[k], &angle[k]);
        let th = Expr::select(theta[k].gt(360.0), Expr::constant(360.0), theta[k].clone());
        let over = th.gt(180.0);
        // Rotation by -180 degrees (HyperFun's pi) about z, axis exactly (0, 0, 1).
        let (oc, os) = ((-180.0 * RD).cos(), (-180.0 * RD).sin());
        let turned = [
            oc * &local[0] - os * &local[1],
            os * &local[0] + oc * &local[1],
            (oc + (1.0 - oc)) * &local[2],
        ];
        let extra = arc_term(&turned, &radius[k], &s[k], &((&th - 180.0) * RD));
        let main_th = Expr::select(over.clone(), Expr::constant(180.0), th) * RD;
        sum = sum
            + Expr::select(over, extra, Expr::constant(0.0))
            + arc_term(&local, &radius[k], &s[k], &main_th);
    }
    Ok(sum - t.into())
}

/// `M d` with `M` the Rodrigues rotation by `-(angle + EPS)` degrees about
/// the normalised `axis + EPS`, written out as HyperFun does.
fn rotate_back(d: &P3, axis: &P3, angle: &Expr) -> P3 {
    let raw: [Expr; 3] = std::array::from_fn(|i| &axis[i] + HF_EPS);
    let len = (raw[0].square() + raw[1].square() + raw[2].square()).sqrt();
    let len = Expr::select(len.lt(HF_EPS), Expr::constant(HF_EPS), len);
    let [i, j, k]: [Expr; 3] = std::array::from_fn(|n| &raw[n] / &len);
    let rad = (angle + HF_EPS).neg() * RD;
    let (c, s) = (rad.cos(), rad.sin());
    let one_c = 1.0 - &c;
    let m = [
        [
            &c + i.square() * &one_c,
            -(&k * &s) + &i * &j * &one_c,
            &j * &s + &k * &i * &one_c,
        ],
        [
            &k * &s + &i * &j * &one_c,
            &c + j.square() * &one_c,
            -(&i * &s) + &j * &k * &one_c,
        ],
        [
            -(&j * &s) + &k * &i * &one_c,
            &i * &s + &j * &k * &one_c,
            &c + k.square() * &one_c,
        ],
    ];
    std::array::from_fn(|r| &m[r][0] * &d[0] + &m[r][1] * &d[1] + &m[r][2] * &d[2])
}
