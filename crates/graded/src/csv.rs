//! Measured material data from CSV into a [`BezierBox`].
//!
//! The file has the header `x,y,z,value` (case and spaces around fields do
//! not matter) and one sample per line: four numbers separated by commas.
//! Blank lines and lines starting with `#` are skipped. The points must form
//! a full regular grid of `(l+1)(m+1)(n+1)` points in any order: on each
//! axis the coordinates take `l+1 >= 2` equally spaced values (each within
//! `1e-6` of the spacing from its node), every combination exactly once.
//! The grid's box is the data's bounding box and the degrees are `l, m, n`.
//!
//! [`CsvMode::Interpolate`] (the default) solves for the weights of the
//! polynomial passing through every sample; [`CsvMode::Weights`] takes the
//! values as the control weights themselves (weight `(i, j, k)` is the
//! sample at grid node `(i, j, k)`, its control point).
//!
//! The format is fixed (four numbers, no quoting), so the reader is a few
//! lines of our own rather than a CSV crate, which lets every error name its
//! line and field and say what was expected.

use crate::bezier::{BezierBox, MAX_DEGREE};
use crate::error::{io_at, Error, Result};
use std::path::Path;

/// How the values are used.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum CsvMode {
    /// The polynomial passes through every sample.
    #[default]
    Interpolate,
    /// The values are the control weights.
    Weights,
}

/// Largest file read (the grid is at most `(MAX_DEGREE+1)^3` samples of a
/// few dozen bytes each).
pub const MAX_FILE_BYTES: u64 = 16 << 20;

const NAMES: [&str; 4] = ["x", "y", "z", "value"];

/// Reads a CSV file.
pub fn read_csv(path: &Path, mode: CsvMode) -> Result<BezierBox> {
    let meta = std::fs::metadata(path).map_err(io_at(path))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(Error::Csv {
            file: path.display().to_string(),
            line: 1,
            message: format!(
                "file of {} bytes is larger than the {MAX_FILE_BYTES} bytes a grid of at most \
                 {} samples needs",
                meta.len(),
                (MAX_DEGREE + 1).pow(3)
            ),
        });
    }
    let text = std::fs::read_to_string(path).map_err(io_at(path))?;
    parse_csv(&text, &path.display().to_string(), mode)
}

/// Parses CSV text; `file` names it in errors and becomes the field's name.
pub fn parse_csv(text: &str, file: &str, mode: CsvMode) -> Result<BezierBox> {
    let err = |line: usize, message: String| Error::Csv {
        file: file.to_string(),
        line,
        message,
    };
    let max_rows = (MAX_DEGREE + 1).pow(3);
    let mut lines = text
        .strip_prefix('\u{feff}')
        .unwrap_or(text)
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty() && !l.starts_with('#'));
    let Some((hline, header)) = lines.next() else {
        return Err(err(
            1,
            "no data: expected the header `x,y,z,value` and one sample per line".into(),
        ));
    };
    let fields: Vec<&str> = header.split(',').map(str::trim).collect();
    let is_header = fields.len() == 4
        && fields
            .iter()
            .zip(NAMES)
            .all(|(f, n)| f.eq_ignore_ascii_case(n));
    if !is_header {
        let looks_numeric = fields.iter().all(|f| f.parse::<f64>().is_ok());
        return Err(err(
            hline,
            if looks_numeric {
                format!("missing header: expected `x,y,z,value` before the data, found {header:?}")
            } else {
                format!("header must be `x,y,z,value`, found {header:?}")
            },
        ));
    }
    let mut rows: Vec<(usize, [f64; 4])> = Vec::new();
    for (line, text) in lines {
        if rows.len() == max_rows {
            return Err(err(
                line,
                format!(
                    "more than {max_rows} samples: a grid has at most {} points per axis",
                    MAX_DEGREE + 1
                ),
            ));
        }
        let fields: Vec<&str> = text.split(',').map(str::trim).collect();
        if fields.len() != 4 {
            return Err(err(
                line,
                format!(
                    "expected 4 comma-separated fields x,y,z,value, found {}",
                    fields.len()
                ),
            ));
        }
        let mut v = [0.0; 4];
        for c in 0..4 {
            v[c] = fields[c]
                .parse::<f64>()
                .map_err(|source| Error::CsvNumber {
                    file: file.to_string(),
                    line,
                    column: c + 1,
                    name: NAMES[c],
                    text: fields[c].to_string(),
                    source,
                })?;
            if !v[c].is_finite() {
                return Err(err(
                    line,
                    format!(
                        "field {} ({}) is {:?}, expected a finite number",
                        c + 1,
                        NAMES[c],
                        fields[c]
                    ),
                ));
            }
        }
        rows.push((line, v));
    }
    let end = text.lines().count() + 1;
    if rows.is_empty() {
        return Err(err(end, "no samples after the header".into()));
    }
    // The grid nodes of each axis.
    let mut nodes = [(0.0, 0.0, 0usize); 3];
    for a in 0..3 {
        let lo = rows.iter().map(|r| r.1[a]).fold(f64::INFINITY, f64::min);
        let hi = rows
            .iter()
            .map(|r| r.1[a])
            .fold(f64::NEG_INFINITY, f64::max);
        let tol = 1e-9 * (hi - lo).abs().max(lo.abs()).max(1e-300);
        let mut vals: Vec<f64> = rows.iter().map(|r| r.1[a]).collect();
        vals.sort_by(f64::total_cmp);
        vals.dedup_by(|b, a| (*b - *a).abs() <= tol);
        let n = vals.len();
        if n < 2 {
            return Err(err(
                end,
                format!(
                    "{} takes the single value {lo}: a grid needs at least 2 values per axis",
                    NAMES[a]
                ),
            ));
        }
        if n > MAX_DEGREE + 1 {
            return Err(err(
                end,
                format!(
                    "{} takes {n} distinct values, more than the {} of a degree-{MAX_DEGREE} grid",
                    NAMES[a],
                    MAX_DEGREE + 1
                ),
            ));
        }
        nodes[a] = (lo, (hi - lo) / (n - 1) as f64, n);
    }
    let dims = nodes.map(|n| n.2);
    let want = dims[0] * dims[1] * dims[2];
    let mut seen: Vec<Option<usize>> = vec![None; want];
    let mut samples = vec![0.0; want];
    for &(line, v) in &rows {
        let mut idx = [0usize; 3];
        for a in 0..3 {
            let (lo, step, n) = nodes[a];
            let t = (v[a] - lo) / step;
            let i = t.round();
            if (t - i).abs() > 1e-6 {
                return Err(err(
                    line,
                    format!(
                        "{} = {} is not on the regular grid of {n} values from {lo} step {step}: \
                         samples must be equally spaced on every axis",
                        NAMES[a], v[a]
                    ),
                ));
            }
            idx[a] = i as usize;
        }
        let k = idx[0] + dims[0] * (idx[1] + dims[1] * idx[2]);
        if let Some(first) = seen[k] {
            return Err(err(
                line,
                format!(
                    "duplicate point ({}, {}, {}), first given on line {first}: each grid point \
                     must appear exactly once",
                    v[0], v[1], v[2]
                ),
            ));
        }
        seen[k] = Some(line);
        samples[k] = v[3];
    }
    if let Some(k) = seen.iter().position(Option::is_none) {
        let idx = [
            k % dims[0],
            (k / dims[0]) % dims[1],
            k / (dims[0] * dims[1]),
        ];
        let p: [f64; 3] = std::array::from_fn(|a| nodes[a].0 + nodes[a].1 * idx[a] as f64);
        return Err(err(
            end,
            format!(
                "not a full grid: {} samples for {} x {} x {} = {want} grid points; point \
                 ({}, {}, {}) is missing",
                rows.len(),
                dims[0],
                dims[1],
                dims[2],
                p[0],
                p[1],
                p[2]
            ),
        ));
    }
    let min = nodes.map(|n| n.0);
    let max: [f64; 3] = std::array::from_fn(|a| nodes[a].0 + nodes[a].1 * (nodes[a].2 - 1) as f64);
    let deg = dims.map(|d| d - 1);
    match mode {
        CsvMode::Interpolate => BezierBox::interpolate(file, min, max, deg, &samples),
        CsvMode::Weights => BezierBox::new(file, min, max, deg, samples),
    }
}
