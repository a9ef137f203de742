//! `POST /api/fill`: the facade's fill ([`microfrep::fill::fill`], the one
//! the CLI and Python call) of a part, answered as HyperFun source for the
//! editor with the report measured on what was built. The part is the
//! session's current model or a mesh, scan or model file under the
//! working directory; a data part comes back bound by a `--field
//! part=PATH` comment, so the page edits to the answer as to any model.

use crate::error::StudioError;
use crate::paths;
use crate::session::Snapshot;
use microfrep::fill::{fill, Density, FillOptions, MeasureOptions, Part, Structure};
use microfrep::{Bounds, LoadOptions};
use serde_json::{json, Value};
use std::path::Path;

/// Where the part comes from.
#[derive(Debug)]
pub(crate) enum PartSpec {
    /// The session's model at the request's `gen`.
    Current,
    /// A file under the working directory (relative, `/`-separated).
    File(String),
}

/// A fill request from the page.
#[derive(Debug)]
pub(crate) struct Request {
    /// The part.
    pub part: PartSpec,
    /// The fill's options.
    pub options: FillOptions,
}

/// How the facade's option names are spelled in the request's JSON.
fn json_key(name: &str) -> String {
    format!("'{}'", name.replace('-', "_"))
}

fn bad(msg: impl Into<String>) -> StudioError {
    StudioError::Request(msg.into())
}

fn number(v: &Value, key: &str) -> Result<Option<f64>, StudioError> {
    match v.get(key) {
        None | Some(Value::Null) => Ok(None),
        Some(x) => x
            .as_f64()
            .filter(|x| x.is_finite())
            .map(Some)
            .ok_or_else(|| bad(format!("'{key}' must be a finite number"))),
    }
}

/// Parses the request body: `part` (`"current"` or a path), `structure`,
/// `sheet`, `cell`, one of `density`, `density_grade` (`[surface, inner,
/// depth]` or an object with those keys) and `density_expr`, `shell`,
/// `seed`.
pub(crate) fn parse(v: &Value) -> Result<Request, StudioError> {
    let part = match v.get("part").and_then(Value::as_str) {
        None => {
            return Err(bad(
                "missing 'part': \"current\" or a file under the working directory",
            ))
        }
        Some("current") => PartSpec::Current,
        Some(p) if p.is_empty() => return Err(bad("'part' is empty")),
        Some(p) => PartSpec::File(p.to_string()),
    };
    let name = v
        .get("structure")
        .and_then(Value::as_str)
        .ok_or_else(|| bad("missing 'structure' (a string)"))?;
    let sheet = match v.get("sheet") {
        None | Some(Value::Null) => false,
        Some(Value::Bool(b)) => *b,
        Some(_) => return Err(bad("'sheet' must be true or false")),
    };
    let structure = Structure::parse(name, sheet).ok_or_else(|| {
        bad(format!(
            "unknown structure '{name}': {}",
            microfrep::fill::with_option_names(Structure::NAMES, &json_key)
        ))
    })?;
    if sheet && !matches!(structure, Structure::Tpms { .. }) {
        return Err(bad("'sheet' applies to TPMS structures only"));
    }
    let cell = number(v, "cell")?.ok_or_else(|| bad("missing 'cell' (mm)"))?;
    let grade = match v.get("density_grade") {
        None | Some(Value::Null) => None,
        Some(g) => {
            let get = |k: &str, i: usize| {
                g.get(k)
                    .or_else(|| g.get(i))
                    .and_then(Value::as_f64)
                    .filter(|x| x.is_finite())
            };
            match (get("surface", 0), get("inner", 1), get("depth", 2)) {
                (Some(s), Some(i), Some(d)) => Some(Density::Graded {
                    at_surface: s,
                    at_depth: i,
                    depth: d,
                }),
                _ => {
                    return Err(bad(
                        "'density_grade' takes [surface, inner, depth] or an object with \
                         those keys, all numbers",
                    ))
                }
            }
        }
    };
    let expr = match v.get("density_expr") {
        None | Some(Value::Null) => None,
        Some(Value::String(s)) => Some(Density::Expression(s.clone())),
        Some(_) => return Err(bad("'density_expr' must be a string")),
    };
    let constant = number(v, "density")?.map(Density::Constant);
    let density = match (constant, grade, expr) {
        (Some(d), None, None) | (None, Some(d), None) | (None, None, Some(d)) => d,
        (None, None, None) => {
            return Err(bad(
                "give one of 'density', 'density_grade' or 'density_expr'",
            ))
        }
        _ => {
            return Err(bad(
                "give only one of 'density', 'density_grade' and 'density_expr'",
            ))
        }
    };
    let seed = match v.get("seed") {
        None | Some(Value::Null) => 1,
        Some(s) => s
            .as_u64()
            .filter(|&s| s <= 1 << 53)
            .ok_or_else(|| bad("'seed' must be a whole number from 0 to 2^53"))?,
    };
    Ok(Request {
        part,
        options: FillOptions {
            structure,
            cell,
            density,
            skin: number(v, "shell")?,
            seed,
            pores: microfrep::fill::PoreControls {
                irregularity: number(v, "irregularity")?,
                parent_scale: number(v, "parent_scale")?,
                tmesh: match v.get("subdivision").and_then(Value::as_str) {
                    None | Some("octree") => false,
                    Some("tmesh") => true,
                    Some(o) => {
                        return Err(bad(format!("'subdivision' '{o}' is 'octree' or 'tmesh'")))
                    }
                },
                opening: number(v, "opening")?,
                hand_t: match v.get("pore_t") {
                    None | Some(Value::Null) => None,
                    Some(Value::Array(t))
                        if t.len() == 24
                            && t.iter().all(|x| x.as_f64().is_some_and(f64::is_finite)) =>
                    {
                        let t: Vec<f64> = t.iter().filter_map(Value::as_f64).collect();
                        Some(std::array::from_fn(|s| {
                            std::array::from_fn(|k| t[3 * s + k])
                        }))
                    }
                    Some(_) => return Err(bad("'pore_t' takes 24 numbers in [0, 1]")),
                },
            },
            // Attribute channels, which the HyperFun answer cannot carry.
            material_layers: Vec::new(),
        },
    })
}

/// Runs the fill and its measurement. `snap` is the session's snapshot
/// for [`PartSpec::Current`]; `check` is called as the work goes on (it
/// unwinds when the job is stopped). The answer: `source` (the filled
/// model), `file` (a name for it), `fields` (the data bindings it needs)
/// and `report` (the keys of `microfrep fill --json`).
pub(crate) fn run(
    root: &Path,
    req: &Request,
    snap: Option<&Snapshot>,
    memory_limit: f64,
    check: &(dyn Fn() + Sync),
) -> Result<Value, StudioError> {
    let progress = |_: &str, _: u64, _: u64| check();
    let engine = |e: microfrep::fill::FillError| bad(e.message_with(&json_key));
    let (part, stem) = match &req.part {
        PartSpec::Current => {
            let snap = snap.ok_or_else(|| bad("'part': \"current\" needs the session's 'gen'"))?;
            // The box the studio works in (the edit's, or the one it
            // proved), so the cells line up with what the page shows.
            let b = Bounds::new(snap.bounds[0], snap.bounds[1]);
            let part = Part::from_shape(snap.shape.clone(), Some(b)).map_err(engine)?;
            (part, stem(&snap.file))
        }
        PartSpec::File(p) => {
            let c = paths::existing(root, p)?;
            let opts = LoadOptions {
                memory_limit: Some(memory_limit as u64),
                ..LoadOptions::default()
            };
            let spec = c.full.to_string_lossy().into_owned();
            let mut part = Part::load(&spec, &opts, None, &progress).map_err(engine)?;
            // The binding the answer carries is relative to the working
            // directory, as the page's fields are.
            if part.source.is_some() {
                part.source = Some(c.relative.clone());
            }
            (part, stem(&c.relative))
        }
    };
    let f = fill(&part, &req.options, &progress).map_err(engine)?;
    let r = f
        .measure(&MeasureOptions::default(), &progress)
        .map_err(engine)?;
    let source = f.hyperfun().map_err(engine)?;
    let fields: serde_json::Map<String, Value> = f
        .binding()
        .into_iter()
        .map(|(n, s)| (n, Value::String(s)))
        .collect();
    Ok(json!({
        "source": source,
        "file": format!("{stem}-filled.hf"),
        "fields": fields,
        "report": r.to_json_with(&f, &json_key),
    }))
}

/// The file name without folders and extension.
fn stem(path: &str) -> String {
    let base = path.rsplit('/').next().unwrap_or(path);
    let base = base.split(':').next().unwrap_or(base);
    let s = base.rsplit_once('.').map_or(base, |(s, _)| s);
    if s.is_empty() {
        "part".into()
    } else {
        s.to_string()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn requests_are_parsed_and_refused_with_their_keys() {
        let r = parse(
            &json!({"part": "parts/femur.stl", "structure": "gyroid", "cell": 12,
            "density": 0.3, "shell": 2}),
        )
        .unwrap();
        assert!(matches!(r.part, PartSpec::File(ref p) if p == "parts/femur.stl"));
        assert_eq!(r.options.cell, 12.0);
        assert_eq!(r.options.skin, Some(2.0));
        assert!(matches!(r.options.density, Density::Constant(d) if d == 0.3));
        let g = parse(&json!({"part": "current", "structure": "octet", "cell": 5,
            "density_grade": {"surface": 0.4, "inner": 0.2, "depth": 3}}))
        .unwrap();
        assert!(matches!(
            g.options.density,
            Density::Graded { at_surface, at_depth, depth } if at_surface == 0.4 && at_depth == 0.2 && depth == 3.0
        ));
        for (body, says) in [
            (
                json!({"structure": "gyroid", "cell": 1, "density": 0.3}),
                "missing 'part'",
            ),
            (
                json!({"part": "current", "structure": "nope", "cell": 1, "density": 0.3}),
                "unknown structure 'nope'",
            ),
            (
                json!({"part": "current", "structure": "octet", "sheet": true, "cell": 1, "density": 0.3}),
                "TPMS structures only",
            ),
            (
                json!({"part": "current", "structure": "gyroid", "density": 0.3}),
                "missing 'cell'",
            ),
            (
                json!({"part": "current", "structure": "gyroid", "cell": 1}),
                "give one of",
            ),
            (
                json!({"part": "current", "structure": "gyroid", "cell": 1, "density": 0.3, "density_expr": "0.2"}),
                "only one of",
            ),
            (
                json!({"part": "current", "structure": "gyroid", "cell": 1, "density_grade": [0.1, 0.2]}),
                "'density_grade' takes",
            ),
            (
                json!({"part": "current", "structure": "gyroid", "cell": 1, "density": 0.3, "seed": -1}),
                "'seed'",
            ),
        ] {
            let e = parse(&body).unwrap_err().to_string();
            assert!(e.contains(says), "{body}: {e}");
        }
        assert_eq!(stem("parts/femur.stl:weld=0.01"), "femur");
        assert_eq!(stem("a/b/model.hf"), "model");
    }
}
