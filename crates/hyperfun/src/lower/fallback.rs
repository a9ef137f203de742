//! Per-point evaluation for models whose control flow depends on the point
//! in a way lowering cannot express: a `while` loop whose trip count varies
//! from point to point, a library call whose constant argument is computed
//! from the point. (Point-dependent `if`s are lowered with `select`.) It
//! runs the same symbolic executor with constant coordinates, so
//! everything folds to numbers and the semantics are those of the lowered
//! path. Each output (value, error code, attribute `s[k]`) is a core
//! `Field`, so the model plugs into every evaluation mode; intervals are
//! the whole line.

use super::errors::{ErrorTable, RuntimeError};
use super::exec::{Exec, Inputs, Stop, POINT_LOOP_BUDGET};
use crate::ast::Program;
use crate::library::Registry;
use microfrep_core::{Expr, Field, Interval};
use std::cell::RefCell;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, OnceLock};

/// Everything needed to evaluate one object at a point.
pub struct Interp {
    /// Distinguishes interpreters in the per-thread cache of results.
    id: u64,
    pub program: Arc<Program>,
    pub object: usize,
    pub registry: Registry,
    pub table: ErrorTable,
    pub params: Vec<f64>,
    /// Attribute channels: `s[1..=attributes]`.
    pub attributes: usize,
    /// Error code of the first loop that ran out of iterations at some
    /// point: from then on every point reports it at once instead of
    /// spending the whole budget again (a loop that never ends would cost
    /// that on every sample of a mesh).
    pub runaway: OnceLock<f64>,
}

impl std::fmt::Debug for Interp {
    /// Short: the program can be megabytes (and deep).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let name = &self.program.objects[self.object].name;
        write!(f, "Interp({name}, params {:?})", self.params)
    }
}

/// One evaluation: value, error code, then the attributes.
type Sample = Arc<[f64]>;

/// A cached sample: interpreter id, point bits, sample.
type Entry = Option<(u64, [u64; 3], Sample)>;

/// Slots of the per-thread cache: a batch evaluator asks for every output
/// of a block of 256 points one output after the other.
const CACHE: usize = 1024;

thread_local! {
    /// Recent samples by (interpreter, point): the outputs of one model are
    /// separate fields, and each would otherwise run the program again.
    static RECENT: RefCell<Vec<Entry>> =
        RefCell::new(vec![None; CACHE]);
}

fn slot_of(id: u64, bits: [u64; 3]) -> usize {
    let mut h = id.wrapping_mul(0x9e37_79b9_7f4a_7c15);
    for b in bits {
        h = (h ^ b).wrapping_mul(0x0100_0000_01b3);
        h ^= h >> 29;
    }
    (h as usize) % CACHE
}

impl Interp {
    /// An interpreter for `object` of `program` with parameters `a[]`,
    /// adding the error sites it meets to `table`.
    pub fn new(
        program: Arc<Program>,
        object: usize,
        registry: Registry,
        table: ErrorTable,
        params: Vec<f64>,
        attributes: usize,
    ) -> Interp {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        Interp {
            id: NEXT.fetch_add(1, Ordering::Relaxed),
            program,
            object,
            registry,
            table,
            params,
            attributes,
            runaway: OnceLock::new(),
        }
    }

    /// Value, error code and attributes at a point, from the cache when
    /// this thread evaluated the point recently.
    pub fn sample(&self, p: [f64; 3]) -> Sample {
        let bits = p.map(f64::to_bits);
        let k = slot_of(self.id, bits);
        let hit = RECENT.with(|c| match &c.borrow()[k] {
            Some((id, b, s)) if *id == self.id && *b == bits => Some(s.clone()),
            _ => None,
        });
        if let Some(s) = hit {
            return s;
        }
        let s: Sample = self.eval_all(p).into();
        RECENT.with(|c| c.borrow_mut()[k] = Some((self.id, bits, s.clone())));
        s
    }

    /// Runs the program at `p`: value, error code, attributes. Where an
    /// error is raised the value and the attributes are NaN.
    fn eval_all(&self, p: [f64; 3]) -> Vec<f64> {
        let mut out = vec![f64::NAN; 2 + self.attributes];
        if let Some(&code) = self.runaway.get() {
            out[1] = code;
            return out;
        }
        let obj = &self.program.objects[self.object];
        let mut ex = Exec::with_budget(
            &self.program,
            &self.registry,
            &self.table,
            POINT_LOOP_BUDGET,
        );
        let inputs = Inputs {
            x: p.iter().map(|&v| Expr::constant(v)).collect(),
            a: self.params.iter().map(|&v| Expr::constant(v)).collect(),
        };
        let run = ex.run(obj, inputs);
        if ex.limit_hit {
            if let Some(code) = ex.err.as_const() {
                let _ = self.runaway.set(code);
            }
        }
        match run {
            Ok(o) => {
                let code = ex.err.as_const().unwrap_or(f64::NAN);
                out[1] = code;
                // As in the lowered graph: no value where an error is raised.
                if code == 0.0 {
                    out[0] = o.value.as_const().unwrap_or(f64::NAN);
                    for (k, s) in o.s.iter().take(self.attributes).enumerate() {
                        out[2 + k] = s.as_const().unwrap_or(f64::NAN);
                    }
                }
            }
            // A call whose constant arguments are only known at this point
            // (e.g. a term count computed in a loop) can be invalid here:
            // a run-time error at the call, like any other.
            Err(Stop::Static(message, pos)) => {
                out[1] = self.table.code(RuntimeError {
                    message,
                    line: pos.line,
                    col: pos.col,
                });
            }
            // With constant inputs every condition is constant.
            Err(Stop::NeedsPoint(_)) => {}
        }
        out
    }
}

/// Which output of the interpreter a field exposes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Channel {
    /// The value (NaN where an error is raised).
    Value,
    /// The error code (0 = none).
    Error,
    /// Attribute `s[k + 1]` (NaN where an error is raised).
    Attribute(usize),
}

/// One output of the interpreter as a field.
#[derive(Debug)]
pub struct Output {
    interp: Arc<Interp>,
    channel: Channel,
    name: String,
}

impl Output {
    /// The field for `channel` of `interp`.
    pub fn new(interp: Arc<Interp>, channel: Channel) -> Output {
        let name = match channel {
            Channel::Value => "hyperfun".to_string(),
            Channel::Error => "hyperfun-error".to_string(),
            Channel::Attribute(k) => format!("hyperfun-s{}", k + 1),
        };
        Output {
            interp,
            channel,
            name,
        }
    }

    /// The field as an expression.
    pub fn expr(interp: &Arc<Interp>, channel: Channel) -> Expr {
        Expr::field(Arc::new(Output::new(interp.clone(), channel)))
    }

    fn pick(&self, p: [f64; 3]) -> f64 {
        let s = self.interp.sample(p);
        match self.channel {
            Channel::Value => s[0],
            Channel::Error => s[1],
            Channel::Attribute(k) => s.get(2 + k).copied().unwrap_or(f64::NAN),
        }
    }
}

/// Step of the central differences that give the fallback's gradient.
const H: f64 = 1e-6;

impl Field for Output {
    fn name(&self) -> &str {
        &self.name
    }
    fn eval(&self, p: [f64; 3]) -> f64 {
        self.pick(p)
    }
    fn grad(&self, p: [f64; 3]) -> (f64, [f64; 3]) {
        let v = self.pick(p);
        let mut g = [0.0; 3];
        for (k, gk) in g.iter_mut().enumerate() {
            let (mut lo, mut hi) = (p, p);
            lo[k] -= H;
            hi[k] += H;
            *gk = (self.pick(hi) - self.pick(lo)) / (2.0 * H);
        }
        (v, g)
    }
    /// Nothing is known: any value, and NaN where an error is raised
    /// (the error code itself is never NaN).
    fn interval(&self, _b: [Interval; 3]) -> Interval {
        Interval::ENTIRE.with_nan(self.channel != Channel::Error)
    }
}
