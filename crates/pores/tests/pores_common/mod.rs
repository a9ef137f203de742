//! Helpers shared by the pore tests: tight blocks, unit-cell T-meshes and
//! the independent voxel measure of microfrep-analysis.
#![allow(dead_code)]

use microfrep_analysis::{analyze, AnalyzeOptions, Grid, Report};
use microfrep_core::{Expr, Shape};
use microfrep_pores::{Built, CellInfo, Split};
use std::sync::Arc;

/// The box `lo..hi` as `min` of its six slabs (tight intervals).
pub fn block(lo: [f64; 3], hi: [f64; 3]) -> Expr {
    let p = Expr::xyz();
    let mut e: Option<Expr> = None;
    for a in 0..3 {
        let s = (&p[a] - lo[a]).min(Expr::constant(hi[a]) - &p[a]);
        e = Some(match e {
            None => s,
            Some(e) => e.min(s),
        });
    }
    e.unwrap()
}

/// A custom T-mesh rule (direction and percentage per cell): cut whole
/// unit cells off the longest side, so any box of whole units is tiled by
/// unit cells.
pub fn unit_cells() -> microfrep_pores::SplitRule {
    Arc::new(|c: &CellInfo| {
        let ext: Vec<f64> = (0..3).map(|a| c.hi[a] - c.lo[a]).collect();
        let axis = (0..3).max_by(|&a, &b| ext[a].total_cmp(&ext[b])).unwrap();
        let n = ext[axis].round();
        if n <= 1.0 {
            Split::Leaf
        } else {
            Split::Across {
                axis,
                percent: (n / 2.0).floor() / n,
            }
        }
    })
}

/// Porosity (and, with `conn`, connectivity) of `part` minus the pores,
/// measured on a voxel grid of `res` along the longest side of `bounds`.
pub fn measure(
    built: &Built,
    part: &Expr,
    bounds: [[f64; 3]; 2],
    res: usize,
    conn: bool,
) -> Report {
    let solid = Shape::from(&built.solid(part));
    let region = Shape::from(part);
    let opts = AnalyzeOptions {
        thickness: false,
        connectivity: conn,
        ..AnalyzeOptions::default()
    };
    analyze(
        &solid,
        Some(&region),
        Grid::new(bounds, res).unwrap(),
        &opts,
        &|_, _, _| {},
    )
    .unwrap()
}
