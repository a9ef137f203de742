use crate::field::Field;
use crate::tape::{Instr, Tape, REG_X, REG_Y, REG_Z};

/// Reference evaluator: one point at a time in f64.
pub struct PointEval<'t> {
    tape: &'t Tape,
    regs: Vec<f64>,
}

impl<'t> PointEval<'t> {
    pub fn new(tape: &'t Tape) -> Self {
        let mut regs = vec![0.0; tape.nregs];
        for (r, v) in tape.preload() {
            regs[r as usize] = v;
        }
        PointEval { tape, regs }
    }

    /// Sets parameter `index` (see [`Tape::param_index`]).
    pub fn set_param(&mut self, index: usize, v: f64) {
        self.regs[self.tape.params[index].0 as usize] = v;
    }

    /// Value of the first output at `p`.
    pub fn eval(&mut self, p: [f64; 3]) -> f64 {
        self.run(p);
        self.regs[self.tape.outputs[0] as usize]
    }

    /// Values of all outputs at `p`.
    pub fn eval_all(&mut self, p: [f64; 3]) -> Vec<f64> {
        self.run(p);
        self.tape
            .outputs
            .iter()
            .map(|&r| self.regs[r as usize])
            .collect()
    }

    fn run(&mut self, p: [f64; 3]) {
        let r = &mut self.regs;
        r[REG_X as usize] = p[0];
        r[REG_Y as usize] = p[1];
        r[REG_Z as usize] = p[2];
        for ins in &self.tape.instrs {
            match *ins {
                Instr::Unary { op, out, a } => r[out as usize] = op.apply(r[a as usize]),
                Instr::Binary { op, out, a, b } => {
                    r[out as usize] = op.apply(r[a as usize], r[b as usize])
                }
                Instr::PowI { out, a, n } => r[out as usize] = r[a as usize].powi(n),
                Instr::Select { out, c, a, b } => {
                    r[out as usize] = if r[c as usize] != 0.0 {
                        r[a as usize]
                    } else {
                        r[b as usize]
                    }
                }
                Instr::Field {
                    out,
                    field,
                    comp,
                    args,
                } => {
                    let q = args.map(|a| r[a as usize]);
                    let f = &self.tape.fields[field as usize];
                    r[out as usize] = field_component(&**f, comp, q);
                }
            }
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
