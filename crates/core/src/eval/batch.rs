//! The f32 batch evaluator: the tape, lowered to a [`plan::Plan`], runs one
//! step at a time over blocks of lanes with loops the compiler vectorises.

pub(crate) mod grad;
pub(crate) mod plan;

use crate::ops::SetOp;
use crate::ops::{BinaryOp, UnaryOp};
use crate::simd_math;
use crate::tape::Tape;
use plan::{Imm, Pair, Plan, SetAlpha, Step};
use std::sync::Arc;

const REG_X: usize = 0;
const REG_Y: usize = 1;
const REG_Z: usize = 2;

/// Points per block: each instruction runs over a whole block, which
/// amortises dispatch and lets the loops vectorise.
pub const BLOCK: usize = 256;

type Lanes = [f32; BLOCK];

/// Batch evaluator in f32, the hot path of meshing, slicing and analysis.
///
/// Agreement with the f64 reference at the same f32 input (tested in
/// `tests/batch.rs`): per op `|batch - point| <= 1e-6 |point| + 5e-7` away from
/// the jumps of discontinuous ops (sin/cos use the polynomial of `simd_math`,
/// absolute error < 5e-7 for |x| < 1e4; exp, ln and pow its kernels within
/// 1 ulp, `tests/simd_math.rs`); for graphs of up to 16 ops with
/// Lipschitz constants near 1 and values in [-1, 1], `<= 2e-6`.
pub struct BatchEval {
    tape: Tape,
    plan: Arc<Plan>,
    regs: Vec<Lanes>,
}

impl BatchEval {
    /// An evaluator of `tape` with the parameters at their defaults. The
    /// tape's lowering is made once and shared by all its batch evaluators.
    pub fn new(tape: &Tape) -> Self {
        let plan = tape
            .0
            .plan
            .get_or_init(|| Arc::new(plan::lower(tape)))
            .clone();
        let mut regs = vec![[0.0f32; BLOCK]; plan.nregs];
        for &(r, c) in &plan.consts {
            regs[r as usize] = [c; BLOCK];
        }
        for (&r, p) in plan.params.iter().zip(tape.params()) {
            regs[r as usize] = [p.default as f32; BLOCK];
        }
        BatchEval {
            tape: tape.clone(),
            plan,
            regs,
        }
    }

    /// Sets parameter `index` (see [`Tape::param_index`]).
    pub fn set_param(&mut self, index: usize, v: f64) {
        self.regs[self.plan.params[index] as usize] = [v as f32; BLOCK];
    }

    /// Evaluates the first output at the points `(x[i], y[i], z[i])`.
    /// All slices must have the same length (any length).
    pub fn eval(&mut self, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        self.eval_output(0, x, y, z, out)
    }

    /// Evaluates output `k` (see [`Tape::with_outputs`]).
    pub fn eval_output(&mut self, k: usize, x: &[f32], y: &[f32], z: &[f32], out: &mut [f32]) {
        let n = out.len();
        assert!(
            x.len() == n && y.len() == n && z.len() == n,
            "slice lengths differ"
        );
        let o = self.plan.outputs[k] as usize;
        let mut start = 0;
        while start < n {
            let len = BLOCK.min(n - start);
            let next = (start + len)..n.min(start + len + BLOCK);
            prefetch(&x[next.clone()]);
            prefetch(&y[next.clone()]);
            prefetch(&z[next.clone()]);
            prefetch(&out[next]);
            self.load(
                &x[start..start + len],
                &y[start..start + len],
                &z[start..start + len],
            );
            self.run(len);
            out[start..start + len].copy_from_slice(&self.regs[o][..len]);
            start += len;
        }
    }

    /// Evaluates a block already loaded with [`Self::coords_mut`]; returns the
    /// first output's lanes. For callers that generate coordinates in place.
    pub fn eval_loaded(&mut self, len: usize) -> &[f32] {
        self.run(len);
        &self.regs[self.plan.outputs[0] as usize][..len]
    }

    /// The x, y, z input lanes, to fill in place before [`Self::eval_loaded`].
    pub fn coords_mut(&mut self) -> (&mut Lanes, &mut Lanes, &mut Lanes) {
        let (xy, rest) = self.regs.split_at_mut(2);
        let (x, y) = xy.split_at_mut(1);
        (&mut x[0], &mut y[0], &mut rest[0])
    }

    fn load(&mut self, x: &[f32], y: &[f32], z: &[f32]) {
        let len = x.len();
        self.regs[REG_X][..len].copy_from_slice(x);
        self.regs[REG_Y][..len].copy_from_slice(y);
        self.regs[REG_Z][..len].copy_from_slice(z);
    }

    fn run(&mut self, len: usize) {
        let regs = self.regs.as_mut_ptr();
        for step in &self.plan.steps {
            // SAFETY: the plan never lets a step's output register alias one
            // of its inputs, and all indices are < nregs, so `o` is a unique
            // borrow and the inputs are shared borrows of other elements.
            unsafe {
                let o = |r: u32| &mut *regs.add(r as usize);
                let a = |r: u32| &*regs.add(r as usize);
                match *step {
                    Step::Unary { op, out, a: x } => unary(op, o(out), a(x), |v| v, |v| v),
                    Step::Binary {
                        op,
                        out,
                        a: x,
                        b: y,
                    } => binary(op, o(out), a(x), a(y)),
                    Step::BinaryImm { imm, out, a: x } if imm.left => {
                        binary(imm.op, o(out), Splat(imm.c), a(x))
                    }
                    Step::BinaryImm { imm, out, a: x } => {
                        binary(imm.op, o(out), a(x), Splat(imm.c))
                    }
                    Step::Pair { out, a: x, pair } => run_pair(o(out), a(x), pair),
                    Step::PowI { out, a: x, n } => powi(o(out), a(x), n),
                    Step::SetImm {
                        op,
                        out,
                        a: x,
                        b: y,
                        alpha,
                    } => set_imm(op, o(out), a(x), a(y), alpha),
                    Step::Set {
                        op,
                        out,
                        a: x,
                        b: y,
                        alpha,
                    } => set_reg(op, o(out), a(x), a(y), a(alpha)),
                    Step::Select { out, c, a: x, b: y } => map3(
                        o(out),
                        a(c),
                        a(x),
                        a(y),
                        |c, x, y| if c != 0.0 { x } else { y },
                    ),
                    Step::Field {
                        out,
                        field,
                        comp,
                        args,
                    } => {
                        let (x, y, z) = (a(args[0]), a(args[1]), a(args[2]));
                        let o = o(out);
                        let f = &self.tape.fields()[field as usize];
                        if comp == 0 {
                            f.eval_batch(&x[..len], &y[..len], &z[..len], &mut o[..len]);
                        } else {
                            for i in 0..len {
                                let g = f.grad([x[i] as f64, y[i] as f64, z[i] as f64]).1;
                                o[i] = g[comp as usize - 1] as f32;
                            }
                        }
                    }
                }
            }
        }
    }
}

/// Receives the per-lane function of a fused pair's first half.
trait LaneFn {
    fn with(self, f: impl Fn(f32) -> f32 + Copy);
}

/// Calls `k` with the per-lane function of an affine immediate.
#[inline(always)]
fn with_imm(imm: Imm, k: impl LaneFn) {
    let c = imm.c;
    match (imm.op, imm.left) {
        (BinaryOp::Add, _) => k.with(move |x| x + c),
        (BinaryOp::Sub, false) => k.with(move |x| x - c),
        (BinaryOp::Sub, true) => k.with(move |x| c - x),
        (BinaryOp::Mul, _) => k.with(move |x| x * c),
        (BinaryOp::Div, false) => k.with(move |x| x / c),
        (BinaryOp::Div, true) => k.with(move |x| c / x),
        _ => unreachable!("the plan links only affine immediates"),
    }
}

/// Both steps of a pair in one pass over the block.
fn run_pair(o: &mut Lanes, a: &Lanes, pair: Pair) {
    /// Runs a unary op after the received function.
    struct Pre<'a>(UnaryOp, &'a mut Lanes, &'a Lanes);
    impl LaneFn for Pre<'_> {
        #[inline(always)]
        fn with(self, f: impl Fn(f32) -> f32 + Copy) {
            unary(self.0, self.1, self.2, f, |v| v)
        }
    }
    /// Runs a unary op before the received function.
    struct Post<'a>(UnaryOp, &'a mut Lanes, &'a Lanes);
    impl LaneFn for Post<'_> {
        #[inline(always)]
        fn with(self, f: impl Fn(f32) -> f32 + Copy) {
            unary(self.0, self.1, self.2, |v| v, f)
        }
    }
    /// Runs an immediate after the received function.
    struct Then<'a>(Imm, &'a mut Lanes, &'a Lanes);
    impl LaneFn for Then<'_> {
        #[inline(always)]
        fn with(self, f: impl Fn(f32) -> f32 + Copy) {
            struct Last<'a, F>(F, &'a mut Lanes, &'a Lanes);
            impl<F: Fn(f32) -> f32 + Copy> LaneFn for Last<'_, F> {
                #[inline(always)]
                fn with(self, g: impl Fn(f32) -> f32 + Copy) {
                    let f = self.0;
                    map1(self.1, self.2, |v| g(f(v)))
                }
            }
            with_imm(self.0, Last(f, self.1, self.2))
        }
    }
    match pair {
        Pair::ImmUnary(i, op) => with_imm(i, Pre(op, o, a)),
        Pair::UnaryImm(op, i) => with_imm(i, Post(op, o, a)),
        Pair::ImmImm(i, j) => with_imm(i, Then(j, o, a)),
    }
}

/// Asks the cache for `s` ahead of use, so the next block's coordinates
/// stream in from memory while this block computes (without it, copying them
/// in stalls on memory for a fifth of the time on large inputs).
#[inline(always)]
fn prefetch(s: &[f32]) {
    #[cfg(target_arch = "x86_64")]
    for line in s.chunks(16) {
        use std::arch::x86_64::{_mm_prefetch, _MM_HINT_T0};
        // SAFETY: a prefetch is only a hint; it never faults, whatever the address.
        #[allow(unused_unsafe)]
        unsafe {
            _mm_prefetch::<_MM_HINT_T0>(line.as_ptr() as *const i8)
        };
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = s;
}

/// An operand of a vectorised loop: a register block or one value for all lanes.
trait Src: Copy {
    fn at(self, i: usize) -> f32;
}

impl Src for &Lanes {
    #[inline(always)]
    fn at(self, i: usize) -> f32 {
        self[i]
    }
}

#[derive(Clone, Copy)]
struct Splat(f32);

impl Src for Splat {
    #[inline(always)]
    fn at(self, _: usize) -> f32 {
        self.0
    }
}

#[inline(always)]
fn map1(o: &mut Lanes, a: &Lanes, f: impl Fn(f32) -> f32) {
    for i in 0..BLOCK {
        o[i] = f(a[i]);
    }
}

#[inline(always)]
fn map2(o: &mut Lanes, a: impl Src, b: impl Src, f: impl Fn(f32, f32) -> f32) {
    for (i, o) in o.iter_mut().enumerate() {
        *o = f(a.at(i), b.at(i));
    }
}

#[inline(always)]
fn map3(o: &mut Lanes, a: &Lanes, b: &Lanes, c: &Lanes, f: impl Fn(f32, f32, f32) -> f32) {
    for i in 0..BLOCK {
        o[i] = f(a[i], b[i], c[i]);
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

/// `post(op(pre(v)))` over a block: `pre` and `post` are the identity or
/// the immediate op of a fused [`Step::Pair`].
// The exp/ln/pow kernels go in as closures: passed as fn items they were
// called per lane through a shim that was not inlined (scalar code, 3x slower).
#[allow(clippy::redundant_closure)]
#[inline(always)]
fn unary(
    op: UnaryOp,
    o: &mut Lanes,
    a: &Lanes,
    pre: impl Fn(f32) -> f32 + Copy,
    post: impl Fn(f32) -> f32 + Copy,
) {
    use UnaryOp::*;
    macro_rules! lane {
        ($f:expr) => {
            map1(o, a, |v| post(($f)(pre(v))))
        };
    }
    match op {
        Neg => lane!(|v: f32| -v),
        Abs => lane!(f32::abs),
        Sign => lane!(|v: f32| t(v > 0.0) - t(v < 0.0)),
        Sqrt => lane!(f32::sqrt),
        Square => lane!(|v: f32| v * v),
        Exp => lane!(|v| simd_math::exp(v)),
        Ln => lane!(|v| simd_math::ln(v)),
        Sin => lane!(simd_math::sin),
        Cos => lane!(simd_math::cos),
        Tan => lane!(f32::tan),
        Asin => lane!(f32::asin),
        Acos => lane!(f32::acos),
        Atan => lane!(f32::atan),
        Sinh => lane!(f32::sinh),
        Cosh => lane!(f32::cosh),
        Tanh => lane!(f32::tanh),
        Floor => lane!(simd_math::floor),
        Ceil => lane!(f32::ceil),
        Trunc => lane!(f32::trunc),
        Round => lane!(f32::round),
        Fract => lane!(|v: f32| v - simd_math::floor(v)),
        Tri => lane!(|u: f32| {
            let s = 0.5 * u + 0.25;
            1.0 - (2.0 * (s - simd_math::floor(s)) - 1.0).abs()
        }),
        Saw => lane!(|u: f32| 0.5 + u - simd_math::floor(u + 0.5)),
        Not => lane!(|v: f32| t(v == 0.0)),
    }
}

// The exp/ln/pow kernels go in as closures: passed as fn items they were
// called per lane through a shim that was not inlined (scalar code, 3x slower).
#[allow(clippy::redundant_closure)]
fn binary(op: BinaryOp, o: &mut Lanes, a: impl Src, b: impl Src) {
    use BinaryOp::*;
    match op {
        Add => map2(o, a, b, |x, y| x + y),
        Sub => map2(o, a, b, |x, y| x - y),
        Mul => map2(o, a, b, |x, y| x * y),
        Div => map2(o, a, b, |x, y| x / y),
        Pow => map2(o, a, b, |x, y| simd_math::pow(x, y)),
        Atan2 => map2(o, a, b, f32::atan2),
        // NaN-propagating like the reference (ops::fmin/fmax).
        Min => map2(o, a, b, |x, y| {
            let m = if x < y { x } else { y };
            if x.is_nan() {
                x
            } else {
                m
            }
        }),
        Max => map2(o, a, b, |x, y| {
            let m = if x > y { x } else { y };
            if x.is_nan() {
                x
            } else {
                m
            }
        }),
        Mod => map2(o, a, b, |x, y| x - y * simd_math::floor(x / y)),
        Rem => map2(o, a, b, |x, y| x % y),
        Lt => map2(o, a, b, |x, y| t(x < y)),
        Le => map2(o, a, b, |x, y| t(x <= y)),
        Gt => map2(o, a, b, |x, y| t(x > y)),
        Ge => map2(o, a, b, |x, y| t(x >= y)),
        Eq => map2(o, a, b, |x, y| t(x == y)),
        Ne => map2(o, a, b, |x, y| t(x != y)),
        And => map2(o, a, b, |x, y| t(x != 0.0 && y != 0.0)),
        Or => map2(o, a, b, |x, y| t(x != 0.0 || y != 0.0)),
    }
}

fn powi(o: &mut Lanes, a: &Lanes, n: i32) {
    // Square-and-multiply over the bits of |n|, each step one loop over
    // the lanes (the loop over the bits inside a lane's closure stayed
    // scalar): per lane the same products in the same order, `acc` from
    // 1 times the set bits' powers of `a`, as the per-lane form.
    let mut e = n.unsigned_abs();
    let mut base = *a;
    o.fill(1.0);
    while e > 0 {
        if e & 1 == 1 {
            for (acc, &b) in o.iter_mut().zip(&base) {
                *acc *= b;
            }
        }
        e >>= 1;
        if e > 0 {
            for b in base.iter_mut() {
                *b *= *b;
            }
        }
    }
    if n < 0 {
        for v in o.iter_mut() {
            *v = 1.0 / *v;
        }
    }
}

/// A set operation with a fixed parameter, with the same f32 operations in
/// the same order as the written-out formula (so bit-identical to it).
fn set_imm(op: SetOp, o: &mut Lanes, a: &Lanes, b: &Lanes, alpha: SetAlpha) {
    let root0 = |x: f32, y: f32| (x * x + y * y).sqrt();
    match (op, alpha.0) {
        (SetOp::Union, None) => map2(o, a, b, |x, y| (x + y) + root0(x, y)),
        (SetOp::Intersection, None) => map2(o, a, b, |x, y| (x + y) - root0(x, y)),
        (SetOp::Union, Some((c2, k))) => map2(o, a, b, |x, y| {
            ((x + y) + (x * x + y * y - c2 * x * y).sqrt()) / k
        }),
        (SetOp::Intersection, Some((c2, k))) => map2(o, a, b, |x, y| {
            ((x + y) - (x * x + y * y - c2 * x * y).sqrt()) / k
        }),
    }
}

/// A set operation whose parameter varies per lane.
fn set_reg(op: SetOp, o: &mut Lanes, a: &Lanes, b: &Lanes, al: &Lanes) {
    let sign = if op == SetOp::Union { 1.0f32 } else { -1.0 };
    for i in 0..BLOCK {
        let (x, y, t) = (a[i], b[i], al[i]);
        let r = (x * x + y * y - 2.0 * t * x * y).sqrt();
        // Negating the root is exact, so `s + -r` equals `s - r` bit for bit.
        let v = (x + y) + sign * r;
        o[i] = if t == 0.0 { v } else { v / (1.0 + t) };
    }
}

#[cfg(test)]
mod tests {
    use super::plan::{lower, Step};
    use super::BatchEval;
    use crate::frep::{intersection, union};
    use crate::{simd_math, Expr, PointEval, Tape, UnaryOp};

    /// Points spread over [-2, 2]^3, more than one block and a partial one.
    fn points(n: usize) -> (Vec<f32>, Vec<f32>, Vec<f32>) {
        let c = |i: usize, k: usize| (((i * k) % 1000) as f32 / 250.0) - 2.0;
        (
            (0..n).map(|i| c(i, 7)).collect(),
            (0..n).map(|i| c(i, 13)).collect(),
            (0..n).map(|i| c(i, 29)).collect(),
        )
    }

    fn eval(e: &Expr, x: &[f32], y: &[f32], z: &[f32]) -> Vec<f32> {
        let tape = Tape::new(e);
        let mut out = vec![0.0; x.len()];
        BatchEval::new(&tape).eval(x, y, z, &mut out);
        out
    }

    fn set_steps(e: &Expr) -> usize {
        let plan = lower(&Tape::new(e));
        plan.steps
            .iter()
            .filter(|s| matches!(s, Step::SetImm { .. } | Step::Set { .. }))
            .count()
    }

    #[test]
    fn set_steps_are_bit_identical_to_their_formula() {
        let (x, y, z) = points(700);
        let [px, py, pz] = Expr::xyz();
        let f1 = &px - 0.3;
        let f2 = py.square() - &pz;
        let e = intersection(&union(&f1, &f2, 0.0), &(1.0 - &pz), 0.0);
        assert_eq!(set_steps(&e), 2);
        let got = eval(&e, &x, &y, &z);
        for i in 0..x.len() {
            let (a, b) = (x[i] - 0.3f32, y[i] * y[i] - z[i]);
            let u = (a + b) + (a * a + b * b).sqrt();
            let c = 1.0f32 - z[i];
            let want = (u + c) - (u * u + c * c).sqrt();
            assert_eq!(got[i].to_bits(), want.to_bits(), "point {i}");
        }
        // Another alpha: the scaled form with `2 alpha` and `1 + alpha`.
        let e = union(&f1, &f2, 0.4);
        assert_eq!(set_steps(&e), 1);
        let got = eval(&e, &x, &y, &z);
        for i in 0..x.len() {
            let (a, b) = (x[i] - 0.3f32, y[i] * y[i] - z[i]);
            let want = ((a + b) + (a * a + b * b - 0.8f32 * a * b).sqrt()) / 1.4f32;
            assert_eq!(got[i].to_bits(), want.to_bits(), "point {i}");
        }
    }

    #[test]
    fn set_steps_with_a_field_parameter_match_the_reference() {
        let (x, y, z) = points(700);
        let [px, py, pz] = Expr::xyz();
        let alpha = 0.5 * (pz.sin());
        let e = intersection(&(&px - 0.3), &py, alpha);
        let tape = Tape::new(&e);
        let got = eval(&e, &x, &y, &z);
        let mut point = PointEval::new(&tape);
        for i in 0..x.len() {
            let want = point.eval([x[i] as f64, y[i] as f64, z[i] as f64]);
            assert!((got[i] as f64 - want).abs() < 1e-5, "{} vs {want}", got[i]);
        }
    }

    #[test]
    fn shared_intermediates_are_not_fused() {
        // The root term is read twice, so it must stay a value of its own.
        let [px, py, _] = Expr::xyz();
        let root = (px.square() + py.square()).sqrt();
        let e = (&px + &py + &root) * &root;
        assert_eq!(set_steps(&e), 0);
        let (x, y, z) = points(300);
        let got = eval(&e, &x, &y, &z);
        for i in 0..x.len() {
            let r = (x[i] * x[i] + y[i] * y[i]).sqrt();
            assert_eq!(got[i], (x[i] + y[i] + r) * r);
        }
    }

    #[test]
    fn immediates_on_either_side_match_the_reference() {
        let (x, y, z) = points(600);
        let px = Expr::x();
        let c = Expr::constant(0.75);
        type Op = fn(&Expr, &Expr) -> Expr;
        let ops: Vec<(&str, Op)> = vec![
            ("add", |a, b| a + b),
            ("sub", |a, b| a - b),
            ("mul", |a, b| a * b),
            ("div", |a, b| a / b),
            ("min", |a, b| a.min(b)),
            ("max", |a, b| a.max(b)),
            ("mod", |a, b| a.modulo(b)),
            ("lt", |a, b| a.lt(b)),
            ("atan2", |a, b| a.atan2(b)),
        ];
        for (name, op) in ops {
            for e in [op(&px, &c), op(&c, &px)] {
                let tape = Tape::new(&e);
                let imm = lower(&tape)
                    .steps
                    .iter()
                    .all(|s| matches!(s, Step::BinaryImm { .. }));
                assert!(imm, "{name}: constant not folded into the step");
                let got = eval(&e, &x, &y, &z);
                let mut point = PointEval::new(&tape);
                for i in 0..x.len() {
                    let want = point.eval([x[i] as f64, y[i] as f64, z[i] as f64]);
                    let g = got[i] as f64;
                    let close = g == want || (g - want).abs() <= 1e-5 * (1.0 + want.abs());
                    assert!(
                        close || (g.is_nan() && want.is_nan()),
                        "{name} {e:?} at x = {}: {} vs {want}",
                        x[i],
                        got[i]
                    );
                }
            }
        }
    }

    #[test]
    fn fused_pairs_are_bit_identical_to_their_formula() {
        let (x, y, z) = points(700);
        let [px, py, _] = Expr::xyz();
        let wave = Expr::unary(UnaryOp::Tri, &px / 0.3);
        let e = (2.0 * wave - 1.0) * (py.sin() - 0.4);
        let plan = lower(&Tape::new(&e));
        let pairs = plan.steps.iter().filter(|s| matches!(s, Step::Pair { .. }));
        assert_eq!(pairs.count(), 3, "{:?}", plan.steps);
        let got = eval(&e, &x, &y, &z);
        for i in 0..x.len() {
            let s = 0.5 * (x[i] / 0.3f32) + 0.25;
            let tri = 1.0 - (2.0 * (s - s.floor()) - 1.0).abs();
            let want = (2.0 * tri - 1.0) * (simd_math::sin(y[i]) - 0.4f32);
            assert_eq!(got[i].to_bits(), want.to_bits(), "point {i}");
        }
    }

    #[test]
    fn parameters_and_constant_outputs_survive_lowering() {
        let (x, y, z) = points(300);
        let r = Expr::param("r", 1.0);
        let e = &r - Expr::x().square();
        let tape = Tape::new(&e);
        let mut ev = BatchEval::new(&tape);
        let mut out = vec![0.0; x.len()];
        ev.eval(&x, &y, &z, &mut out);
        assert_eq!(out[5], 1.0 - x[5] * x[5]);
        ev.set_param(tape.param_index("r").unwrap(), 3.0);
        ev.eval(&x, &y, &z, &mut out);
        assert_eq!(out[5], 3.0 - x[5] * x[5]);

        let two = Tape::with_outputs(&[Expr::constant(2.5), Expr::y()]);
        let mut ev = BatchEval::new(&two);
        ev.eval_output(0, &x, &y, &z, &mut out);
        assert!(out.iter().all(|&v| v == 2.5));
        ev.eval_output(1, &x, &y, &z, &mut out);
        assert_eq!(out, y);
    }

    /// Integer powers give, bit for bit, the per-lane square-and-multiply
    /// (1 times the set bits' powers, the base squared after each bit;
    /// then the reciprocal for negative exponents) for every exponent in
    /// -16..=16 and bases of every kind: signed zeros, subnormals, huge
    /// values that overflow, infinities, NaN.
    #[test]
    fn integer_powers_are_the_per_lane_products() {
        let per_lane = |v: f32, n: i32| {
            let (mut base, mut acc, mut e) = (v, 1.0f32, n.unsigned_abs());
            while e > 0 {
                if e & 1 == 1 {
                    acc *= base;
                }
                base *= base;
                e >>= 1;
            }
            if n < 0 {
                1.0 / acc
            } else {
                acc
            }
        };
        let mut xs: Vec<f32> = (0..super::BLOCK as i32 + 37)
            .map(|k| (k - 150) as f32 * 0.0173 + 1e-3 * (k % 7) as f32)
            .collect();
        xs.extend([
            0.0,
            -0.0,
            1e-40,
            -3e-39,
            f32::MIN_POSITIVE,
            1e20,
            -3e15,
            f32::MAX,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            1.0,
            -1.0,
        ]);
        let zeros = vec![0f32; xs.len()];
        let mut out = vec![0f32; xs.len()];
        for n in -16..=16 {
            let tape = Tape::new(&Expr::x().powi(n));
            assert!(
                n.abs() < 3
                    || tape
                        .ops()
                        .iter()
                        .any(|op| matches!(op, crate::Op::PowI(..))),
                "n = {n}"
            );
            BatchEval::new(&tape).eval(&xs, &zeros, &zeros, &mut out);
            for (&x, &got) in xs.iter().zip(&out) {
                let want = per_lane(x, n);
                assert!(
                    got.to_bits() == want.to_bits() || (got.is_nan() && want.is_nan()),
                    "{x:e}^{n}: {got:e} vs {want:e}"
                );
            }
        }
    }
}
