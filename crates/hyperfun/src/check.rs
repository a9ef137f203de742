//! `check`: a whole HyperFun file reviewed for its author: every object
//! lowered on its own (so errors anywhere are found), the evaluated object
//! and its parameters, and warnings where a model relies on a quirk of the
//! reference interpreter.

use crate::ast::Pos;
use crate::library::Registry;
use crate::lower::{self, calls_of};
use crate::{Diagnostic, Diagnostics, Severity};
use std::sync::Arc;

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

/// What [`check`] found.
#[derive(Clone, Debug)]
pub struct CheckReport {
    /// One line per object: `name(x[3], a[N], s[M])`.
    pub objects: Vec<String>,
    /// The object that would be evaluated, and its `a[]` size.
    pub evaluated: Option<(String, usize)>,
    /// Whether the evaluated object needs the per-point interpreter.
    pub per_point: bool,
    /// Why, and where (the loop or call that depends on the point).
    pub per_point_reason: Option<lower::PerPoint>,
    /// Errors and warnings with positions.
    pub diagnostics: Diagnostics,
    /// Errors without a position (e.g. no such object).
    pub unlocated: Vec<String>,
    /// The evaluated object lowered with the parameters and fields, when
    /// it lowers (errors of other objects do not stop it).
    pub model: Option<lower::Model>,
}

impl CheckReport {
    /// Errors found (with and without positions).
    pub fn errors(&self) -> usize {
        self.diagnostics.errors().count() + self.unlocated.len()
    }
}

/// Parses and lowers every object of `src`; `Err` holds parse errors.
pub fn check(src: &str, file: &str, object: Option<&str>) -> Result<CheckReport, Diagnostics> {
    let opts = crate::LoadOptions {
        object: object.map(str::to_string),
        ..Default::default()
    };
    check_with(src, file, &opts)
}

/// [`check`] with what a load would be given: the object, its parameters
/// (checked against the object's `a[N]`) and the data fields the model
/// calls by name.
pub fn check_with(
    src: &str,
    file: &str,
    opts: &crate::LoadOptions,
) -> Result<CheckReport, Diagnostics> {
    let mut registry = Registry::standard();
    for (name, f) in &opts.fields {
        registry.register_field(name, f.clone());
    }
    let (program, warnings) =
        crate::parse_with_registry(src, file, crate::Options::default(), &registry)?;
    let program = Arc::new(program);
    let mut items = warnings.items;
    let mut unlocated = Vec::new();
    let mut objects = Vec::new();
    let object = opts.object.as_deref();
    let mut report = |items: &mut Vec<Diagnostic>, name: &str, e: lower::LowerError| {
        if e.pos.line == 0 {
            unlocated.push(format!("object '{name}': {}", e.message));
        } else {
            items.push(diag(Severity::Error, e.pos, e.message));
        }
    };
    for (i, o) in program.objects.iter().enumerate() {
        objects.push(format!(
            "{}(x[{}], a[{}], s[{}])",
            o.name, o.x_size, o.a_size, o.s_size
        ));
        match lower::lower(program.clone(), i, &registry, &[]) {
            Err(e) => report(&mut items, &o.name, e),
            Ok(m) => {
                for e in m.certain_errors {
                    let message = format!("{} (whenever this runs, for every point)", e.message);
                    report(&mut items, &o.name, lower::LowerError { message, ..e });
                }
            }
        }
    }
    let mut evaluated = None;
    let mut per_point = false;
    let mut per_point_reason = None;
    let mut model = None;
    match lower::select_object(&program, object) {
        Some(i) => {
            let o = &program.objects[i];
            evaluated = Some((o.name.clone(), o.a_size));
            match lower::load_program_with(program.clone(), object, &opts.params, &registry) {
                Ok(m) => {
                    per_point = !m.lowered;
                    per_point_reason = m.per_point.clone();
                    model = Some(m);
                }
                // Parameter errors (the object's own errors are above).
                Err(e) if e.pos.line == 0 => report(&mut items, &o.name, e),
                Err(_) => {}
            }
        }
        None => unlocated.push(match object {
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
    Ok(CheckReport {
        objects,
        evaluated,
        per_point,
        per_point_reason,
        diagnostics: Diagnostics {
            file: file.to_string(),
            items,
            ..Default::default()
        },
        unlocated,
        model,
    })
}
