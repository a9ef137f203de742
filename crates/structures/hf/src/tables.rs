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

/// The level table of a TPMS solid: the levels solved once by
/// [`solve_tpms_table`] and stored in `tables_data.rs` (a test checks that
/// they are what the solver gives, bit for bit), so no process pays for
/// solving them.
pub fn tpms_table(kind: Tpms, solid: Solid) -> Result<LevelTable, String> {
    let k = Tpms::ALL.iter().position(|t| *t == kind).unwrap_or(0);
    let s = (solid == Solid::Sheet) as usize;
    cached((k as u8, 1 + s as u8), || {
        from_rows(&DENSITIES, &data::TPMS_LEVELS[k][s])
    })
}

/// The radius table (cell units) of a strut lattice: the densities a radius
/// up to `MAX_RADIUS` can reach, stored as [`tpms_table`]'s are (solved by
/// [`solve_strut_table`]).
pub fn strut_table(kind: StrutLattice) -> Result<LevelTable, String> {
    let k = StrutLattice::ALL
        .iter()
        .position(|t| *t == kind)
        .unwrap_or(0);
    cached((k as u8, 0), || {
        let radii = data::STRUT_RADII[k];
        from_rows(&DENSITIES[..radii.len()], radii)
    })
}

fn from_rows(densities: &[f64], levels: &[f64]) -> Result<LevelTable, String> {
    LevelTable::build(densities, |d| {
        let i = densities.iter().position(|&x| x == d).unwrap_or(0);
        Ok(levels[i])
    })
    .map_err(|e| e.to_string())
}

/// Solves the level table of a TPMS solid (what `tables_data.rs` holds).
pub fn solve_tpms_table(kind: Tpms, solid: Solid) -> Result<LevelTable, String> {
    let solver = DensitySolver::tpms(kind, solid, TPMS_CELLS).map_err(|e| e.to_string())?;
    LevelTable::build(&DENSITIES, |d| solver.solve(d)).map_err(|e| e.to_string())
}

/// Solves the radius table of a strut lattice, up to the first density its
/// largest radius cannot reach (what `tables_data.rs` holds).
pub fn solve_strut_table(kind: StrutLattice) -> Result<LevelTable, String> {
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
    from_rows(&ds, &rs)
}

#[path = "tables_data.rs"]
mod data;

#[cfg(test)]
mod tests {
    use super::*;

    /// The source of `tables_data.rs` for the tables the solver gives.
    fn source() -> String {
        let row = |v: &[f64]| {
            let items: Vec<String> = v.iter().map(|x| format!("{x:?}")).collect();
            format!("[{}]", items.join(", "))
        };
        let mut s = String::from(
            "//! The level tables of `tables.rs`, as the density solver gives them\n\
             //! (generated: `MICROFREP_WRITE_TABLES=1 cargo test -p microfrep-structures-hf\n\
             //! --release --lib tables`; a test checks them against the solver).\n\n",
        );
        s += "/// Levels per TPMS (in `Tpms::ALL` order), network then sheet, at `DENSITIES`.\n";
        s += "#[rustfmt::skip]\npub(super) const TPMS_LEVELS: [[[f64; 22]; 2]; 6] = [\n";
        for kind in Tpms::ALL {
            let n = solve_tpms_table(kind, Solid::Network).unwrap();
            let sh = solve_tpms_table(kind, Solid::Sheet).unwrap();
            s += &format!(
                "    [\n        {},\n        {},\n    ],\n",
                row(n.level()),
                row(sh.level())
            );
        }
        s += "];\n\n/// Radii per strut lattice (in `StrutLattice::ALL` order), at the first\n";
        s += "/// `DENSITIES` they reach.\n#[rustfmt::skip]\npub(super) const STRUT_RADII: [&[f64]; 6] = [\n";
        for kind in StrutLattice::ALL {
            s += &format!("    &{},\n", row(solve_strut_table(kind).unwrap().level()));
        }
        s += "];\n";
        s
    }

    /// The stored tables are the solver's, bit for bit (set
    /// `MICROFREP_WRITE_TABLES=1` to write them after a solver change).
    #[test]
    fn stored_tables_are_what_the_solver_gives() {
        let want = source();
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/src/tables_data.rs");
        if std::env::var_os("MICROFREP_WRITE_TABLES").is_some() {
            std::fs::write(path, &want).unwrap();
        }
        let have = std::fs::read_to_string(path).unwrap();
        assert!(
            have == want,
            "tables_data.rs differs from the solver's tables"
        );
    }
}
