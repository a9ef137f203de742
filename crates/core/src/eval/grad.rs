use super::batch::BLOCK;
use super::deriv::{binary_partials, powi_derivative, unary_derivative};
use crate::field::Field;
use crate::tape::{Instr, Tape, REG_X, REG_Y, REG_Z};

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
fn field_dual(f: &dyn Field, comp: u8, q: [Dual; 3]) -> Dual {
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
pub struct GradEval<'t> {
    tape: &'t Tape,
    regs: Vec<Dual>,
}

impl<'t> GradEval<'t> {
    pub fn new(tape: &'t Tape) -> Self {
        let mut regs = vec![(0.0, [0.0; 3]); tape.nregs];
        for (r, v) in tape.preload() {
            regs[r as usize] = (v, [0.0; 3]);
        }
        GradEval { tape, regs }
    }

    pub fn set_param(&mut self, index: usize, v: f64) {
        self.regs[self.tape.params[index].0 as usize] = (v, [0.0; 3]);
    }

    /// Value and gradient of the first output at `p`.
    pub fn eval(&mut self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let r = &mut self.regs;
        r[REG_X as usize] = (p[0], [1.0, 0.0, 0.0]);
        r[REG_Y as usize] = (p[1], [0.0, 1.0, 0.0]);
        r[REG_Z as usize] = (p[2], [0.0, 0.0, 1.0]);
        for ins in &self.tape.instrs {
            match *ins {
                Instr::Unary { op, out, a } => {
                    let (av, ad) = r[a as usize];
                    let v = op.apply(av);
                    let k = unary_derivative(op, av, v);
                    r[out as usize] = (v, lin(&ad, k));
                }
                Instr::Binary { op, out, a, b } => {
                    let (av, ad) = r[a as usize];
                    let (bv, bd) = r[b as usize];
                    let v = op.apply(av, bv);
                    let (ka, kb) = binary_partials(op, av, bv, v);
                    r[out as usize] = (v, lin2(&ad, ka, &bd, kb));
                }
                Instr::PowI { out, a, n } => {
                    let (av, ad) = r[a as usize];
                    r[out as usize] = (av.powi(n), lin(&ad, powi_derivative(av, n)));
                }
                Instr::Select { out, c, a, b } => {
                    r[out as usize] = if r[c as usize].0 != 0.0 {
                        r[a as usize]
                    } else {
                        r[b as usize]
                    };
                }
                Instr::Field {
                    out,
                    field,
                    comp,
                    args,
                } => {
                    let q = args.map(|a| r[a as usize]);
                    r[out as usize] = field_dual(&*self.tape.fields[field as usize], comp, q);
                }
            }
        }
        r[self.tape.outputs[0] as usize]
    }
}

/// Batched gradients in f32: value and the three partials for many points,
/// e.g. the normals of every vertex of a mesh. Each block is computed with
/// the f64 rules and stored as f32.
pub struct GradBatchEval<'t> {
    inner: GradEval<'t>,
}

impl<'t> GradBatchEval<'t> {
    pub fn new(tape: &'t Tape) -> Self {
        GradBatchEval {
            inner: GradEval::new(tape),
        }
    }

    pub fn set_param(&mut self, index: usize, v: f64) {
        self.inner.set_param(index, v);
    }

    /// Fills `out` with value and gradient `[v, dx, dy, dz]` at each point.
    pub fn eval(&mut self, x: &[f32], y: &[f32], z: &[f32], out: &mut [[f32; 4]]) {
        let n = out.len();
        assert!(
            x.len() == n && y.len() == n && z.len() == n,
            "slice lengths differ"
        );
        for start in (0..n).step_by(BLOCK) {
            for i in start..(start + BLOCK).min(n) {
                let (v, g) = self.inner.eval([x[i] as f64, y[i] as f64, z[i] as f64]);
                out[i] = [v as f32, g[0] as f32, g[1] as f32, g[2] as f32];
            }
        }
    }
}
