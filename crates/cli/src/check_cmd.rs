//! `microfrep check MODEL.hf`: parse and lower a HyperFun file, list its
//! objects and parameters, report every error and warning with
//! `file:line:col`, the source line and a caret. Exits non-zero on an error.

use anyhow::{bail, Context, Result};
use clap::Args;
use microfrep_hyperfun::library::Registry;
use microfrep_hyperfun::lower::{self, calls_of};
use microfrep_hyperfun::{ast::Pos, Diagnostic, Diagnostics, Severity};
use std::sync::Arc;

#[derive(Args)]
pub struct CheckArgs {
    /// HyperFun model file (.hf).
    model: String,
    /// Object to check as the evaluated one (default `my_model`, else the first).
    #[arg(long)]
    object: Option<String>,
}

/// Calls whose result in the reference interpreter is a bug or not
/// portable, with the warning `check` gives for each.
const SUSPECT_CALLS: &[(&str, &str)] = &[
    (
        "sign",
        "sign() always returns 1 in HyperFun (a bug of the reference interpreter, kept for \
         compatibility); use x/abs(x) for the real sign",
    ),
    (
        "hfa_cerp",
        "hfA_Cerp is linear interpolation in HyperFun (the reference maps it to hfA_Lerp's code)",
    ),
    (
        "hfr",
        "hfR calls back into R in the R package; here (as in the reference data) it returns 0",
    ),
    (
        "hfa_noisep",
        "hfA_NoiseP: the reference seeds its noise tables from the clock; values here are \
         deterministic and differ from any run of the reference",
    ),
    (
        "hfa_turbulence",
        "hfA_Turbulence: the reference seeds its noise tables from the clock; values here are \
         deterministic and differ from any run of the reference",
    ),
];

fn diag(severity: Severity, pos: Pos, message: impl Into<String>) -> Diagnostic {
    Diagnostic {
        severity,
        pos,
        message: message.into(),
    }
}

pub fn run(a: CheckArgs) -> Result<()> {
    let src = std::fs::read_to_string(&a.model).with_context(|| format!("reading {}", a.model))?;
    let options = microfrep_hyperfun::Options::default();
    let (program, mut items) = match microfrep_hyperfun::parse_with(&src, &a.model, options) {
        Ok((p, warnings)) => (Arc::new(p), warnings.items),
        Err(d) => {
            eprint!("{}", d.render(&src));
            bail!("{}: {} error(s)", a.model, d.errors().count());
        }
    };

    // Every object is lowered on its own, so errors in objects other than
    // the evaluated one are found too.
    let registry = Registry::standard();
    let mut unlocated = Vec::new();
    for (i, o) in program.objects.iter().enumerate() {
        println!(
            "object {}(x[{}], a[{}], s[{}])",
            o.name, o.x_size, o.a_size, o.s_size
        );
        if let Err(e) = lower::lower(program.clone(), i, &registry, &[]) {
            if e.pos.line == 0 {
                unlocated.push(format!("object '{}': {}", o.name, e.message));
            } else {
                items.push(diag(Severity::Error, e.pos, e.message));
            }
        }
    }
    let chosen = lower::select_object(&program, a.object.as_deref());
    match chosen {
        Some(i) => {
            let o = &program.objects[i];
            println!("evaluated object: {}", o.name);
            let params: Vec<String> = (1..=o.a_size).map(|k| format!("a[{k}]")).collect();
            println!(
                "parameters: {} (default 0; set with -a K=V)",
                params.join(" ")
            );
            if let Ok(m) = lower::lower(program.clone(), i, &registry, &[]) {
                if !m.lowered {
                    println!(
                        "note: control flow depends on the point; evaluated per point \
                         (slower, no interval pruning)"
                    );
                }
            }
        }
        None => unlocated.push(match &a.object {
            Some(n) => format!("no object named '{n}'"),
            None => "the file defines no object".into(),
        }),
    }
    for (name, msg) in SUSPECT_CALLS {
        for p in calls_of(&program, name) {
            items.push(diag(Severity::Warning, p, *msg));
        }
    }
    items.sort_by_key(|d| d.pos);
    items.dedup();
    let report = Diagnostics {
        file: a.model.clone(),
        items,
        ..Default::default()
    };
    eprint!("{}", report.render(&src));
    for m in &unlocated {
        eprintln!("{}: error: {m}", a.model);
    }
    let errors = report.errors().count() + unlocated.len();
    if errors > 0 {
        bail!("{}: {errors} error(s)", a.model);
    }
    let warnings = report.items.len();
    println!("ok ({warnings} warning(s))");
    Ok(())
}
