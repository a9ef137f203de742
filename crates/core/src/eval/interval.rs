use crate::interval::Interval;
use crate::tape::{Instr, Tape, REG_X, REG_Y, REG_Z};

/// Interval evaluator: bounds of the model over an axis-aligned box.
pub struct IntervalEval<'t> {
    tape: &'t Tape,
    regs: Vec<Interval>,
}

impl<'t> IntervalEval<'t> {
    pub fn new(tape: &'t Tape) -> Self {
        let mut regs = vec![Interval::point(0.0); tape.nregs];
        for (r, v) in tape.preload() {
            regs[r as usize] = Interval::point(v);
        }
        IntervalEval { tape, regs }
    }

    pub fn set_param(&mut self, index: usize, v: f64) {
        self.regs[self.tape.params[index].0 as usize] = Interval::point(v);
    }

    /// Bounds a parameter over a range instead of a single value.
    pub fn set_param_interval(&mut self, index: usize, v: Interval) {
        self.regs[self.tape.params[index].0 as usize] = v;
    }

    /// Bounds of the first output over the box `[x] x [y] x [z]`.
    pub fn eval(&mut self, x: Interval, y: Interval, z: Interval) -> Interval {
        self.eval_output(0, x, y, z)
    }

    pub fn eval_output(&mut self, k: usize, x: Interval, y: Interval, z: Interval) -> Interval {
        self.run(x, y, z);
        self.regs[self.tape.outputs[k] as usize]
    }

    /// Bounds of every output, in one pass over the tape.
    pub fn eval_all(&mut self, x: Interval, y: Interval, z: Interval) -> Vec<Interval> {
        self.run(x, y, z);
        let r = &self.regs;
        self.tape.outputs.iter().map(|&o| r[o as usize]).collect()
    }

    fn run(&mut self, x: Interval, y: Interval, z: Interval) {
        let r = &mut self.regs;
        r[REG_X as usize] = x;
        r[REG_Y as usize] = y;
        r[REG_Z as usize] = z;
        for ins in &self.tape.instrs {
            match *ins {
                Instr::Unary { op, out, a } => r[out as usize] = r[a as usize].unary(op),
                Instr::Binary { op, out, a, b } => {
                    r[out as usize] = r[a as usize].binary(op, r[b as usize])
                }
                Instr::PowI { out, a, n } => r[out as usize] = r[a as usize].powi(n),
                Instr::Select { out, c, a, b } => {
                    r[out as usize] = Interval::select(r[c as usize], r[a as usize], r[b as usize])
                }
                Instr::Field {
                    out,
                    field,
                    comp,
                    args,
                } => {
                    let q = args.map(|a| r[a as usize]);
                    let f = &self.tape.fields[field as usize];
                    let v = if comp == 0 {
                        f.interval(q)
                    } else {
                        f.grad_interval(q)[comp as usize - 1]
                    };
                    // A NaN coordinate makes the field NaN.
                    r[out as usize] = v.with_nan(q.iter().any(Interval::may_be_nan));
                }
            }
        }
    }
}
