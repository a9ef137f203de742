//! Level and radius tables for density-driven TPMS and strut lattices,
//! solved once per process (on first use) and cached.
//!
//! Each table holds the level (or strut radius, in cell units) solved by
//! bisection on one sampling of the unit cell's field on a grid (see
//! `microfrep_structures::density::DensitySolver`, accurate to about 1e-4
//! relative) at a ladder of densities that includes 0.1, 0.2, 0.3 and 0.5;
//! a density field becomes a level field by piecewise-linear interpolation
//! between them, so those tabulated densities are hit to the solver's
//! accuracy.

use microfrep_structures::density::{DensitySolver, LevelTable, STRUT_CELLS, TPMS_CELLS};
use microfrep_structures::struts::StrutLattice;
use microfrep_structures::tpms::{Solid, Tpms};
use microfrep_structures::Error;
use std::collections::HashMap;
use std::sync::{Mutex, OnceLock};

/// Densities of the table rows.
pub const DENSITIES: [f64; 22] = [
    0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8,
    0.85, 0.9, 0.95, 0.97, 0.98,
];

type Cache = Mutex<HashMap<(u8, u8), Result<LevelTable, String>>>;

fn cached(
    key: (u8, u8),
    solve: impl FnOnce() -> Result<LevelTable, String>,
) -> Result<LevelTable, String> {
    static CACHE: OnceLock<Cache> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    let mut map = cache.lock().unwrap_or_else(|e| e.into_inner());
    map.entry(key).or_insert_with(solve).clone()
}

/// The level table of a TPMS solid.
pub fn tpms_table(kind: Tpms, solid: Solid) -> Result<LevelTable, String> {
    let k = Tpms::ALL.iter().position(|t| *t == kind).unwrap_or(0) as u8;
    cached((k, 1 + (solid == Solid::Sheet) as u8), || {
        let solver = DensitySolver::tpms(kind, solid, TPMS_CELLS).map_err(|e| e.to_string())?;
        LevelTable::build(&DENSITIES, |d| solver.solve(d)).map_err(|e| e.to_string())
    })
}

/// The radius table (cell units) of a strut lattice: the densities a radius
/// up to `MAX_RADIUS` can reach.
pub fn strut_table(kind: StrutLattice) -> Result<LevelTable, String> {
    let k = StrutLattice::ALL
        .iter()
        .position(|t| *t == kind)
        .unwrap_or(0) as u8;
    cached((k, 0), || {
        let solver = DensitySolver::struts(kind, STRUT_CELLS).map_err(|e| e.to_string())?;
        let (mut ds, mut rs) = (Vec::new(), Vec::new());
        for d in DENSITIES {
            match solver.solve(d) {
                Ok(r) => {
                    ds.push(d);
                    rs.push(r);
                }
                Err(Error::Unreachable { .. }) => break,
                Err(e) => return Err(e.to_string()),
            }
        }
        LevelTable::build(&ds, |d| {
            let i = ds.iter().position(|&x| x == d).unwrap_or(0);
            Ok(rs[i])
        })
        .map_err(|e| e.to_string())
    })
}
