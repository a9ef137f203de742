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
}

impl CheckReport {
    /// Errors found (with and without positions).
    pub fn errors(&self) -> usize {
        self.diagnostics.errors().count() + self.unlocated.len()
    }
}

/// Parses and lowers every object of `src`; `Err` holds parse errors.
pub fn check(src: &str, file: &str, object: Option<&str>) -> Result<CheckReport, Diagnostics> {
    let (program, warnings) = crate::parse_with(src, file, crate::Options::default())?;
    let program = Arc::new(program);
    let mut items = warnings.items;
    let registry = Registry::standard();
    let mut unlocated = Vec::new();
    let mut objects = Vec::new();
    for (i, o) in program.objects.iter().enumerate() {
        objects.push(format!(
            "{}(x[{}], a[{}], s[{}])",
            o.name, o.x_size, o.a_size, o.s_size
        ));
        if let Err(e) = lower::lower(program.clone(), i, &registry, &[]) {
            if e.pos.line == 0 {
                unlocated.push(format!("object '{}': {}", o.name, e.message));
            } else {
                items.push(diag(Severity::Error, e.pos, e.message));
            }
        }
    }
    let mut evaluated = None;
    let mut per_point = false;
    let mut per_point_reason = None;
    match lower::select_object(&program, object) {
        Some(i) => {
            let o = &program.objects[i];
            evaluated = Some((o.name.clone(), o.a_size));
            if let Ok(m) = lower::lower(program.clone(), i, &registry, &[]) {
                per_point = !m.lowered;
                per_point_reason = m.per_point;
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
    })
}
