//! Compilation of a graph into a tape: straight-line code over registers.
//!
//! Registers 0..3 hold x, y, z. Constants and parameters get their own
//! registers, filled once per evaluator; temporaries reuse registers as soon
//! as their last reader has run, which keeps the batch evaluator's working
//! set (one block of lanes per register) small enough for the L1/L2 cache.

use crate::expr::{Axis, Expr};
use crate::field::Field;
use crate::graph::{Graph, Node, NodeId, ParamInfo};
use crate::ops::{BinaryOp, UnaryOp};
use std::sync::Arc;

pub type Reg = u32;

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Instr {
    Unary {
        op: UnaryOp,
        out: Reg,
        a: Reg,
    },
    Binary {
        op: BinaryOp,
        out: Reg,
        a: Reg,
        b: Reg,
    },
    PowI {
        out: Reg,
        a: Reg,
        n: i32,
    },
    Select {
        out: Reg,
        c: Reg,
        a: Reg,
        b: Reg,
    },
    Field {
        out: Reg,
        field: u32,
        comp: u8,
        args: [Reg; 3],
    },
}

impl Instr {
    pub fn out(&self) -> Reg {
        match *self {
            Instr::Unary { out, .. }
            | Instr::Binary { out, .. }
            | Instr::PowI { out, .. }
            | Instr::Select { out, .. }
            | Instr::Field { out, .. } => out,
        }
    }
}

/// A compiled model. Immutable and shareable between threads; each thread
/// makes its own evaluator from it.
#[derive(Clone, Debug)]
pub struct Tape {
    pub(crate) instrs: Vec<Instr>,
    pub(crate) nregs: usize,
    /// Registers preloaded with constants.
    pub(crate) consts: Vec<(Reg, f64)>,
    /// Registers preloaded with parameter values (defaults unless overridden).
    pub(crate) params: Vec<(Reg, ParamInfo)>,
    pub(crate) fields: Vec<Arc<dyn Field>>,
    pub(crate) outputs: Vec<Reg>,
}

pub const REG_X: Reg = 0;
pub const REG_Y: Reg = 1;
pub const REG_Z: Reg = 2;

impl Tape {
    /// Compiles one expression.
    pub fn new(e: &Expr) -> Tape {
        let mut g = Graph::new();
        let root = g.add(e);
        Tape::from_graph(&g, &[root])
    }

    /// Compiles several outputs that share one register file (e.g. a value
    /// and an error flag).
    pub fn with_outputs(es: &[Expr]) -> Tape {
        let mut g = Graph::new();
        let roots: Vec<NodeId> = es.iter().map(|e| g.add(e)).collect();
        Tape::from_graph(&g, &roots)
    }

    pub fn from_graph(g: &Graph, roots: &[NodeId]) -> Tape {
        let n = g.len();
        // Reachability from the roots (ids are topologically ordered).
        let mut live = vec![false; n];
        for r in roots {
            live[r.0 as usize] = true;
        }
        for i in (0..n).rev() {
            if live[i] {
                for c in children(&g.nodes()[i]) {
                    live[c.0 as usize] = true;
                }
            }
        }
        // Last reader of each node; roots live to the end.
        let mut last_use = vec![0usize; n];
        for (i, node) in g.nodes().iter().enumerate() {
            if live[i] {
                for c in children(node) {
                    last_use[c.0 as usize] = i;
                }
            }
        }
        for r in roots {
            last_use[r.0 as usize] = usize::MAX;
        }

        let mut reg_of: Vec<Reg> = vec![Reg::MAX; n];
        let mut nregs: usize = 3;
        let mut consts = Vec::new();
        let mut params = Vec::new();
        // Pinned registers: coordinates, constants, parameters.
        for i in 0..n {
            if !live[i] {
                continue;
            }
            match g.nodes()[i] {
                Node::Var(a) => {
                    reg_of[i] = match a {
                        Axis::X => REG_X,
                        Axis::Y => REG_Y,
                        Axis::Z => REG_Z,
                    }
                }
                Node::Const(bits) => {
                    reg_of[i] = nregs as Reg;
                    consts.push((nregs as Reg, f64::from_bits(bits)));
                    nregs += 1;
                }
                Node::Param(p) => {
                    reg_of[i] = nregs as Reg;
                    params.push((nregs as Reg, g.params()[p as usize].clone()));
                    nregs += 1;
                }
                _ => {}
            }
        }
        let pinned_end = nregs;
        let mut free: Vec<Reg> = Vec::new();
        // Which temporaries die at instruction i.
        let mut dying: Vec<Vec<usize>> = vec![Vec::new(); n];
        for i in 0..n {
            if live[i] && last_use[i] != usize::MAX && is_computed(&g.nodes()[i]) {
                dying[last_use[i]].push(i);
            }
        }
        let mut instrs = Vec::new();
        let mut field_map: Vec<Option<u32>> = vec![None; g.fields().len()];
        let mut fields: Vec<Arc<dyn Field>> = Vec::new();
        for i in 0..n {
            if !live[i] || !is_computed(&g.nodes()[i]) {
                continue;
            }
            let out = match free.pop() {
                Some(r) => r,
                None => {
                    nregs += 1;
                    (nregs - 1) as Reg
                }
            };
            reg_of[i] = out;
            let r = |id: NodeId| reg_of[id.0 as usize];
            instrs.push(match g.nodes()[i] {
                Node::Unary(op, a) => Instr::Unary { op, out, a: r(a) },
                Node::Binary(op, a, b) => Instr::Binary {
                    op,
                    out,
                    a: r(a),
                    b: r(b),
                },
                Node::PowI(a, n) => Instr::PowI { out, a: r(a), n },
                Node::Select(c, a, b) => Instr::Select {
                    out,
                    c: r(c),
                    a: r(a),
                    b: r(b),
                },
                Node::Field { field, comp, args } => {
                    let fi = *field_map[field as usize].get_or_insert_with(|| {
                        fields.push(g.fields()[field as usize].clone());
                        (fields.len() - 1) as u32
                    });
                    Instr::Field {
                        out,
                        field: fi,
                        comp,
                        args: [r(args[0]), r(args[1]), r(args[2])],
                    }
                }
                _ => unreachable!("pinned nodes are not computed"),
            });
            // Operands whose last reader is this instruction free their
            // registers only now, so an output never aliases an input.
            for &d in &dying[i] {
                if reg_of[d] as usize >= pinned_end {
                    free.push(reg_of[d]);
                }
            }
        }
        let outputs = roots.iter().map(|r| reg_of[r.0 as usize]).collect();
        Tape {
            instrs,
            nregs,
            consts,
            params,
            fields,
            outputs,
        }
    }

    pub fn instrs(&self) -> &[Instr] {
        &self.instrs
    }
    pub fn reg_count(&self) -> usize {
        self.nregs
    }
    pub fn outputs(&self) -> &[Reg] {
        &self.outputs
    }
    pub fn fields(&self) -> &[Arc<dyn Field>] {
        &self.fields
    }
    /// Parameters in register order.
    pub fn params(&self) -> impl Iterator<Item = &ParamInfo> {
        self.params.iter().map(|(_, p)| p)
    }
    /// Index of a parameter by name, for `set_param` on evaluators.
    pub fn param_index(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|(_, p)| p.name == name)
    }

    /// Initial register values (constants and parameter defaults) in f64.
    pub(crate) fn preload(&self) -> impl Iterator<Item = (Reg, f64)> + '_ {
        self.consts
            .iter()
            .cloned()
            .chain(self.params.iter().map(|(r, p)| (*r, p.default)))
    }

    /// A stable textual listing, for debugging and for tape equality checks.
    pub fn listing(&self) -> String {
        use std::fmt::Write;
        let mut s = String::new();
        for (r, c) in &self.consts {
            let _ = writeln!(s, "r{r} = const {c:e} ({:016x})", c.to_bits());
        }
        for (r, p) in &self.params {
            let _ = writeln!(s, "r{r} = param {} = {}", p.name, p.default);
        }
        for i in &self.instrs {
            let _ = match *i {
                Instr::Unary { op, out, a } => writeln!(s, "r{out} = {} r{a}", op.name()),
                Instr::Binary { op, out, a, b } => {
                    writeln!(s, "r{out} = {} r{a} r{b}", op.name())
                }
                Instr::PowI { out, a, n } => writeln!(s, "r{out} = powi r{a} {n}"),
                Instr::Select { out, c, a, b } => {
                    writeln!(s, "r{out} = select r{c} r{a} r{b}")
                }
                Instr::Field {
                    out,
                    field,
                    comp,
                    args,
                } => writeln!(
                    s,
                    "r{out} = field{field}.{comp} r{} r{} r{}",
                    args[0], args[1], args[2]
                ),
            };
        }
        let _ = writeln!(s, "out {:?}", self.outputs);
        s
    }
}

fn is_computed(n: &Node) -> bool {
    !matches!(n, Node::Var(_) | Node::Const(_) | Node::Param(_))
}

fn children(n: &Node) -> Vec<NodeId> {
    match *n {
        Node::Var(_) | Node::Const(_) | Node::Param(_) => vec![],
        Node::Unary(_, a) | Node::PowI(a, _) => vec![a],
        Node::Binary(_, a, b) => vec![a, b],
        Node::Select(c, a, b) => vec![c, a, b],
        Node::Field { args, .. } => args.to_vec(),
    }
}
