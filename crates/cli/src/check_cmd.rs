//! `microfrep check MODEL.hf`: parse and lower a HyperFun file, list its
//! objects and parameters, report errors and warnings. Exits non-zero on an
//! error.

use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep_hyperfun::lower::{self, calls_of};
use std::sync::Arc;

#[derive(Args)]
pub struct CheckArgs {
    /// HyperFun model file (.hf).
    model: String,
    /// Object to check as the evaluated one (default `my_model`, else the first).
    #[arg(long)]
    object: Option<String>,
}

/// `file:line:col: message`, the source line and a caret under the column.
fn located(file: &str, src: &str, line: u32, col: u32, what: &str, msg: &str) -> String {
    let text = src
        .lines()
        .nth(line.saturating_sub(1) as usize)
        .unwrap_or("");
    let pad = " ".repeat(col.saturating_sub(1) as usize);
    format!("{file}:{line}:{col}: {what}: {msg}\n  {text}\n  {pad}^")
}

pub fn run(a: CheckArgs) -> Result<()> {
    let src = std::fs::read_to_string(&a.model).with_context(|| format!("reading {}", a.model))?;
    let options = microfrep_hyperfun::Options::default();
    let program = match microfrep_hyperfun::parse_with(&src, &a.model, options) {
        Ok((p, warnings)) => {
            eprint!("{}", warnings.render(&src));
            Arc::new(p)
        }
        Err(d) => {
            eprint!("{}", d.render(&src));
            bail!("{}: {} error(s)", a.model, d.errors().count());
        }
    };
    for o in &program.objects {
        println!(
            "object {}(x[{}], a[{}], s[{}])",
            o.name, o.x_size, o.a_size, o.s_size
        );
    }
    let m = match lower::load_program(program.clone(), a.object.as_deref(), &[]) {
        Ok(m) => m,
        Err(e) => {
            let (l, c) = (e.pos.line, e.pos.col);
            eprintln!("{}", located(&a.model, &src, l, c, "error", &e.message));
            bail!("{}: check failed", a.model);
        }
    };
    println!("evaluated object: {}", m.object);
    let names: Vec<&str> = m.params.iter().map(|(n, _)| n.as_str()).collect();
    println!("parameters: {}", names.join(" "));
    if !m.lowered {
        println!(
            "note: control flow depends on the point; evaluated per point (no interval pruning)"
        );
    }
    for p in calls_of(&program, "sign") {
        let msg = "sign() always returns 1 in HyperFun (reference interpreter bug, kept for compatibility)";
        eprintln!("{}", located(&a.model, &src, p.line, p.col, "warning", msg));
    }
    println!("ok");
    Ok(())
}
