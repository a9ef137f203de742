//! The `.raw` + `.json` pair that `microfrep voxels -o x.raw` writes:
//! samples x fastest, then y, then z; the sidecar gives `dims`, `spacing`,
//! `origin` (centre of the first voxel), `type` (`uint8 (1 inside)`
//! occupancy or `float32` field values; other integer and float names are
//! accepted too) and `endian`.

use crate::error::{header, io_at, Result, ScanError};
use crate::volume::{stream_slices, Assembler, FileType, Geometry, Progress, ReadOptions, Volume};
use serde_json::Value;
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

/// Reads a `.raw` file through its `.json` sidecar (either path may be
/// given).
pub fn read_raw(path: &Path, opts: &ReadOptions, progress: Progress) -> Result<Volume> {
    let raw = path.with_extension("raw");
    let side = path.with_extension("json");
    let text = std::fs::read_to_string(&side).map_err(io_at(&side))?;
    let j: Value = serde_json::from_str(&text).map_err(|source| ScanError::Json {
        path: side.clone(),
        source,
    })?;
    let nums = |key: &str, n: usize| -> Result<Vec<f64>> {
        let v = j.get(key).ok_or_else(|| header(&side, key, "missing"))?;
        let list: Vec<f64> = match v {
            Value::Array(a) => a
                .iter()
                .map(|x| x.as_f64())
                .collect::<Option<Vec<f64>>>()
                .ok_or_else(|| header(&side, key, format!("expected numbers, found {v}")))?,
            Value::Number(x) if key == "spacing" => vec![x.as_f64().unwrap_or(f64::NAN); n],
            _ => {
                return Err(header(
                    &side,
                    key,
                    format!("expected an array of {n} numbers, found {v}"),
                ))
            }
        };
        if list.len() != n {
            return Err(header(
                &side,
                key,
                format!("expected {n} numbers, found {}", list.len()),
            ));
        }
        Ok(list)
    };
    let d = nums("dims", 3)?;
    let mut dims = [0usize; 3];
    for a in 0..3 {
        if !(d[a] >= 1.0 && d[a].fract() == 0.0 && d[a] < 1e12) {
            return Err(header(
                &side,
                "dims",
                format!("expected positive integers, found {}", d[a]),
            ));
        }
        dims[a] = d[a] as usize;
    }
    let s = nums("spacing", 3)?;
    let o = match j.get("origin") {
        Some(_) => nums("origin", 3)?,
        None => vec![0.0; 3],
    };
    let ty_name = j.get("type").and_then(|t| t.as_str()).ok_or_else(|| {
        header(
            &side,
            "type",
            "missing (expected e.g. \"float32\" or \"uint8\")",
        )
    })?;
    let word = ty_name.split_whitespace().next().unwrap_or("");
    let ty = match word {
        "uint8" | "u8" => FileType::U8,
        "int8" | "i8" => FileType::I8,
        "uint16" | "u16" => FileType::U16,
        "int16" | "i16" => FileType::I16,
        "uint32" | "u32" => FileType::U32,
        "int32" | "i32" => FileType::I32,
        "float32" | "float" | "f32" => FileType::F32,
        "float64" | "double" | "f64" => FileType::F64,
        _ => {
            return Err(header(
                &side,
                "type",
                format!("unknown sample type `{ty_name}`"),
            ))
        }
    };
    let little = match j.get("endian").and_then(|e| e.as_str()) {
        None | Some("little") => true,
        Some("big") => false,
        Some(other) => {
            return Err(header(
                &side,
                "endian",
                format!("expected \"little\" or \"big\", found \"{other}\""),
            ))
        }
    };
    let geometry = Geometry::diagonal([s[0], s[1], s[2]], [o[0], o[1], o[2]]);
    let f = File::open(&raw).map_err(io_at(&raw))?;
    let len = f.metadata().map_err(io_at(&raw))?.len();
    let want = dims.iter().map(|&d| d as u64).product::<u64>() * ty.size() as u64;
    if len < want {
        return Err(ScanError::Truncated {
            path: raw,
            offset: 0,
            expected: want,
            found: len,
        });
    }
    if len > want {
        return Err(ScanError::SizeMismatch {
            path: raw,
            what: format!(
                "bytes for {} x {} x {} samples of {word}",
                dims[0], dims[1], dims[2]
            ),
            expected: want,
            found: len,
        });
    }
    let plane = (dims[0] * dims[1] * ty.size()) as u64;
    let mut asm = Assembler::new(
        &raw,
        dims,
        ty,
        geometry,
        (1.0, 0.0),
        true,
        plane * 2,
        "unknown",
        opts,
    )?;
    asm.add_file(&side);
    stream_slices(
        &mut asm,
        &mut BufReader::new(f),
        ty,
        little,
        &raw,
        0,
        progress,
    )?;
    asm.finish()
}
