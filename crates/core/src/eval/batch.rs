use crate::ops::{BinaryOp, UnaryOp};
use crate::simd_math;
use crate::tape::{Instr, Tape, REG_X, REG_Y, REG_Z};

/// Points per block: each instruction runs over a whole block, which
/// amortises dispatch and lets the loops vectorise.
pub const BLOCK: usize = 256;

type Lanes = [f32; BLOCK];

/// Batch evaluator in f32, the hot path of meshing, slicing and analysis.
///
/// Agreement with the f64 reference: relative error of order 1e-6 per op on
/// well-conditioned expressions (f32 rounding); sin/cos use the polynomial of
/// `simd_math` (absolute error < 5e-7 for |x| < 1e4).
pub struct BatchEval<'t> {
    tape: &'t Tape,
    regs: Vec<Lanes>,
}

impl<'t> BatchEval<'t> {
    pub fn new(tape: &'t Tape) -> Self {
        let mut regs = vec![[0.0f32; BLOCK]; tape.nregs];
        for (r, v) in tape.preload() {
            regs[r as usize] = [v as f32; BLOCK];
        }
        BatchEval { tape, regs }
    }

    pub fn set_param(&mut self, index: usize, v: f64) {
        self.regs[self.tape.params[index].0 as usize] = [v as f32; BLOCK];
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
        let o = self.tape.outputs[k] as usize;
        let mut start = 0;
        while start < n {
            let len = BLOCK.min(n - start);
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
        &self.regs[self.tape.outputs[0] as usize][..len]
    }

    /// The x, y, z input lanes, to fill in place before [`Self::eval_loaded`].
    pub fn coords_mut(&mut self) -> (&mut Lanes, &mut Lanes, &mut Lanes) {
        let (xy, rest) = self.regs.split_at_mut(2);
        let (x, y) = xy.split_at_mut(1);
        (&mut x[0], &mut y[0], &mut rest[0])
    }

    fn load(&mut self, x: &[f32], y: &[f32], z: &[f32]) {
        let len = x.len();
        self.regs[REG_X as usize][..len].copy_from_slice(x);
        self.regs[REG_Y as usize][..len].copy_from_slice(y);
        self.regs[REG_Z as usize][..len].copy_from_slice(z);
    }

    fn run(&mut self, len: usize) {
        let regs = self.regs.as_mut_ptr();
        for ins in &self.tape.instrs {
            // SAFETY: the tape compiler never lets an instruction's output
            // register alias one of its inputs, and all indices are < nregs,
            // so `o` is a unique borrow and the inputs are shared borrows of
            // other elements of `regs`.
            unsafe {
                match *ins {
                    Instr::Unary { op, out, a } => {
                        let o = &mut *regs.add(out as usize);
                        let a = &*regs.add(a as usize);
                        unary(op, o, a);
                    }
                    Instr::Binary { op, out, a, b } => {
                        let o = &mut *regs.add(out as usize);
                        let a = &*regs.add(a as usize);
                        let b = &*regs.add(b as usize);
                        binary(op, o, a, b);
                    }
                    Instr::PowI { out, a, n } => {
                        let o = &mut *regs.add(out as usize);
                        let a = &*regs.add(a as usize);
                        powi(o, a, n);
                    }
                    Instr::Select { out, c, a, b } => {
                        let o = &mut *regs.add(out as usize);
                        let (c, a, b) = (
                            &*regs.add(c as usize),
                            &*regs.add(a as usize),
                            &*regs.add(b as usize),
                        );
                        for i in 0..BLOCK {
                            o[i] = if c[i] != 0.0 { a[i] } else { b[i] };
                        }
                    }
                    Instr::Field {
                        out,
                        field,
                        comp,
                        args,
                    } => {
                        let o = &mut *regs.add(out as usize);
                        let (x, y, z) = (
                            &*regs.add(args[0] as usize),
                            &*regs.add(args[1] as usize),
                            &*regs.add(args[2] as usize),
                        );
                        let f = &self.tape.fields[field as usize];
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

#[inline(always)]
fn map1(o: &mut Lanes, a: &Lanes, f: impl Fn(f32) -> f32) {
    for i in 0..BLOCK {
        o[i] = f(a[i]);
    }
}

#[inline(always)]
fn map2(o: &mut Lanes, a: &Lanes, b: &Lanes, f: impl Fn(f32, f32) -> f32) {
    for i in 0..BLOCK {
        o[i] = f(a[i], b[i]);
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

fn unary(op: UnaryOp, o: &mut Lanes, a: &Lanes) {
    use UnaryOp::*;
    match op {
        Neg => map1(o, a, |v| -v),
        Abs => map1(o, a, f32::abs),
        Sign => map1(o, a, |v| t(v > 0.0) - t(v < 0.0)),
        Sqrt => map1(o, a, f32::sqrt),
        Square => map1(o, a, |v| v * v),
        Exp => map1(o, a, f32::exp),
        Ln => map1(o, a, f32::ln),
        Sin => map1(o, a, simd_math::sin),
        Cos => map1(o, a, simd_math::cos),
        Tan => map1(o, a, f32::tan),
        Asin => map1(o, a, f32::asin),
        Acos => map1(o, a, f32::acos),
        Atan => map1(o, a, f32::atan),
        Sinh => map1(o, a, f32::sinh),
        Cosh => map1(o, a, f32::cosh),
        Tanh => map1(o, a, f32::tanh),
        Floor => map1(o, a, simd_math::floor),
        Ceil => map1(o, a, f32::ceil),
        Trunc => map1(o, a, f32::trunc),
        Round => map1(o, a, f32::round),
        Fract => map1(o, a, |v| v - simd_math::floor(v)),
        Tri => map1(o, a, |u| {
            let s = 0.5 * u + 0.25;
            1.0 - (2.0 * (s - simd_math::floor(s)) - 1.0).abs()
        }),
        Saw => map1(o, a, |u| 0.5 + u - simd_math::floor(u + 0.5)),
        Not => map1(o, a, |v| t(v == 0.0)),
    }
}

fn binary(op: BinaryOp, o: &mut Lanes, a: &Lanes, b: &Lanes) {
    use BinaryOp::*;
    match op {
        Add => map2(o, a, b, |x, y| x + y),
        Sub => map2(o, a, b, |x, y| x - y),
        Mul => map2(o, a, b, |x, y| x * y),
        Div => map2(o, a, b, |x, y| x / y),
        Pow => map2(o, a, b, f32::powf),
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
    let m = n.unsigned_abs();
    map1(o, a, |v| {
        // Square-and-multiply with a loop count fixed by n, so it vectorises.
        let mut base = v;
        let mut acc = 1.0f32;
        let mut e = m;
        while e > 0 {
            if e & 1 == 1 {
                acc *= base;
            }
            base *= base;
            e >>= 1;
        }
        acc
    });
    if n < 0 {
        for v in o.iter_mut() {
            *v = 1.0 / *v;
        }
    }
}
