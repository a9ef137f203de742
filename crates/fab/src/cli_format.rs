//! Common Layer Interface (CLI), ASCII form: the layer format of laser
//! sintering and melting machines. All layers in one file; each closed
//! polyline repeats its first point at the end; direction 1 is an outer
//! boundary (counter-clockwise), 0 a hole (clockwise). `$$LAYER` holds the
//! top height of the layer, as the machines expect; the contours themselves
//! are taken at the layer's middle.

use crate::contour::{signed_area, Polygon};
use crate::error::{FabError, Result};
use std::fmt::Write;

/// Units are model units, declared as millimetres (`$$UNITS/1`).
pub fn header(min: [f64; 3], max: [f64; 3], layers: usize) -> String {
    format!(
        "$$HEADERSTART\n$$ASCII\n$$UNITS/1\n$$VERSION/200\n$$LABEL/1,microfrep\n\
         $$DIMENSION/{},{},{},{},{},{}\n$$LAYERS/{layers}\n$$HEADEREND\n$$GEOMETRYSTART\n",
        min[0], min[1], min[2], max[0], max[1], max[2]
    )
}

/// Closes the geometry section opened by [`header`]; the last text of a
/// CLI file, after every [`layer_block`].
pub const FOOTER: &str = "$$GEOMETRYEND\n";

/// One layer's block: `$$LAYER/z` and a `$$POLYLINE` per loop.
pub fn layer_block(z: f64, polys: &[Polygon]) -> String {
    let mut s = format!("$$LAYER/{z}\n");
    for p in polys {
        let dir = if signed_area(p) > 0.0 { 1 } else { 0 };
        let _ = write!(s, "$$POLYLINE/1,{dir},{}", p.len() + 1);
        for v in p.iter().chain(p.first()) {
            let _ = write!(s, ",{},{}", v[0], v[1]);
        }
        s.push('\n');
    }
    s
}

/// A polyline as read back: label id, direction, points (closed ones end
/// with their first point).
#[derive(Clone, Debug, PartialEq)]
pub struct Polyline {
    /// Label (part) id the polyline belongs to; the writer uses 1 throughout.
    pub id: u32,
    /// Direction: 1 an outer boundary (counter-clockwise), 0 a hole
    /// (clockwise), 2 an open polyline; other values are rejected on reading.
    pub dir: u8,
    /// Points `[x, y]` in file units (multiply by [`CliFile::units`] for
    /// millimetres), as many as the `$$POLYLINE` line declares.
    pub points: Vec<[f64; 2]>,
}

/// One `$$LAYER` block as read back: its height and its polylines in file
/// order.
#[derive(Clone, Debug, PartialEq)]
pub struct CliLayer {
    /// The `$$LAYER` height in file units: the top of the layer (contours were
    /// taken at its middle).
    pub z: f64,
    /// The layer's polylines (may be empty for a layer without material).
    pub polylines: Vec<Polyline>,
}

/// An ASCII CLI file as read back by [`read_cli`].
#[derive(Clone, Debug, PartialEq)]
pub struct CliFile {
    /// The `$$UNITS` value: millimetres per file unit (1 for files this crate
    /// writes). Coordinates are kept in file units, not scaled.
    pub units: f64,
    /// The layers in file order, as many as `$$LAYERS` declared.
    pub layers: Vec<CliLayer>,
}

/// Parses an ASCII CLI file; errors name the line.
pub fn read_cli(text: &str) -> Result<CliFile> {
    let mut units = None;
    let mut declared = None;
    let mut layers: Vec<CliLayer> = Vec::new();
    let (mut in_header, mut in_geometry, mut ended) = (false, false, false);
    for (n, raw) in text.lines().enumerate() {
        let line = n + 1;
        let err = |msg: String| FabError::Parse { line, msg };
        let l = raw.trim();
        if l.is_empty() {
            continue;
        }
        let (cmd, arg) = l.split_once('/').unwrap_or((l, ""));
        let num = |t: &str| -> Result<f64> {
            t.trim()
                .parse::<f64>()
                .map_err(|_| err(format!("'{t}' is not a number")))
        };
        match cmd {
            "$$HEADERSTART" => in_header = true,
            "$$HEADEREND" => in_header = false,
            "$$UNITS" if in_header => units = Some(num(arg)?),
            "$$LAYERS" if in_header => declared = Some(num(arg)? as usize),
            _ if in_header => {} // other header fields are informative
            "$$GEOMETRYSTART" => in_geometry = true,
            "$$GEOMETRYEND" => {
                in_geometry = false;
                ended = true;
            }
            "$$LAYER" if in_geometry => layers.push(CliLayer {
                z: num(arg)?,
                polylines: Vec::new(),
            }),
            "$$POLYLINE" if in_geometry => {
                let f: Vec<&str> = arg.split(',').collect();
                if f.len() < 3 {
                    return Err(err("POLYLINE needs id, dir, n".into()));
                }
                let id = num(f[0])? as u32;
                let dir = num(f[1])?;
                if ![0.0, 1.0, 2.0].contains(&dir) {
                    return Err(err(format!("direction {dir} is not 0, 1 or 2")));
                }
                let count = num(f[2])? as usize;
                if f.len() != 3 + 2 * count {
                    return Err(err(format!(
                        "POLYLINE declares {count} points but has {} coordinates",
                        f.len() - 3
                    )));
                }
                let mut points = Vec::with_capacity(count);
                for c in f[3..].chunks(2) {
                    points.push([num(c[0])?, num(c[1])?]);
                }
                let layer = layers
                    .last_mut()
                    .ok_or_else(|| err("POLYLINE before any LAYER".into()))?;
                layer.polylines.push(Polyline {
                    id,
                    dir: dir as u8,
                    points,
                });
            }
            _ => return Err(err(format!("unexpected '{l}'"))),
        }
    }
    let units = units.ok_or(FabError::Parse {
        line: 0,
        msg: "no $$UNITS in the header".into(),
    })?;
    if !ended {
        return Err(FabError::Parse {
            line: text.lines().count(),
            msg: "no $$GEOMETRYEND: file incomplete".into(),
        });
    }
    if let Some(d) = declared {
        if d != layers.len() {
            return Err(FabError::Parse {
                line: 0,
                msg: format!("header declares {d} layers, file has {}", layers.len()),
            });
        }
    }
    Ok(CliFile { units, layers })
}
