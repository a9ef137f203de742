//! `microfrep check MODEL.hf`: parse and lower a HyperFun file, list its
//! objects and parameters, report every error and warning with
//! `file:line:col`, the source line and a caret. Takes the model options
//! that `mesh` takes (`--object`, `-a`, `--field`, `--bounds`): fields are
//! built (so a broken mesh or scan is found here) and parameters are
//! checked against the object. Exits non-zero on an error.

use crate::common::{parse_box, with_stages, ModelArgs, RunArgs};
use anyhow::{bail, Context, Result};
use clap::Args;

#[derive(Args)]
pub struct CheckArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// No progress bars and no notes.
    #[arg(long)]
    quiet: bool,
}

pub fn run(a: CheckArgs) -> Result<()> {
    microfrep::install_library();
    let m = &a.model;
    let run = RunArgs {
        quiet: a.quiet,
        json: false,
        threads: None,
    };
    if let Some(b) = &m.bounds {
        parse_box("--bounds", b)?;
    }
    let src = std::fs::read_to_string(&m.model).with_context(|| format!("reading {}", m.model))?;
    let opts = m.load_options();
    let bound = with_stages(&run, |p| microfrep::load::bind_fields(&opts, p));
    let bound = bound?;
    for n in &bound.notes {
        run.note(n);
    }
    let lo = microfrep::hyperfun::LoadOptions {
        object: m.object.clone(),
        params: m.params.clone(),
        fields: bound.fields,
    };
    let r = match microfrep::hyperfun::check::check_with(&src, &m.model, &lo) {
        Ok(r) => r,
        Err(d) => {
            eprint!("{}", d.render(&src));
            bail!("{}: {} error(s)", m.model, d.errors().count());
        }
    };
    for o in &r.objects {
        println!("object {o}");
    }
    if let Some((name, n)) = &r.evaluated {
        println!("evaluated object: {name}");
        let params: Vec<String> = (1..=*n).map(|k| format!("a[{k}]")).collect();
        println!(
            "parameters: {} (default 0; set with -a K=V)",
            params.join(" ")
        );
        if r.per_point {
            println!(
                "note: control flow depends on the point; evaluated per point \
                 (slower, no interval pruning)"
            );
        }
    }
    eprint!("{}", r.diagnostics.render(&src));
    for msg in &r.unlocated {
        eprintln!("{}: error: {msg}", m.model);
    }
    if r.errors() > 0 {
        bail!("{}: {} error(s)", m.model, r.errors());
    }
    println!("ok ({} warning(s))", r.diagnostics.items.len());
    Ok(())
}
