//! Loading a model named on the command line: a HyperFun file (`.hf`) or a
//! built-in example.

use anyhow::{anyhow, bail, Context, Result};
use microfrep_core::Expr;
use microfrep_structures::examples;
use std::path::Path;
use std::sync::Arc;

/// A loaded model.
pub struct Model {
    pub expr: Expr,
    /// The compiled model every consumer takes.
    pub shape: microfrep_core::Shape,
    /// For HyperFun models: the lowered model with its error output.
    pub hf: Option<microfrep_hyperfun::lower::Model>,
}

/// How to load a HyperFun model.
#[derive(Default)]
pub struct Options {
    /// Object to evaluate (default `my_model`, else the first).
    pub object: Option<String>,
    /// `a[k] = v` pairs (1-based k).
    pub params: Vec<(usize, f64)>,
}

/// Resolves a model argument with default options.
pub fn load(spec: &str) -> Result<Model> {
    load_with(spec, &Options::default())
}

/// Resolves a model argument: a `.hf` file, or the name of a built-in example.
pub fn load_with(spec: &str, opts: &Options) -> Result<Model> {
    if spec.to_ascii_lowercase().ends_with(".hf") || Path::new(spec).is_file() {
        return load_hf(spec, opts);
    }
    if let Some(ex) = examples::by_name(spec) {
        if opts.object.is_some() || !opts.params.is_empty() {
            bail!("--object and --param apply to HyperFun (.hf) models only");
        }
        let expr = (ex.build)();
        let (lo, hi) = ex.bounds;
        return Ok(Model {
            shape: microfrep_core::Shape::new(expr.clone())
                .with_bounds(microfrep_core::Bounds::new(lo, hi)),
            expr,
            hf: None,
        });
    }
    let names: Vec<&str> = examples::all().iter().map(|e| e.name).collect();
    bail!(
        "unknown model '{spec}': not a .hf file or a built-in example (known: {})",
        names.join(", ")
    )
}

fn load_hf(path: &str, opts: &Options) -> Result<Model> {
    // The mf* microstructure functions join the HyperFun library.
    microfrep_structures_hf::install();
    let src = std::fs::read_to_string(path).with_context(|| format!("reading {path}"))?;
    let program = microfrep_hyperfun::parse(&src, path).map_err(|d| anyhow!("{d}"))?;
    // Indices are checked against the object's a[N] before anything is sized.
    let m = microfrep_hyperfun::lower::load_program(
        Arc::new(program),
        opts.object.as_deref(),
        &opts.params,
    )
    .map_err(|e| match e.pos.line {
        0 => anyhow!("{path}: {}", e.message),
        _ => anyhow!("{path}:{e}"),
    })?;
    Ok(Model {
        expr: m.value.clone(),
        shape: m.shape(),
        hf: Some(m),
    })
}

/// Parses `K=V` (as given to `-a`/`--param`).
pub fn parse_param(s: &str) -> Result<(usize, f64), String> {
    let (k, v) = s
        .split_once('=')
        .ok_or_else(|| format!("expected K=V (e.g. 1=0.5), got '{s}'"))?;
    let k = k
        .trim()
        .parse()
        .map_err(|_| format!("bad parameter index '{k}'"))?;
    let v = v
        .trim()
        .parse()
        .map_err(|_| format!("bad parameter value '{v}'"))?;
    Ok((k, v))
}

pub fn list_examples(only: Option<&str>) -> Result<()> {
    let all = examples::all();
    if let Some(n) = only {
        if !all.iter().any(|e| e.name == n) {
            bail!("no example named '{n}'");
        }
    }
    for e in all.iter().filter(|e| only.is_none_or(|n| n == e.name)) {
        let (lo, hi) = e.bounds;
        println!(
            "{:<14} bounds {:?}..{:?}\n    {}",
            e.name, lo, hi, e.description
        );
    }
    Ok(())
}
