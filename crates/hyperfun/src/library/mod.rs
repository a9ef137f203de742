//! The HyperFun library registry: every callable `hf*` function by name, with
//! its argument kinds and a builder that produces core expressions.
//!
//! Builders work on symbolic values, so the same code serves the lowered
//! graph and (with constant arguments, which fold) the per-point fallback.
//! Adding a function is one `register` call; the parser asks the registry
//! which names are functions and what they take.

mod attr_arrays;
mod attr_patterns;
mod attrs;
mod blends;
mod conv;
mod conv_arc;
mod dellipsoid;
mod extend;
mod prims;
mod sardef;
pub mod shapes;
mod transforms;

pub use extend::{add_extension, extensions, Extension};
use microfrep_core::Expr;
use std::collections::HashMap;

/// `EPS` of the reference interpreter.
pub const EPS: f64 = 1e-6;
/// Value most primitives return for a point array whose length is not 3.
pub const SENTINEL: f64 = -1111111111111.0;

/// Kind of one parameter: an array name passed by reference or a real value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// An array name, passed by reference (the function may overwrite it).
    A,
    /// A real value (any expression).
    R,
}

/// One evaluated argument.
#[derive(Clone, Debug)]
pub enum Arg {
    /// A real argument's value.
    Real(Expr),
    /// An array argument's elements.
    Array(Vec<Expr>),
}

impl Arg {
    /// The real value (an array argument reads as NaN; the registry's kinds
    /// make that unreachable for well-formed calls).
    pub fn real(&self) -> Expr {
        match self {
            Arg::Real(e) => e.clone(),
            Arg::Array(_) => Expr::constant(f64::NAN),
        }
    }
    /// The elements of an array argument (empty for a real one).
    pub fn array(&self) -> &[Expr] {
        match self {
            Arg::Array(v) => v,
            Arg::Real(_) => &[],
        }
    }
}

/// Element `i` (0-based) of an array argument. The C code reads past short
/// arrays; here such a read is NaN, never a panic.
pub fn el(a: &[Expr], i: usize) -> Expr {
    a.get(i).cloned().unwrap_or(Expr::constant(f64::NAN))
}

/// What a call produces: its value and the arrays it overwrote
/// (argument position, new contents).
pub struct Output {
    /// The value of the call.
    pub value: Expr,
    /// Arrays the call overwrote, as (argument position from 0, new
    /// elements).
    pub writes: Vec<(usize, Vec<Expr>)>,
    /// The builder needed a constant where it got a point-dependent value
    /// (e.g. a term count); the model must take the per-point fallback.
    pub needs_constants: bool,
    /// A static error in the arguments (e.g. an unknown kind code); the
    /// model fails to load with this message at the call's position.
    pub error: Option<String>,
}

impl Output {
    /// A call that yields `value` and writes no array.
    pub fn value(value: Expr) -> Output {
        Output {
            value,
            writes: Vec::new(),
            needs_constants: false,
            error: None,
        }
    }
    /// A call that yields `value` and overwrites the arrays in `writes`.
    pub fn writes(value: Expr, writes: Vec<(usize, Vec<Expr>)>) -> Output {
        Output {
            value,
            writes,
            needs_constants: false,
            error: None,
        }
    }
    /// A call that needs constant arguments it did not get, so the model
    /// must take the per-point fallback.
    pub fn needs_constants() -> Output {
        Output {
            value: Expr::constant(f64::NAN),
            writes: Vec::new(),
            needs_constants: true,
            error: None,
        }
    }
    /// A call whose (constant) arguments are invalid.
    pub fn error(message: impl Into<String>) -> Output {
        Output {
            value: Expr::constant(f64::NAN),
            writes: Vec::new(),
            needs_constants: false,
            error: Some(message.into()),
        }
    }
}

/// Builds the call from arguments already checked against `kinds`.
pub type Builder = std::sync::Arc<dyn Fn(&[Arg]) -> Output + Send + Sync>;

/// One library function.
#[derive(Clone)]
pub struct LibFn {
    /// Lower-case name.
    pub name: &'static str,
    /// The kind of each parameter.
    pub kinds: &'static [Kind],
    /// Builds a call's value from its arguments.
    pub build: Builder,
}

impl std::fmt::Debug for LibFn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("LibFn")
            .field("name", &self.name)
            .field("kinds", &self.kinds)
            .finish()
    }
}

/// A name made `'static` once per distinct spelling (names of bound
/// fields come at run time; there are few of them).
fn intern(name: &str) -> &'static str {
    static NAMES: std::sync::Mutex<Vec<&'static str>> = std::sync::Mutex::new(Vec::new());
    let mut v = NAMES.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(n) = v.iter().find(|n| **n == name) {
        return n;
    }
    let n: &'static str = Box::leak(name.to_string().into_boxed_str());
    v.push(n);
    n
}

/// Name (lower case) to library function.
#[derive(Clone, Debug)]
pub struct Registry {
    map: HashMap<&'static str, LibFn>,
}

impl Registry {
    /// An empty registry.
    pub fn empty() -> Registry {
        Registry {
            map: HashMap::new(),
        }
    }

    /// The library of the reference interpreter plus the installed
    /// extensions ([`add_extension`]).
    pub fn standard() -> Registry {
        let mut r = Registry::reference();
        extend::apply(&mut r);
        r
    }

    /// The library of the reference interpreter only.
    pub fn reference() -> Registry {
        let mut r = Registry::empty();
        prims::register(&mut r);
        transforms::register(&mut r);
        blends::register(&mut r);
        sardef::register(&mut r);
        conv::register(&mut r);
        conv_arc::register(&mut r);
        attrs::register(&mut r);
        attr_arrays::register(&mut r);
        attr_patterns::register(&mut r);
        r
    }

    /// Adds (or replaces) a function. `name` must be lower case.
    pub fn register(
        &mut self,
        name: &'static str,
        kinds: &'static [Kind],
        build: impl Fn(&[Arg]) -> Output + Send + Sync + 'static,
    ) {
        let build: Builder = std::sync::Arc::new(build);
        self.map.insert(name, LibFn { name, kinds, build });
    }

    /// Binds a data field as the function `name(x[3])` (case-insensitive),
    /// which returns the field's value at `x`: how `--field NAME=FILE`
    /// brings a mesh, a scan or measured data into a model.
    pub fn register_field(&mut self, name: &str, field: std::sync::Arc<dyn microfrep_core::Field>) {
        let name = intern(&name.to_ascii_lowercase());
        self.register(name, &[Kind::A], move |a: &[Arg]| {
            let p = a[0].array();
            if p.len() != 3 {
                return Output::error(format!(
                    "{name}: argument 1 ('x') has {} elements; it must have 3 elements",
                    p.len()
                ));
            }
            Output::value(Expr::field_at(
                field.clone(),
                [p[0].clone(), p[1].clone(), p[2].clone()],
            ))
        });
    }

    /// Looks a name up, case-insensitively.
    pub fn get(&self, name: &str) -> Option<&LibFn> {
        self.map.get(name.to_ascii_lowercase().as_str())
    }

    /// All names, sorted.
    pub fn names(&self) -> Vec<&'static str> {
        let mut v: Vec<_> = self.map.keys().copied().collect();
        v.sort_unstable();
        v
    }
}

/// `R0&(u, v) = u + v - sqrt(u^2 + v^2)`.
pub fn r0_and(u: &Expr, v: &Expr) -> Expr {
    Expr::set(microfrep_core::SetOp::Intersection, u, v, 0.0)
}

/// `R0|(u, v) = u + v + sqrt(u^2 + v^2)`.
pub fn r0_or(u: &Expr, v: &Expr) -> Expr {
    Expr::set(microfrep_core::SetOp::Union, u, v, 0.0)
}

/// `v` unless the point array has the wrong length (then the sentinel).
pub fn point3(args: &[Arg], f: impl FnOnce(&[Expr]) -> Expr) -> Expr {
    let p = args[0].array();
    if p.len() != 3 {
        return Expr::constant(SENTINEL);
    }
    f(p)
}

/// `1` when `|v| < EPS`, else `0`.
pub fn tiny(v: &Expr) -> Expr {
    v.abs().lt(EPS)
}

#[cfg(test)]
mod tests;
