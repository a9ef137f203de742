//! `microfrep eval`: values (and gradients) at points.

use crate::model;
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep_core::{GradEval, PointEval, Tape};
use std::io::{BufRead, Write};
use std::path::Path;

#[derive(Args)]
pub struct EvalArgs {
    /// Model: a HyperFun file (.hf) or a built-in example name.
    model: String,
    /// Coordinates x y z [x y z ...]; read from stdin (one point per line) if absent.
    #[arg(allow_negative_numbers = true)]
    coords: Vec<f64>,
    /// Also print the gradient (df/dx df/dy df/dz).
    #[arg(long)]
    grad: bool,
    /// HyperFun object to evaluate (default `my_model`, else the first).
    #[arg(long)]
    object: Option<String>,
    /// HyperFun parameter a[K] = V, as K=V (repeatable).
    #[arg(short = 'a', long = "param", value_parser = model::parse_param)]
    params: Vec<(usize, f64)>,
}

/// For a HyperFun file with parse errors: prints all of them with their
/// source lines and carets (the loader reports only the first) and fails.
fn report_parse_errors(path: &str) -> Result<()> {
    let is_hf = path.to_ascii_lowercase().ends_with(".hf") || Path::new(path).is_file();
    let Ok(src) = std::fs::read_to_string(path) else {
        return Ok(()); // the loader reports unreadable files
    };
    if is_hf {
        if let Err(d) = microfrep_hyperfun::parse(&src, path) {
            eprint!("{}", d.render(&src));
            bail!("{path}: {} error(s)", d.errors().count());
        }
    }
    Ok(())
}

pub fn run(a: EvalArgs) -> Result<()> {
    report_parse_errors(&a.model)?;
    let opts = model::Options {
        object: a.object.clone(),
        params: a.params.clone(),
    };
    let m = model::load_with(&a.model, &opts)?;
    // HyperFun models have a second output: the run-time error code.
    let tape = match &m.hf {
        Some(hf) => hf.tape(),
        None => Tape::new(&m.expr),
    };
    let mut pe = PointEval::new(&tape);
    let mut ge = GradEval::new(&tape);
    let stdout = std::io::stdout();
    let mut out = std::io::BufWriter::new(stdout.lock());
    let mut emit = |p: [f64; 3], out: &mut dyn Write| -> Result<()> {
        if let Some(hf) = &m.hf {
            let vals = pe.eval_all(p);
            match hf.result(vals[0], vals[1]) {
                Err(e) => writeln!(out, "error: {} at {}:{}", e.message, e.line, e.col)?,
                Ok(v) if !a.grad => writeln!(out, "{v}")?,
                Ok(_) => {
                    let (v, g) = ge.eval(p);
                    writeln!(out, "{v} {} {} {}", g[0], g[1], g[2])?;
                }
            }
            return Ok(());
        }
        if a.grad {
            let (v, g) = ge.eval(p);
            writeln!(out, "{v} {} {} {}", g[0], g[1], g[2])?;
        } else {
            writeln!(out, "{}", pe.eval(p))?;
        }
        Ok(())
    };
    if !a.coords.is_empty() {
        // `is_multiple_of` needs Rust 1.87; the workspace supports 1.85.
        #[allow(clippy::manual_is_multiple_of)]
        if a.coords.len() % 3 != 0 {
            bail!("coordinates come in threes (x y z); got {}", a.coords.len());
        }
        for c in a.coords.chunks(3) {
            emit([c[0], c[1], c[2]], &mut out)?;
        }
    } else {
        for (i, line) in std::io::stdin().lock().lines().enumerate() {
            let line = line.context("reading stdin")?;
            let t = line.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let v: Vec<f64> = t
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|s| !s.is_empty())
                .map(|s| s.parse::<f64>())
                .collect::<Result<_, _>>()
                .with_context(|| format!("stdin line {}: not a number in '{t}'", i + 1))?;
            if v.len() != 3 {
                bail!(
                    "stdin line {}: expected 3 numbers (x y z), got {}",
                    i + 1,
                    v.len()
                );
            }
            emit([v[0], v[1], v[2]], &mut out)?;
        }
    }
    out.flush()?;
    Ok(())
}
