//! `microfrep check MODEL.hf`: parse and lower a HyperFun file, list its
//! objects and parameters, report every error and warning with
//! `file:line:col`, the source line and a caret. Exits non-zero on an error.

use anyhow::{bail, Context, Result};
use clap::Args;

#[derive(Args)]
pub struct CheckArgs {
    /// HyperFun model file (.hf).
    model: String,
    /// Object to check as the evaluated one (default `my_model`, else the first).
    #[arg(long)]
    object: Option<String>,
}

pub fn run(a: CheckArgs) -> Result<()> {
    microfrep::install_library();
    let src = std::fs::read_to_string(&a.model).with_context(|| format!("reading {}", a.model))?;
    let r = match microfrep::hyperfun::check::check(&src, &a.model, a.object.as_deref()) {
        Ok(r) => r,
        Err(d) => {
            eprint!("{}", d.render(&src));
            bail!("{}: {} error(s)", a.model, d.errors().count());
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
    for m in &r.unlocated {
        eprintln!("{}: error: {m}", a.model);
    }
    if r.errors() > 0 {
        bail!("{}: {} error(s)", a.model, r.errors());
    }
    println!("ok ({} warning(s))", r.diagnostics.items.len());
    Ok(())
}
