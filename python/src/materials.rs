//! Park's material subspaces (`microfrep::graded::subspace`): graded
//! regions with their own local coordinates over a primary material, as
//! one fraction expression per material.

use crate::errors;
use crate::model::PyExpr;
use microfrep::graded::subspace::{MaterialModel, Subspace};
use pyo3::prelude::*;

/// A material subspace (built by `subspace`, `subspace_below_surface` or
/// `subspace_in_box`); materials are 0-based here.
#[pyclass(name = "Subspace", module = "microfrep._core", frozen)]
#[derive(Clone)]
pub struct PySubspace {
    s: Subspace,
}

fn based(s: Subspace, base: Option<usize>) -> PySubspace {
    PySubspace {
        s: match base {
            Some(b) => s.with_base(b),
            None => s,
        },
    }
}

/// A subspace with region `region` (inside `>= 0`), local coordinates
/// `local` (three expressions of the point) and the fraction of `material`
/// written in the local coordinates (its x, y, z are the local u, v, w).
#[pyfunction]
#[pyo3(signature = (region, local, fraction, material, base=None))]
fn subspace(
    region: &PyExpr,
    local: (PyExpr, PyExpr, PyExpr),
    fraction: &PyExpr,
    material: usize,
    base: Option<usize>,
) -> PySubspace {
    let local = [local.0.e, local.1.e, local.2.e];
    based(
        Subspace::new(region.e.clone(), local, fraction.e.clone(), material),
        base,
    )
}

/// The layer from depth `depth_from` down, local coordinates `uv` and
/// `w = clamp((depth - depth_from) / ramp, 0, 1)`.
#[pyfunction]
#[pyo3(signature = (depth, depth_from, ramp, uv, fraction, material, base=None))]
fn subspace_below_surface(
    depth: &PyExpr,
    depth_from: f64,
    ramp: f64,
    uv: (PyExpr, PyExpr),
    fraction: &PyExpr,
    material: usize,
    base: Option<usize>,
) -> PyResult<PySubspace> {
    if !(depth_from.is_finite() && ramp.is_finite() && ramp > 0.0) {
        return Err(errors::input(format!(
            "a subspace below a surface needs a finite depth and a depth range > 0, \
             got from {depth_from} over {ramp}"
        )));
    }
    let s = Subspace::below_surface(
        &depth.e,
        depth_from,
        ramp,
        [uv.0.e, uv.1.e],
        fraction.e.clone(),
        material,
    );
    Ok(based(s, base))
}

/// The box `lo`..`hi` mapped to local coordinates `[0, 1]^3`.
#[pyfunction]
#[pyo3(signature = (lo, hi, fraction, material, base=None))]
fn subspace_in_box(
    lo: [f64; 3],
    hi: [f64; 3],
    fraction: &PyExpr,
    material: usize,
    base: Option<usize>,
) -> PyResult<PySubspace> {
    if !(0..3).all(|a| lo[a].is_finite() && hi[a].is_finite() && lo[a] < hi[a]) {
        return Err(errors::input(format!(
            "a subspace box needs finite lo < hi on every axis, got {lo:?} .. {hi:?}"
        )));
    }
    Ok(based(
        Subspace::in_box(lo, hi, fraction.e.clone(), material),
        base,
    ))
}

/// One fraction expression per material of `part`: `primary` fills the
/// part, the subspaces are laid over it in order; all 0 outside the part.
#[pyfunction]
fn material_fractions(
    part: &PyExpr,
    count: usize,
    primary: usize,
    subspaces: Vec<PySubspace>,
) -> PyResult<Vec<PyExpr>> {
    let mut m = MaterialModel::new(count, primary).map_err(|e| errors::input(e.to_string()))?;
    for s in subspaces {
        m.push(s.s).map_err(|e| errors::input(e.to_string()))?;
    }
    Ok(m.fractions(&part.e)
        .into_iter()
        .map(|e| PyExpr { e })
        .collect())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PySubspace>()?;
    m.add_function(wrap_pyfunction!(subspace, m)?)?;
    m.add_function(wrap_pyfunction!(subspace_below_surface, m)?)?;
    m.add_function(wrap_pyfunction!(subspace_in_box, m)?)?;
    m.add_function(wrap_pyfunction!(material_fractions, m)?)?;
    Ok(())
}
