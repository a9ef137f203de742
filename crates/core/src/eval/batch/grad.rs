//! Forward-mode gradients over blocks of f32 lanes.
//!
//! The evaluator runs the batch evaluator's [`Plan`] (the same steps, the
//! same registers) with a second register file beside the values: three
//! lanes of partial derivatives (d/dx, d/dy, d/dz) per register. Each step
//! first computes its value with the batch kernels, so values are
//! bit-identical to [`super::BatchEval`]'s, then its derivative factors in
//! f32 (the rules of `eval/deriv.rs` and [`SetOp::partials`]), then pushes
//! the operands' partials through them with the chain rule. Every loop is
//! one op over a whole block, like the value kernels, so it vectorises;
//! lanes never mix, so a point's result does not depend on the block it
//! falls in.
//!
//! Many registers depend on one or two axes only (the scalings and waves
//! of one coordinate, their squares and sums) or on none (parameters,
//! steps such as `floor` whose derivative is zero): the evaluator tracks,
//! per step, which partials can be non-zero ([`Axes`], from the plan, once)
//! and computes only those. A skipped partial is exactly +0 in the full
//! computation (every rule goes through [`mul0`], which gives +0 for a zero
//! partial), so the terms it would add are written as `+ 0.0` and the
//! results stay bit for bit those of computing every lane.

use super::plan::{Imm, Pair, Plan, SetAlpha, Step};
use super::{binary, map3, powi, set_imm, set_reg, unary, Lanes, Splat, Src, BLOCK};
use super::{REG_X, REG_Y, REG_Z};
use crate::eval::grad::field_dual;
use crate::ops::{BinaryOp, SetOp, UnaryOp};
use crate::simd_math;
use crate::tape::Tape;
use std::sync::Arc;

/// The partial derivatives of one register: d/dx, d/dy, d/dz lanes.
type Partials = [Lanes; 3];

/// Which partials of a register can be non-zero: bit `a` for axis `a`.
/// The lanes of the others are not kept (they hold whatever an earlier
/// use of the register left): readers take them as zero.
type Axes = u8;

/// All three partials.
const ALL: Axes = 0b111;

/// Partials read as zero where an operand has none on an axis.
static ZERO: Lanes = [0.0; BLOCK];

/// The axes of a step's output and of its operands (in the order of the
/// step's fields: `a`, `b`, then `alpha` or the field's arguments; `c` of
/// a select is not differentiated).
#[derive(Clone, Copy, Debug, Default)]
struct StepAxes {
    out: Axes,
    ops: [Axes; 3],
}

/// Whether `op`'s derivative is zero everywhere (`unary_factor` fills 0).
fn unary_flat(op: UnaryOp) -> bool {
    use UnaryOp::*;
    matches!(op, Sign | Floor | Ceil | Trunc | Round | Not)
}

/// Whether both of `op`'s factors are zero everywhere (`binary_factors`
/// fills 0).
fn binary_flat(op: BinaryOp) -> bool {
    use BinaryOp::*;
    matches!(op, Lt | Le | Gt | Ge | Eq | Ne | And | Or)
}

/// The axes of each step of `plan` and of its first output, from those of
/// the inputs (x, y, z: one each; constants and parameters: none).
fn axes_of(plan: &Plan) -> (Vec<StepAxes>, Axes) {
    let mut m = vec![0 as Axes; plan.nregs];
    for (axis, r) in [REG_X, REG_Y, REG_Z].into_iter().enumerate() {
        m[r] = 1 << axis;
    }
    let unary = |op: UnaryOp, a: Axes| if unary_flat(op) { 0 } else { a };
    let imm = |i: Imm, a: Axes| if binary_flat(i.op) { 0 } else { a };
    let steps = plan
        .steps
        .iter()
        .map(|step| {
            let g = |r: u32| m[r as usize];
            let (out, sa) = match *step {
                Step::Unary { op, out, a } => (
                    out,
                    StepAxes {
                        out: unary(op, g(a)),
                        ops: [g(a), 0, 0],
                    },
                ),
                Step::Binary { op, out, a, b } => (
                    out,
                    StepAxes {
                        out: if binary_flat(op) { 0 } else { g(a) | g(b) },
                        ops: [g(a), g(b), 0],
                    },
                ),
                Step::BinaryImm { imm: i, out, a } => (
                    out,
                    StepAxes {
                        out: imm(i, g(a)),
                        ops: [g(a), 0, 0],
                    },
                ),
                Step::Pair { out, a, pair } => {
                    // The axes of the inner value go in `ops[1]`.
                    let mid = match pair {
                        Pair::ImmUnary(i, _) | Pair::ImmImm(i, _) => imm(i, g(a)),
                        Pair::UnaryImm(op, _) => unary(op, g(a)),
                    };
                    let o = match pair {
                        Pair::ImmUnary(_, op) => unary(op, mid),
                        Pair::UnaryImm(_, i) | Pair::ImmImm(_, i) => imm(i, mid),
                    };
                    (
                        out,
                        StepAxes {
                            out: o,
                            ops: [g(a), mid, 0],
                        },
                    )
                }
                Step::PowI { out, a, n } => (
                    out,
                    StepAxes {
                        out: if n == 0 { 0 } else { g(a) },
                        ops: [g(a), 0, 0],
                    },
                ),
                Step::Select { out, a, b, .. } => (
                    out,
                    StepAxes {
                        out: g(a) | g(b),
                        ops: [g(a), g(b), 0],
                    },
                ),
                // The field's f64 gradient gives every partial.
                Step::Field { out, args, .. } => (
                    out,
                    StepAxes {
                        out: ALL,
                        ops: args.map(g),
                    },
                ),
                Step::Set {
                    out, a, b, alpha, ..
                } => (
                    out,
                    StepAxes {
                        out: g(a) | g(b) | g(alpha),
                        ops: [g(a), g(b), g(alpha)],
                    },
                ),
                Step::SetImm { out, a, b, .. } => (
                    out,
                    StepAxes {
                        out: g(a) | g(b),
                        ops: [g(a), g(b), 0],
                    },
                ),
            };
            m[out as usize] = sa.out;
            sa
        })
        .collect();
    (steps, m[plan.outputs[0] as usize])
}

/// The partials of `d` on the axes of `axes`, [`ZERO`] on the others.
#[inline(always)]
fn or_zero(d: &Partials, axes: Axes) -> [&Lanes; 3] {
    std::array::from_fn(|a| if axes >> a & 1 != 0 { &d[a] } else { &ZERO })
}

/// Batched gradients in f32: value and the three partials for many points,
/// e.g. the normals of every vertex of a mesh.
///
/// Forward mode in f32 lanes over the batch evaluator's plan: the values
/// are bit-identical to [`super::BatchEval`]'s at the same points, and the
/// partials agree with the f64 [`crate::GradEval`] at the same (f32) inputs
/// to f32 rounding of each derivative factor (tested in `tests/grad.rs`).
/// Data-driven fields give their values in batch and their gradients from
/// the field's f64 `grad`, one lane at a time.
pub struct GradBatchEval {
    tape: Tape,
    plan: Arc<Plan>,
    /// The axes of each step of the plan, and of its first output.
    axes: Vec<StepAxes>,
    out_axes: Axes,
    vals: Vec<Lanes>,
    ders: Vec<Partials>,
    /// Derivative factors of the step running (up to three operands).
    k: Box<[Lanes; 3]>,
    /// The inner value of a fused pair and its partials.
    mid: Box<Lanes>,
    mid_d: Box<Partials>,
}

impl GradBatchEval {
    /// An evaluator of `tape` with the parameters at their defaults.
    pub fn new(tape: &Tape) -> Self {
        let plan = tape
            .0
            .plan
            .get_or_init(|| Arc::new(super::plan::lower(tape)))
            .clone();
        let mut vals = vec![[0.0f32; BLOCK]; plan.nregs];
        for &(r, c) in &plan.consts {
            vals[r as usize] = [c; BLOCK];
        }
        for (&r, p) in plan.params.iter().zip(tape.params()) {
            vals[r as usize] = [p.default as f32; BLOCK];
        }
        // Constants and parameters keep zero partials; no step writes them.
        let mut ders = vec![[[0.0f32; BLOCK]; 3]; plan.nregs];
        for (axis, r) in [REG_X, REG_Y, REG_Z].into_iter().enumerate() {
            ders[r][axis] = [1.0; BLOCK];
        }
        let (axes, out_axes) = axes_of(&plan);
        GradBatchEval {
            tape: tape.clone(),
            axes,
            out_axes,
            plan,
            vals,
            ders,
            k: Box::new([[0.0; BLOCK]; 3]),
            mid: Box::new([0.0; BLOCK]),
            mid_d: Box::new([[0.0; BLOCK]; 3]),
        }
    }

    /// Sets parameter `index` (see [`Tape::param_index`]).
    pub fn set_param(&mut self, index: usize, v: f64) {
        self.vals[self.plan.params[index] as usize] = [v as f32; BLOCK];
    }

    /// Fills `out` with value and gradient `[v, dx, dy, dz]` of the first
    /// output at each point `(x[i], y[i], z[i])`; all slices have the same
    /// length (any length).
    pub fn eval(&mut self, x: &[f32], y: &[f32], z: &[f32], out: &mut [[f32; 4]]) {
        let n = out.len();
        assert!(
            x.len() == n && y.len() == n && z.len() == n,
            "slice lengths differ"
        );
        let o = self.plan.outputs[0] as usize;
        let mut start = 0;
        while start < n {
            let len = BLOCK.min(n - start);
            let end = start + len;
            self.vals[REG_X][..len].copy_from_slice(&x[start..end]);
            self.vals[REG_Y][..len].copy_from_slice(&y[start..end]);
            self.vals[REG_Z][..len].copy_from_slice(&z[start..end]);
            self.run(len);
            let (v, d) = (&self.vals[o], or_zero(&self.ders[o], self.out_axes));
            for (i, dst) in out[start..end].iter_mut().enumerate() {
                *dst = [v[i], d[0][i], d[1][i], d[2][i]];
            }
            start = end;
        }
    }

    fn run(&mut self, len: usize) {
        let vals = self.vals.as_mut_ptr();
        let ders = self.ders.as_mut_ptr();
        let [ka, kb, kc] = &mut *self.k;
        let (mid, mid_d) = (&mut *self.mid, &mut *self.mid_d);
        for (step, &ax) in self.plan.steps.iter().zip(&self.axes) {
            let on = ax.out;
            // SAFETY: as in `BatchEval::run`: a step's output register is
            // never one of its inputs and every index is < nregs, in both
            // files (they have the same length), so the output borrows are
            // unique and the input borrows shared borrows of other elements.
            unsafe {
                let o = |r: u32| (&mut *vals.add(r as usize), &mut *ders.add(r as usize));
                let a = |r: u32| (&*vals.add(r as usize), &*ders.add(r as usize));
                match *step {
                    Step::Unary { op, out, a: x } => {
                        let ((ov, od), (av, ad)) = (o(out), a(x));
                        unary_step(op, ov, od, av, ad, ka, on);
                    }
                    Step::Binary {
                        op,
                        out,
                        a: x,
                        b: y,
                    } => {
                        let ((ov, od), (av, ad), (bv, bd)) = (o(out), a(x), a(y));
                        binary(op, ov, av, bv);
                        if on != 0 {
                            binary_factors(op, ka, kb, av, bv, ov);
                            chain2::<false>(od, ad, ka, bd, kb, ax.ops[0], ax.ops[1]);
                        }
                    }
                    Step::BinaryImm { imm, out, a: x } => {
                        let ((ov, od), (av, ad)) = (o(out), a(x));
                        imm_step(imm, ov, od, av, ad, ka, kb, on);
                    }
                    Step::Pair { out, a: x, pair } => {
                        let ((ov, od), (av, ad)) = (o(out), a(x));
                        let inner = ax.ops[1];
                        match pair {
                            Pair::ImmUnary(i, op) => {
                                imm_step(i, mid, mid_d, av, ad, ka, kb, inner);
                                unary_step(op, ov, od, mid, mid_d, ka, on);
                            }
                            Pair::UnaryImm(op, i) => {
                                unary_step(op, mid, mid_d, av, ad, ka, inner);
                                imm_step(i, ov, od, mid, mid_d, ka, kb, on);
                            }
                            Pair::ImmImm(i, j) => {
                                imm_step(i, mid, mid_d, av, ad, ka, kb, inner);
                                imm_step(j, ov, od, mid, mid_d, ka, kb, on);
                            }
                        }
                    }
                    Step::PowI { out, a: x, n } => {
                        let ((ov, od), (av, ad)) = (o(out), a(x));
                        powi(ov, av, n);
                        if on != 0 {
                            // n a^(n - 1), the power by the same products
                            // (n is not 0: its partials have no axes).
                            powi(ka, av, n - 1);
                            let m = n as f32;
                            ka.iter_mut().for_each(|k| *k *= m);
                            chain1(od, ad, ka, on);
                        }
                    }
                    Step::SetImm {
                        op,
                        out,
                        a: x,
                        b: y,
                        alpha,
                    } => {
                        let ((ov, od), (av, ad), (bv, bd)) = (o(out), a(x), a(y));
                        set_imm(op, ov, av, bv, alpha);
                        if on != 0 {
                            set_imm_factors(op, ka, kb, av, bv, alpha);
                            // With the constant parameter's zero term of the f64 rule.
                            chain2::<true>(od, ad, ka, bd, kb, ax.ops[0], ax.ops[1]);
                        }
                    }
                    Step::Set {
                        op,
                        out,
                        a: x,
                        b: y,
                        alpha,
                    } => {
                        let ((ov, od), (av, ad), (bv, bd), (cv, cd)) =
                            (o(out), a(x), a(y), a(alpha));
                        set_reg(op, ov, av, bv, cv);
                        if on != 0 {
                            set_reg_factors(op, [&mut *ka, &mut *kb, &mut *kc], av, bv, cv, ov);
                            let d = [ad, bd, cd];
                            let d: [[&Lanes; 3]; 3] =
                                std::array::from_fn(|j| or_zero(d[j], ax.ops[j]));
                            chain3(od, d, [ka, kb, kc], on);
                        }
                    }
                    Step::Select { out, c, a: x, b: y } => {
                        let ((ov, od), (cv, _), (av, ad), (bv, bd)) = (o(out), a(c), a(x), a(y));
                        let pick = |c: f32, x: f32, y: f32| if c != 0.0 { x } else { y };
                        map3(ov, cv, av, bv, pick);
                        let (ad, bd) = (or_zero(ad, ax.ops[0]), or_zero(bd, ax.ops[1]));
                        for axis in (0..3).filter(|a| on >> a & 1 != 0) {
                            map3(&mut od[axis], cv, ad[axis], bd[axis], pick);
                        }
                    }
                    Step::Field {
                        out,
                        field,
                        comp,
                        args,
                    } => {
                        let (ov, od) = o(out);
                        let q = args.map(a);
                        let f = &*self.tape.fields()[field as usize];
                        if comp == 0 {
                            let (x, y, z) = (q[0].0, q[1].0, q[2].0);
                            f.eval_batch(&x[..len], &y[..len], &z[..len], &mut ov[..len]);
                        }
                        let qd: [[&Lanes; 3]; 3] =
                            std::array::from_fn(|j| or_zero(q[j].1, ax.ops[j]));
                        // Gradients one lane at a time through the field's
                        // f64 `grad`, as the point evaluator does.
                        for i in 0..len {
                            let dual: [(f64, [f64; 3]); 3] = std::array::from_fn(|j| {
                                let d = qd[j];
                                (
                                    q[j].0[i] as f64,
                                    [d[0][i] as f64, d[1][i] as f64, d[2][i] as f64],
                                )
                            });
                            let (v, g) = field_dual(f, comp, dual);
                            if comp != 0 {
                                ov[i] = v as f32;
                            }
                            for axis in 0..3 {
                                od[axis][i] = g[axis] as f32;
                            }
                        }
                    }
                }
            }
        }
    }
}

/// `d k` with a zero factor or partial giving 0 (as `mul0` of the f64
/// rules): a partial that does not depend on an axis stays 0 even where the
/// factor is infinite or NaN.
#[inline(always)]
fn mul0(d: f32, k: f32) -> f32 {
    if d == 0.0 || k == 0.0 {
        0.0
    } else {
        d * k
    }
}

/// Partials of a one-operand step on the axes of `on` (those of the
/// operand or none): `od = mul0(ad, k)`.
#[inline(always)]
fn chain1(od: &mut Partials, ad: &Partials, k: &Lanes, on: Axes) {
    for axis in (0..3).filter(|a| on >> a & 1 != 0) {
        let (o, a) = (&mut od[axis], &ad[axis]);
        for i in 0..BLOCK {
            o[i] = mul0(a[i], k[i]);
        }
    }
}

/// Partials of a two-operand step, summed in the order of the f64 rule;
/// `ZERO_TERM` adds the zero term of a third, constant operand (`+ 0.0`,
/// which turns a partial of -0 into +0 as that rule does). On the axes of
/// only one operand (`ma`, `mb`) the other's term is its +0.
#[inline(always)]
fn chain2<const ZERO_TERM: bool>(
    od: &mut Partials,
    ad: &Partials,
    ka: &Lanes,
    bd: &Partials,
    kb: &Lanes,
    ma: Axes,
    mb: Axes,
) {
    for axis in 0..3 {
        let o = &mut od[axis];
        match (ma >> axis & 1 != 0, mb >> axis & 1 != 0) {
            (true, true) => {
                let (a, b) = (&ad[axis], &bd[axis]);
                for i in 0..BLOCK {
                    let d = mul0(a[i], ka[i]) + mul0(b[i], kb[i]);
                    o[i] = if ZERO_TERM { d + 0.0 } else { d };
                }
            }
            // `t + 0.0` (or `0.0 + t`: the same value, sign of zero
            // included).
            (true, false) => one_term::<ZERO_TERM>(o, &ad[axis], ka),
            (false, true) => one_term::<ZERO_TERM>(o, &bd[axis], kb),
            (false, false) => {}
        }
    }
}

/// `o = mul0(d, k) + 0.0`, and `+ 0.0` again with `ZERO_TERM`: a sum of
/// [`chain2`] whose other term is +0.
#[inline(always)]
fn one_term<const ZERO_TERM: bool>(o: &mut Lanes, d: &Lanes, k: &Lanes) {
    for i in 0..BLOCK {
        let t = mul0(d[i], k[i]) + 0.0;
        o[i] = if ZERO_TERM { t + 0.0 } else { t };
    }
}

/// Partials of a three-operand step on the axes of `on`: the first two
/// terms, then the third.
#[inline(always)]
fn chain3(od: &mut Partials, d: [[&Lanes; 3]; 3], k: [&Lanes; 3], on: Axes) {
    for axis in (0..3).filter(|a| on >> a & 1 != 0) {
        let o = &mut od[axis];
        let (a, b, c) = (d[0][axis], d[1][axis], d[2][axis]);
        for i in 0..BLOCK {
            o[i] = (mul0(a[i], k[0][i]) + mul0(b[i], k[1][i])) + mul0(c[i], k[2][i]);
        }
    }
}

/// Value and partials (on the axes of `on`) of a unary op; `k` is scratch
/// for its factor.
#[inline(always)]
fn unary_step(
    op: UnaryOp,
    ov: &mut Lanes,
    od: &mut Partials,
    av: &Lanes,
    ad: &Partials,
    k: &mut Lanes,
    on: Axes,
) {
    unary(op, ov, av, |v| v, |v| v);
    if on != 0 {
        unary_factor(op, k, av, ov);
        chain1(od, ad, k, on);
    }
}

/// Value and partials (on the axes of `on`: those of the operand or
/// none) of a binary op with a constant operand. The constant's zero term
/// of the f64 rule is added too (`+ 0.0`, which turns a partial of -0 into
/// +0 as that rule does).
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn imm_step(
    imm: Imm,
    ov: &mut Lanes,
    od: &mut Partials,
    av: &Lanes,
    ad: &Partials,
    ka: &mut Lanes,
    kb: &mut Lanes,
    on: Axes,
) {
    if imm.left {
        binary(imm.op, ov, Splat(imm.c), av);
    } else {
        binary(imm.op, ov, av, Splat(imm.c));
    }
    if on == 0 {
        return;
    }
    let k = if imm.left {
        binary_factors(imm.op, ka, kb, Splat(imm.c), av, ov);
        &*kb
    } else {
        binary_factors(imm.op, ka, kb, av, Splat(imm.c), ov);
        &*ka
    };
    for axis in (0..3).filter(|a| on >> a & 1 != 0) {
        let (o, a) = (&mut od[axis], &ad[axis]);
        for i in 0..BLOCK {
            o[i] = mul0(a[i], k[i]) + 0.0;
        }
    }
}

#[inline(always)]
fn t(b: bool) -> f32 {
    if b {
        1.0
    } else {
        0.0
    }
}

/// `k = d op(a) / da` per lane, given `a` and `v = op(a)`.
fn unary_factor(op: UnaryOp, k: &mut Lanes, a: &Lanes, v: &Lanes) {
    use UnaryOp::*;
    macro_rules! lane {
        ($f:expr) => {
            for i in 0..BLOCK {
                k[i] = ($f)(a[i], v[i]);
            }
        };
    }
    match op {
        Neg => k.fill(-1.0),
        Abs => lane!(|a: f32, _| t(a > 0.0) - t(a < 0.0)),
        Sqrt => lane!(|_, v: f32| 0.5 / v),
        Square => lane!(|a: f32, _| 2.0 * a),
        Exp => lane!(|_, v: f32| v),
        Ln => lane!(|a: f32, _| 1.0 / a),
        Sin => lane!(|a: f32, _| simd_math::cos(a)),
        Cos => lane!(|a: f32, _| -simd_math::sin(a)),
        Tan => lane!(|_, v: f32| 1.0 + v * v),
        Asin => lane!(|a: f32, _| 1.0 / (1.0 - a * a).sqrt()),
        Acos => lane!(|a: f32, _| -1.0 / (1.0 - a * a).sqrt()),
        Atan => lane!(|a: f32, _| 1.0 / (1.0 + a * a)),
        Sinh => lane!(|a: f32, _| a.cosh()),
        Cosh => lane!(|a: f32, _| a.sinh()),
        Tanh => lane!(|_, v: f32| 1.0 - v * v),
        Sign | Floor | Ceil | Trunc | Round | Not => k.fill(0.0),
        Fract | Saw => k.fill(1.0),
        Tri => lane!(|a: f32, _| {
            let s = 0.5 * a + 0.25;
            if s - simd_math::floor(s) < 0.5 {
                1.0
            } else {
                -1.0
            }
        }),
    }
}

/// `(ka, kb) = (d op / da, d op / db)` per lane at `(a, b)` with value `v`.
// The pow/ln kernels go in as closures for the reason given at `binary`.
#[allow(clippy::redundant_closure)]
#[inline(always)]
fn binary_factors(
    op: BinaryOp,
    ka: &mut Lanes,
    kb: &mut Lanes,
    a: impl Src,
    b: impl Src,
    v: &Lanes,
) {
    use BinaryOp::*;
    macro_rules! lane {
        ($f:expr) => {
            for i in 0..BLOCK {
                let (x, y) = ($f)(a.at(i), b.at(i), v[i]);
                ka[i] = x;
                kb[i] = y;
            }
        };
    }
    match op {
        Add => {
            ka.fill(1.0);
            kb.fill(1.0);
        }
        Sub => {
            ka.fill(1.0);
            kb.fill(-1.0);
        }
        Mul => lane!(|x: f32, y: f32, _| (y, x)),
        Div => lane!(|x: f32, y: f32, _| (1.0 / y, -x / (y * y))),
        Pow => lane!(|x: f32, y: f32, v: f32| {
            let dx = if y == 0.0 {
                0.0
            } else {
                y * simd_math::pow(x, y - 1.0)
            };
            let dy = if x > 0.0 { v * simd_math::ln(x) } else { 0.0 };
            (dx, dy)
        }),
        Atan2 => lane!(|x: f32, y: f32, _| {
            let r2 = x * x + y * y;
            (y / r2, -x / r2)
        }),
        Min => lane!(|x: f32, y: f32, _| if x <= y { (1.0, 0.0) } else { (0.0, 1.0) }),
        Max => lane!(|x: f32, y: f32, _| if x >= y { (1.0, 0.0) } else { (0.0, 1.0) }),
        Mod => lane!(|x: f32, y: f32, _| (1.0, -simd_math::floor(x / y))),
        Rem => lane!(|x: f32, y: f32, _| (1.0, -(x / y).trunc())),
        Lt | Le | Gt | Ge | Eq | Ne | And | Or => {
            ka.fill(0.0);
            kb.fill(0.0);
        }
    }
}

/// The f32 form of [`SetOp::partials`] for the operands: `(d/da, d/db,
/// d/dalpha)` with `sign` +1 for union, -1 for intersection, the parameter
/// `al`, its scale `k = 1 + al` and the value `v`.
#[inline(always)]
fn set_partials(sign: f32, a: f32, b: f32, al: f32, k: f32, v: f32) -> (f32, f32, f32) {
    let r = (a * a + b * b - 2.0 * al * a * b).sqrt();
    if r == 0.0 || !r.is_finite() {
        return (1.0 / k, 1.0 / k, 0.0);
    }
    let da = (1.0 + sign * (a - al * b) / r) / k;
    let db = (1.0 + sign * (b - al * a) / r) / k;
    let dal = (-sign * a * b / r) / k - v / k;
    (da, db, dal)
}

fn set_sign(op: SetOp) -> f32 {
    if op == SetOp::Union {
        1.0
    } else {
        -1.0
    }
}

/// Factors of a set operation with a constant parameter.
fn set_imm_factors(
    op: SetOp,
    ka: &mut Lanes,
    kb: &mut Lanes,
    a: &Lanes,
    b: &Lanes,
    alpha: SetAlpha,
) {
    let sign = set_sign(op);
    // The parameter as the f32 plan holds it: 2 alpha and 1 + alpha.
    let (al, k) = match alpha.0 {
        None => (0.0, 1.0),
        Some((c2, k)) => (0.5 * c2, k),
    };
    for i in 0..BLOCK {
        let (x, y, _) = set_partials(sign, a[i], b[i], al, k, 0.0);
        ka[i] = x;
        kb[i] = y;
    }
}

/// Factors of a set operation whose parameter is a register.
fn set_reg_factors(op: SetOp, k: [&mut Lanes; 3], a: &Lanes, b: &Lanes, al: &Lanes, v: &Lanes) {
    let sign = set_sign(op);
    let [ka, kb, kc] = k;
    for i in 0..BLOCK {
        let (x, y, z) = set_partials(sign, a[i], b[i], al[i], 1.0 + al[i], v[i]);
        ka[i] = x;
        kb[i] = y;
        kc[i] = z;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ops::SetOp;
    use crate::Expr;

    /// Value and partials at `pts`, with the partials kept to the axes
    /// that can be non-zero (`masked`) or all of them on every step (the
    /// full computation).
    fn grads(tape: &Tape, pts: &[[f32; 3]], masked: bool) -> Vec<[f32; 4]> {
        let mut ev = GradBatchEval::new(tape);
        if !masked {
            for a in &mut ev.axes {
                *a = StepAxes {
                    out: ALL,
                    ops: [ALL; 3],
                };
            }
            ev.out_axes = ALL;
        }
        let (x, y, z): (Vec<f32>, Vec<f32>, Vec<f32>) = (
            pts.iter().map(|p| p[0]).collect(),
            pts.iter().map(|p| p[1]).collect(),
            pts.iter().map(|p| p[2]).collect(),
        );
        let mut out = vec![[0.0f32; 4]; pts.len()];
        ev.eval(&x, &y, &z, &mut out);
        out
    }

    /// Skipping the partials known to be zero changes no bit (signs of
    /// zero, infinities and NaN included), on steps of every kind over
    /// one, two and three axes, with zero factors, flat steps, register
    /// parameters and singular points.
    #[test]
    fn skipped_partials_change_no_bit() {
        let [x, y, z] = Expr::xyz();
        let t = Expr::param("t", 0.3);
        let wave = |c: &Expr| 4.0 * (c / 0.4 - (c / 0.4 + 0.5).floor()).abs() - 1.0;
        let exprs = [
            x.clone(),
            Expr::constant(2.0) + t.clone(),
            (3.0 * &x).sin() * (2.0 * &y).cos() + z.square(),
            wave(&x).square() + wave(&y).square() - (wave(&z).square() + 0.25).sqrt(),
            Expr::select(x.lt(&y), y.sqrt(), (&z * &x).exp()),
            Expr::set(SetOp::Union, &(&x - 0.5), &y.abs(), t.clone()),
            Expr::set(SetOp::Intersection, &x.square(), &(-&y), 0.4),
            Expr::set(SetOp::Union, &x, &y, 0.0).min(&z.max(&(-&x))),
            (&x / &y) + (&z).ln() * x.floor() + y.powi(0) + z.powi(3),
            (-&x * 0.0) + (&y - &y) + x.atan2(&y) + (x.clone() * y.sign()),
            (x.clone() + 1.0).modulo(&(&y + 2.0)) + x.pow(&y) + z.round() * z.tanh(),
            // Registers of three axes reused by values of fewer, read by
            // a select, a set with a register parameter, and the output.
            Expr::select(x.lt(0.0), (&x * &y * &z).sin(), (2.0 * &x).cos()),
            Expr::set(
                SetOp::Union,
                &(&x * &y * &z).sin(),
                &(3.0 * &x).cos(),
                (&y * 0.5).tanh(),
            ),
            Expr::select(
                (&x * &y * &z).sin().lt(0.1),
                (2.0 * &x).cos(),
                (3.0 * &x).sin(),
            ),
            (&x * &y * &z).sin().lt(0.1) + (2.0 * &x).cos() * (3.0 * &y).sin(),
        ];
        let mut pts = Vec::new();
        for &a in &[0.0f32, -0.0, 0.5, -0.7, 1.0, 0.2] {
            for &b in &[0.0f32, -0.0, 0.3, -1.0] {
                for &c in &[0.0f32, -0.0, 0.9, -0.4, 2.0] {
                    pts.push([a, b, c]);
                }
            }
        }
        // Over one block, to check the lanes a block leaves behind.
        let many: Vec<[f32; 3]> = (0..BLOCK + 37).map(|i| pts[i % pts.len()]).collect();
        for e in &exprs {
            let tape = Tape::new(e);
            let (a, b) = (grads(&tape, &many, true), grads(&tape, &many, false));
            for (i, (a, b)) in a.iter().zip(&b).enumerate() {
                assert_eq!(
                    a.map(f32::to_bits),
                    b.map(f32::to_bits),
                    "{e:?} at {:?}: {a:?} against {b:?}",
                    many[i]
                );
            }
        }
    }
}
