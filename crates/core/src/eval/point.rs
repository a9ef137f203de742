use crate::field::Field;
use crate::tape::{Op, Tape};

/// Reference evaluator: one point at a time in f64.
pub struct PointEval {
    tape: Tape,
    params: Vec<f64>,
    slots: Vec<f64>,
}

impl PointEval {
    /// An evaluator of `tape` with the parameters at their defaults.
    pub fn new(tape: &Tape) -> Self {
        PointEval {
            tape: tape.clone(),
            params: tape.params().iter().map(|p| p.default).collect(),
            slots: vec![0.0; tape.ops().len()],
        }
    }

    /// Sets parameter `index` (see [`Tape::param_index`]).
    pub fn set_param(&mut self, index: usize, v: f64) {
        self.params[index] = v;
    }

    /// Value of the first output at `p`.
    pub fn eval(&mut self, p: [f64; 3]) -> f64 {
        self.run(p);
        self.slots[self.tape.outputs()[0] as usize]
    }

    /// Value of output `k` at `p`.
    pub fn eval_output(&mut self, k: usize, p: [f64; 3]) -> f64 {
        self.run(p);
        self.slots[self.tape.outputs()[k] as usize]
    }

    /// Values of all outputs at `p`.
    pub fn eval_all(&mut self, p: [f64; 3]) -> Vec<f64> {
        self.run(p);
        self.tape
            .outputs()
            .iter()
            .map(|&r| self.slots[r as usize])
            .collect()
    }

    /// Every value of the tape after the last evaluation.
    pub fn values(&self) -> &[f64] {
        &self.slots
    }

    fn run(&mut self, p: [f64; 3]) {
        let s = &mut self.slots;
        for (i, op) in self.tape.ops().iter().enumerate() {
            s[i] = match *op {
                Op::Var(a) => p[a as usize],
                Op::Const(c) => c,
                Op::Param(k) => self.params[k as usize],
                Op::Unary(op, a) => op.apply(s[a as usize]),
                Op::Binary(op, a, b) => op.apply(s[a as usize], s[b as usize]),
                Op::PowI(a, n) => s[a as usize].powi(n),
                Op::Select(c, a, b) => {
                    if s[c as usize] != 0.0 {
                        s[a as usize]
                    } else {
                        s[b as usize]
                    }
                }
                Op::Set { op, a, b, alpha } => {
                    op.apply(s[a as usize], s[b as usize], s[alpha as usize])
                }
                Op::Field { field, comp, args } => {
                    let q = args.map(|a| s[a as usize]);
                    field_component(&*self.tape.fields()[field as usize], comp, q)
                }
            };
        }
    }
}

pub(crate) fn field_component(f: &dyn Field, comp: u8, q: [f64; 3]) -> f64 {
    if comp == 0 {
        f.eval(q)
    } else {
        f.grad(q).1[comp as usize - 1]
    }
}
