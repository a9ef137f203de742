use crate::interval::Interval;
use crate::tape::{Op, Tape};

/// Interval evaluator: bounds of the model over an axis-aligned box.
pub struct IntervalEval {
    tape: Tape,
    params: Vec<Interval>,
    slots: Vec<Interval>,
}

impl IntervalEval {
    /// An evaluator of `tape` with the parameters at their defaults.
    pub fn new(tape: &Tape) -> Self {
        IntervalEval {
            tape: tape.clone(),
            params: tape
                .params()
                .iter()
                .map(|p| Interval::point(p.default))
                .collect(),
            slots: vec![Interval::point(0.0); tape.ops().len()],
        }
    }

    /// Sets parameter `index` to one value.
    pub fn set_param(&mut self, index: usize, v: f64) {
        self.params[index] = Interval::point(v);
    }

    /// Bounds a parameter over a range instead of a single value.
    pub fn set_param_interval(&mut self, index: usize, v: Interval) {
        self.params[index] = v;
    }

    /// Bounds of the first output over the box `[x] x [y] x [z]`.
    pub fn eval(&mut self, x: Interval, y: Interval, z: Interval) -> Interval {
        self.eval_output(0, x, y, z)
    }

    /// Bounds of output `k` over the box.
    pub fn eval_output(&mut self, k: usize, x: Interval, y: Interval, z: Interval) -> Interval {
        self.run([x, y, z]);
        self.slots[self.tape.outputs()[k] as usize]
    }

    /// Bounds of every output, in one pass over the tape.
    pub fn eval_all(&mut self, x: Interval, y: Interval, z: Interval) -> Vec<Interval> {
        self.run([x, y, z]);
        let s = &self.slots;
        self.tape.outputs().iter().map(|&o| s[o as usize]).collect()
    }

    /// The bounds of every value of the tape after the last evaluation
    /// (what per-region simplification reads).
    pub fn values(&self) -> &[Interval] {
        &self.slots
    }

    fn run(&mut self, p: [Interval; 3]) {
        let s = &mut self.slots;
        for (i, op) in self.tape.ops().iter().enumerate() {
            s[i] = match *op {
                Op::Var(a) => p[a as usize],
                Op::Const(c) if c.is_nan() => Interval::only_nan(),
                Op::Const(c) => Interval::point(c),
                Op::Param(k) => self.params[k as usize],
                Op::Unary(op, a) => s[a as usize].unary(op),
                Op::Binary(op, a, b) => s[a as usize].binary(op, s[b as usize]),
                Op::PowI(a, n) => s[a as usize].powi(n),
                Op::Select(c, a, b) => {
                    Interval::select(s[c as usize], s[a as usize], s[b as usize])
                }
                Op::Set { op, a, b, alpha } => {
                    Interval::set(op, s[a as usize], s[b as usize], s[alpha as usize])
                }
                Op::Field { field, comp, args } => {
                    let q = args.map(|a| s[a as usize]);
                    let f = &self.tape.fields()[field as usize];
                    let v = if comp == 0 {
                        f.interval(q)
                    } else {
                        f.grad_interval(q)[comp as usize - 1]
                    };
                    // A NaN coordinate makes the field NaN.
                    v.with_nan(q.iter().any(Interval::may_be_nan))
                }
            };
        }
    }
}
