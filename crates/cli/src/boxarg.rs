//! The one parser for box options (`--bounds`, `--box`), so every verb
//! accepts and rejects the same spellings with the same messages.

use anyhow::{bail, Context, Result};

/// Parses `xmin,ymin,zmin,xmax,ymax,zmax` for option `flag`: six finite
/// numbers with min < max on every axis.
pub fn parse_box(flag: &str, s: &str) -> Result<([f64; 3], [f64; 3])> {
    let v: Vec<f64> = s
        .split(',')
        .enumerate()
        .map(|(i, t)| {
            t.trim()
                .parse::<f64>()
                .with_context(|| format!("{flag}: value {} ('{t}') is not a number", i + 1))
        })
        .collect::<Result<_>>()?;
    if v.len() != 6 {
        bail!(
            "{flag} needs 6 numbers xmin,ymin,zmin,xmax,ymax,zmax, got {}",
            v.len()
        );
    }
    if let Some(t) = v.iter().find(|t| !t.is_finite()) {
        bail!("{flag}: {t} is not a finite number");
    }
    let (lo, hi) = ([v[0], v[1], v[2]], [v[3], v[4], v[5]]);
    for (a, name) in ["x", "y", "z"].iter().enumerate() {
        if lo[a] >= hi[a] {
            bail!(
                "{flag}: {name}min {} must be below {name}max {}",
                lo[a],
                hi[a]
            );
        }
    }
    Ok((lo, hi))
}
