//! Loading a model named on the command line.

use anyhow::{bail, Result};
use microfrep_core::Expr;
use microfrep_structures::examples;

/// A loaded model.
pub struct Model {
    pub expr: Expr,
}

/// Resolves a model argument: the name of a built-in example.
pub fn load(spec: &str) -> Result<Model> {
    if let Some(ex) = examples::by_name(spec) {
        return Ok(Model { expr: (ex.build)() });
    }
    let names: Vec<&str> = examples::all().iter().map(|e| e.name).collect();
    bail!(
        "unknown model '{spec}': not a built-in example (known: {})",
        names.join(", ")
    )
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
