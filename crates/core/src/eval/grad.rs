use super::deriv::{binary_partials, powi_derivative, unary_derivative};
use crate::field::Field;
use crate::tape::{Op, Tape};

/// Value and gradient of one register.
type Dual = (f64, [f64; 3]);

/// `d * k` with `0 * anything = 0`: a component that does not depend on an
/// axis stays independent of it even where `k` is infinite (e.g. the
/// derivative of sqrt at 0 on an axis of symmetry).
fn mul0(d: f64, k: f64) -> f64 {
    if d == 0.0 || k == 0.0 {
        0.0
    } else {
        d * k
    }
}
fn lin(d: &[f64; 3], k: f64) -> [f64; 3] {
    [mul0(d[0], k), mul0(d[1], k), mul0(d[2], k)]
}
fn lin2(da: &[f64; 3], ka: f64, db: &[f64; 3], kb: f64) -> [f64; 3] {
    [
        mul0(da[0], ka) + mul0(db[0], kb),
        mul0(da[1], ka) + mul0(db[1], kb),
        mul0(da[2], ka) + mul0(db[2], kb),
    ]
}

/// Chain rule through a field: d f(q(p)) = sum_k (df/dq_k) dq_k.
pub(in crate::eval) fn field_dual(f: &dyn Field, comp: u8, q: [Dual; 3]) -> Dual {
    let pos = [q[0].0, q[1].0, q[2].0];
    let (v, g) = if comp == 0 {
        f.grad(pos)
    } else {
        // The value is a partial derivative; its own gradient by central
        // differences of the analytic gradient.
        let c = comp as usize - 1;
        let v = f.grad(pos).1[c];
        let g = std::array::from_fn(|k| {
            let h = 1e-6 * (1.0 + pos[k].abs());
            let mut a = pos;
            let mut b = pos;
            a[k] += h;
            b[k] -= h;
            (f.grad(a).1[c] - f.grad(b).1[c]) / (2.0 * h)
        });
        (v, g)
    };
    let mut d = [0.0; 3];
    for k in 0..3 {
        for (a, da) in d.iter_mut().enumerate() {
            if g[k] != 0.0 {
                *da += g[k] * q[k].1[a];
            }
        }
    }
    (v, d)
}

/// Forward-mode gradient evaluator for single points in f64 (the reference,
/// used for Newton steps, normals and the normalised offset checks).
pub struct GradEval {
    tape: Tape,
    params: Vec<f64>,
    slots: Vec<Dual>,
}

impl GradEval {
    /// An evaluator of `tape` with the parameters at their defaults.
    pub fn new(tape: &Tape) -> Self {
        GradEval {
            tape: tape.clone(),
            params: tape.params().iter().map(|p| p.default).collect(),
            slots: vec![(0.0, [0.0; 3]); tape.ops().len()],
        }
    }

    /// Sets parameter `index` (see [`Tape::param_index`]).
    pub fn set_param(&mut self, index: usize, v: f64) {
        self.params[index] = v;
    }

    /// Value and gradient of the first output at `p`.
    pub fn eval(&mut self, p: [f64; 3]) -> (f64, [f64; 3]) {
        self.eval_output(0, p)
    }

    /// Value and gradient of output `k` at `p`.
    pub fn eval_output(&mut self, k: usize, p: [f64; 3]) -> (f64, [f64; 3]) {
        let s = &mut self.slots;
        for (i, op) in self.tape.ops().iter().enumerate() {
            s[i] = match *op {
                Op::Var(a) => {
                    let mut d = [0.0; 3];
                    d[a as usize] = 1.0;
                    (p[a as usize], d)
                }
                Op::Const(c) => (c, [0.0; 3]),
                Op::Param(k) => (self.params[k as usize], [0.0; 3]),
                Op::Unary(op, a) => {
                    let (av, ad) = s[a as usize];
                    let v = op.apply(av);
                    (v, lin(&ad, unary_derivative(op, av, v)))
                }
                Op::Binary(op, a, b) => {
                    let (av, ad) = s[a as usize];
                    let (bv, bd) = s[b as usize];
                    let v = op.apply(av, bv);
                    let (ka, kb) = binary_partials(op, av, bv, v);
                    (v, lin2(&ad, ka, &bd, kb))
                }
                Op::PowI(a, n) => {
                    let (av, ad) = s[a as usize];
                    (av.powi(n), lin(&ad, powi_derivative(av, n)))
                }
                Op::Select(c, a, b) => {
                    if s[c as usize].0 != 0.0 {
                        s[a as usize]
                    } else {
                        s[b as usize]
                    }
                }
                Op::Set { op, a, b, alpha } => {
                    let (av, ad) = s[a as usize];
                    let (bv, bd) = s[b as usize];
                    let (cv, cd) = s[alpha as usize];
                    let v = op.apply(av, bv, cv);
                    let (ka, kb, kc) = op.partials(av, bv, cv, v);
                    let d = lin2(&ad, ka, &bd, kb);
                    let e = lin(&cd, kc);
                    (v, [d[0] + e[0], d[1] + e[1], d[2] + e[2]])
                }
                Op::Field { field, comp, args } => {
                    let q = args.map(|a| s[a as usize]);
                    field_dual(&*self.tape.fields()[field as usize], comp, q)
                }
            };
        }
        s[self.tape.outputs()[k] as usize]
    }
}
