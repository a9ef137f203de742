//! HyperFun: read, check and evaluate HyperFun models on the microfrep core.
//!
//! [`parse`] reads a file into an [`ast::Program`], reporting every error it
//! can recover from ([`Diagnostics`]); [`lower`] turns a program into core
//! expressions; [`printer::to_hyperfun`] writes a core expression back as
//! HyperFun. [`load`] does parsing and lowering in one step and gives a
//! [`Model`], whose value follows the core's convention (inside is
//! `f >= 0`) and whose run-time errors (division by zero, square root of a
//! negative, ...) come back located, as the reference interpreter reports
//! them.
//!
//! ```
//! use microfrep_hyperfun::{load, parse};
//!
//! let src = "my_model(x[3], a[1]) {
//!     r = 1 - x[1]^2 - x[2]^2 - x[3]^2;
//!     my_model = r & x[3];
//! }";
//! let model = load(src, "half_ball.hf", None).unwrap();
//! let v = model.eval_points(&[[0.0, 0.0, 0.5], [0.0, 0.0, -0.5]]);
//! assert!(v[0].as_ref().unwrap() > &0.0); // inside
//! assert!(v[1].as_ref().unwrap() < &0.0); // cut away by x[3] >= 0
//!
//! // Errors carry the file, line and column.
//! let err = parse("my_model(x[3], a[1]) { my_model = ; }", "bad.hf").unwrap_err();
//! assert!(err.has_errors());
//! assert_eq!((err.file.as_str(), err.pos.line), ("bad.hf", 1));
//! ```

#![warn(missing_docs)]

pub mod ast;
pub mod check;
mod diag;
mod lexer;
pub mod library;
pub mod lower;
mod parser;
pub mod printer;

pub use diag::{Diagnostic, Diagnostics, Severity};
pub use lower::Model;
pub use parser::{hf_round, FunctionTable, ParamKind};

/// Parsing choices.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Accept CR as whitespace (with one warning). The reference rejects it
    /// ("Unknown lexem"), which breaks CRLF files.
    pub accept_cr: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { accept_cr: true }
    }
}

/// Parses a HyperFun file with the standard function table; CR is accepted.
pub fn parse(src: &str, file: &str) -> Result<ast::Program, Diagnostics> {
    parse_with(src, file, Options::default()).map(|(p, _)| p)
}

/// Parses with the standard function table; on success also returns the
/// warnings.
pub fn parse_with(
    src: &str,
    file: &str,
    options: Options,
) -> Result<(ast::Program, Diagnostics), Diagnostics> {
    parse_with_registry(src, file, options, &library::Registry::standard())
}

/// Parameters of a built-in (SPEC section 7) or library function.
fn standard_signature(registry: &library::Registry, name: &str) -> Option<Vec<ParamKind>> {
    if let Some(&(_, n)) = lower::ops::BUILTINS.iter().find(|(b, _)| *b == name) {
        return Some(vec![ParamKind::Real; n]);
    }
    let f = registry.get(name)?;
    let kind = |k: &library::Kind| match k {
        library::Kind::A => ParamKind::Array,
        library::Kind::R => ParamKind::Real,
    };
    Some(f.kinds.iter().map(kind).collect())
}

/// Parses with the functions of `registry` (the standard library plus any
/// bound data fields) and the built-ins as the function table.
pub fn parse_with_registry(
    src: &str,
    file: &str,
    options: Options,
    registry: &library::Registry,
) -> Result<(ast::Program, Diagnostics), Diagnostics> {
    let table = |name: &str| standard_signature(registry, name);
    parse_with_table(src, file, options, &table)
}

/// Parses with a caller-supplied function table (which names are functions
/// and their parameter kinds).
pub fn parse_with_table(
    src: &str,
    file: &str,
    options: Options,
    functions: FunctionTable,
) -> Result<(ast::Program, Diagnostics), Diagnostics> {
    let mut diags = Vec::new();
    let toks = lexer::lex(src, options.accept_cr, &mut diags);
    let mut p = parser::Parser::new(toks, functions, diags);
    let program = p.program();
    let diags = Diagnostics::new(file, p.diags);
    if diags.has_errors() {
        Err(diags)
    } else {
        Ok((program, diags))
    }
}

/// Parses and lowers object `object` (default `my_model`, else the first).
pub fn load(src: &str, file: &str, object: Option<&str>) -> Result<Model, Diagnostics> {
    load_with_params(src, file, object, &[])
}

/// What to load from a HyperFun file besides the source.
#[derive(Clone, Default)]
pub struct LoadOptions {
    /// Object to evaluate (default `my_model`, else the first).
    pub object: Option<String>,
    /// `a[k] = value` as `(k, value)` pairs, 1-based.
    pub params: Vec<(usize, f64)>,
    /// Data fields bound as functions `NAME(x[3])` (see
    /// [`library::Registry::register_field`]).
    pub fields: Vec<(String, std::sync::Arc<dyn microfrep_core::Field>)>,
}

/// Parses and lowers with [`LoadOptions`]: the object, its parameters and
/// the data fields the model may call by name.
pub fn load_with_options(src: &str, file: &str, opts: &LoadOptions) -> Result<Model, Diagnostics> {
    let mut registry = library::Registry::standard();
    for (name, f) in &opts.fields {
        registry.register_field(name, f.clone());
    }
    let (program, _) = parse_with_registry(src, file, Options::default(), &registry)?;
    let program = std::sync::Arc::new(program);
    lower::load_program_with(program, opts.object.as_deref(), &opts.params, &registry).map_err(
        |e| {
            let d = Diagnostic {
                severity: Severity::Error,
                pos: e.pos,
                message: e.message,
            };
            Diagnostics::new(file, vec![d])
        },
    )
}

/// As [`load`], with parameters `a[k] = value` given as `(k, value)` pairs
/// (1-based, checked against the object's `a[N]`; see
/// [`lower::load_program`]).
pub fn load_with_params(
    src: &str,
    file: &str,
    object: Option<&str>,
    params: &[(usize, f64)],
) -> Result<Model, Diagnostics> {
    let program = std::sync::Arc::new(parse(src, file)?);
    lower::load_program(program, object, params).map_err(|e| {
        let d = Diagnostic {
            severity: Severity::Error,
            pos: e.pos,
            message: e.message,
        };
        Diagnostics::new(file, vec![d])
    })
}
