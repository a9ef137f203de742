//! `microfrep eval`: values (and gradients, attributes) at points.

use crate::common::{load_model, ModelArgs, RunArgs};
use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep::io::text::exact;
use std::io::{BufRead, Write};

#[derive(Args)]
pub struct EvalArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Coordinates x y z [x y z ...]; read from stdin (one point per line) if absent.
    #[arg(allow_negative_numbers = true, num_args = 0..)]
    coords: Vec<String>,
    /// Also print the gradient (df/dx df/dy df/dz).
    #[arg(long)]
    grad: bool,
    /// Also print the attributes s[1] ... s[n].
    #[arg(long)]
    attributes: bool,
    #[command(flatten)]
    run: RunArgs,
}

fn parse(t: &str, at: &str) -> Result<f64> {
    t.parse::<f64>()
        .with_context(|| format!("{at}: '{t}' is not a number"))
}

pub fn run(a: EvalArgs) -> Result<()> {
    a.run.init()?;
    let m = load_model(&a.model, &a.run)?;
    let s = &m.shape;
    let mut pe = microfrep::core::PointEval::new(s.outputs());
    let mut ge = s.grad();
    let n_attr = s.attributes().len();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let (mut points, mut failed) = (0u64, 0u64);
    let mut emit = |p: [f64; 3], out: &mut dyn Write| -> Result<()> {
        points += 1;
        let vals = pe.eval_all(p);
        let code = s.error_output().map_or(0.0, |k| vals[k]);
        if let Some(e) = s.runtime_error(code) {
            failed += 1;
            writeln!(out, "error: {e}")?;
            return Ok(());
        }
        let mut line = exact(vals[0]);
        if a.grad {
            let (_, g) = ge.eval(p);
            for c in g {
                line += &format!(" {}", exact(c));
            }
        }
        if a.attributes {
            for k in 0..n_attr {
                line += &format!(" {}", exact(vals[s.attribute_output(k)]));
            }
        }
        writeln!(out, "{line}")?;
        Ok(())
    };
    if !a.coords.is_empty() {
        if a.coords.len() % 3 != 0 {
            bail!("coordinates come in threes (x y z); got {}", a.coords.len());
        }
        for c in a.coords.chunks(3) {
            let v: Vec<f64> = c
                .iter()
                .map(|t| parse(t, "coordinate"))
                .collect::<Result<_>>()?;
            emit([v[0], v[1], v[2]], &mut out)?;
        }
    } else {
        for (i, line) in std::io::stdin().lock().lines().enumerate() {
            let line = line.context("reading stdin")?;
            let t = line.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let at = format!("stdin line {}", i + 1);
            let v: Vec<f64> = t
                .split(|c: char| c.is_whitespace() || c == ',')
                .filter(|s| !s.is_empty())
                .map(|s| parse(s, &at))
                .collect::<Result<_>>()?;
            if v.len() != 3 {
                bail!("{at}: expected 3 numbers (x y z), got {}", v.len());
            }
            emit([v[0], v[1], v[2]], &mut out)?;
        }
    }
    out.flush()?;
    if let Some(e) = m.hyperfun.as_ref().and_then(|h| h.runaway_loop()) {
        bail!("the model does not terminate: {e}");
    }
    if points > 0 && failed == points {
        bail!("every point raised a run-time error");
    }
    Ok(())
}
