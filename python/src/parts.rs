//! Analysis in parts for distributed runs (`microfrep.dask`): the survey
//! and refinement of whole-brick slabs, slab labels, and the exact merge
//! (see `microfrep_analysis::partial`). What crosses processes is plain
//! data: tuples, lists and NumPy arrays, which pickle.

use crate::arrays;
use crate::errors;
use crate::fab::analysis_grid;
use crate::model::PyShape;
use microfrep::analysis::partial::{self, BrickMeasures, SlabLabels};
use microfrep::analysis::summary::to_json;
use microfrep::analysis::{Connectivity, Estimate, Report, Sampler};
use numpy::{IntoPyArray, PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

type Box3 = ([f64; 3], [f64; 3]);

/// Brick measures as arrays: ids (u64), values (n x 11: volume, region,
/// area, each value, coarse, kink; then the sampled volume and its
/// variance), sampled flags (u8).
type BrickArrays<'py> = (
    Bound<'py, PyArray1<u64>>,
    Bound<'py, PyArray1<f64>>,
    Bound<'py, PyArray1<u8>>,
);

/// Values per brick in the value arrays.
const PER_BRICK: usize = 11;

fn to_arrays<'py>(py: Python<'py>, b: &[BrickMeasures]) -> BrickArrays<'py> {
    let ids: Vec<u64> = b.iter().map(|m| m.brick as u64).collect();
    let mut vals = Vec::with_capacity(PER_BRICK * b.len());
    for m in b {
        for e in [m.volume, m.region, m.area] {
            vals.extend([e.value, e.coarse, e.kink_diff]);
        }
        vals.extend(m.sampled_volume);
    }
    let s: Vec<u8> = b.iter().map(|m| m.sampled as u8).collect();
    (
        ids.into_pyarray(py),
        vals.into_pyarray(py),
        s.into_pyarray(py),
    )
}

fn from_arrays(
    ids: &PyReadonlyArray1<u64>,
    vals: &PyReadonlyArray1<f64>,
    sampled: &PyReadonlyArray1<u8>,
) -> PyResult<Vec<BrickMeasures>> {
    let (ids, vals, s) = (ids.as_slice()?, vals.as_slice()?, sampled.as_slice()?);
    if vals.len() != PER_BRICK * ids.len() || s.len() != ids.len() {
        return Err(errors::input("brick arrays differ in length"));
    }
    let est = |v: &[f64]| Estimate {
        value: v[0],
        coarse: v[1],
        kink_diff: v[2],
    };
    Ok(ids
        .iter()
        .enumerate()
        .map(|(i, &b)| {
            let v = &vals[PER_BRICK * i..PER_BRICK * (i + 1)];
            BrickMeasures {
                brick: b as usize,
                volume: est(&v[0..3]),
                region: est(&v[3..6]),
                area: est(&v[6..9]),
                sampled: s[i] != 0,
                sampled_volume: [v[9], v[10]],
            }
        })
        .collect())
}

/// Grid of an analysis: (dims, step, brick layers).
#[pyfunction]
#[pyo3(signature = (bounds, resolution=None, voxel=None))]
fn analysis_grid_info(
    bounds: Box3,
    resolution: Option<usize>,
    voxel: Option<f64>,
) -> PyResult<([usize; 3], [f64; 3], usize)> {
    let g = analysis_grid(bounds, resolution, voxel)?;
    Ok((g.dims, g.step, microfrep::analysis::measure::BRICK))
}

/// Survey of voxel layers `k0..k1`: (ids, values, sampled, redo, creased,
/// nodes).
#[pyfunction]
#[pyo3(signature = (shape, region, bounds, resolution, voxel, k0, k1))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn analysis_survey<'py>(
    py: Python<'py>,
    shape: &PyShape,
    region: Option<PyShape>,
    bounds: Box3,
    resolution: Option<usize>,
    voxel: Option<f64>,
    k0: usize,
    k1: usize,
) -> PyResult<(BrickArrays<'py>, Vec<usize>, usize, usize)> {
    let g = analysis_grid(bounds, resolution, voxel)?;
    let (s, r) = (shape.s.clone(), region.map(|r| r.s));
    let sv = py
        .allow_threads(|| partial::survey(&s, r.as_ref(), &g, k0, k1, &|_, _| {}))
        .map_err(errors::analysis)?;
    Ok((to_arrays(py, &sv.bricks), sv.redo, sv.creased, sv.nodes))
}

/// The refinement depth from summed survey counts.
#[pyfunction]
fn analysis_depth(creased: usize, nodes: usize) -> u32 {
    partial::refine_depth(creased, nodes)
}

/// Measures `bricks` at `depth`: (ids, values, sampled).
#[pyfunction]
#[pyo3(signature = (shape, region, bounds, resolution, voxel, depth, bricks))]
#[allow(clippy::too_many_arguments)]
fn analysis_refine<'py>(
    py: Python<'py>,
    shape: &PyShape,
    region: Option<PyShape>,
    bounds: Box3,
    resolution: Option<usize>,
    voxel: Option<f64>,
    depth: u32,
    bricks: Vec<usize>,
) -> PyResult<BrickArrays<'py>> {
    let g = analysis_grid(bounds, resolution, voxel)?;
    let nb = partial::brick_counts(&g);
    let total = nb[0] * nb[1] * nb[2];
    if let Some(b) = bricks.iter().find(|&&b| b >= total) {
        return Err(errors::input(format!(
            "brick {b} is not in the grid of {total}"
        )));
    }
    let (s, r) = (shape.s.clone(), region.map(|r| r.s));
    let m = py.allow_threads(|| partial::refine(&s, r.as_ref(), &g, depth, &bricks, &|_, _| {}));
    Ok(to_arrays(py, &m))
}

/// Labels voxel layers `k0..k1`: a dict of plain data (see
/// `microfrep_analysis::partial::SlabLabels`).
#[pyfunction]
#[pyo3(signature = (shape, region, bounds, resolution, voxel, k0, k1))]
#[allow(clippy::too_many_arguments)]
fn analysis_labels<'py>(
    py: Python<'py>,
    shape: &PyShape,
    region: Option<PyShape>,
    bounds: Box3,
    resolution: Option<usize>,
    voxel: Option<f64>,
    k0: usize,
    k1: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let g = analysis_grid(bounds, resolution, voxel)?;
    let (s, r) = (shape.s.clone(), region.map(|r| r.s));
    let l = py
        .allow_threads(|| {
            let sampler = Sampler::new(&s, r.as_ref(), g.clone());
            partial::label_slab(&sampler, k0, k1, &|_, _| {})
        })
        .map_err(errors::analysis)?;
    let d = PyDict::new(py);
    let c = &l.inner;
    d.set_item("k0", l.k0)?;
    d.set_item("k1", l.k1)?;
    d.set_item("solid_volumes", c.solid_volumes.clone().into_pyarray(py))?;
    d.set_item("pore_components", c.pore_components)?;
    d.set_item("pore_volume", c.pore_volume)?;
    d.set_item("open_pore_volume", c.open_pore_volume)?;
    d.set_item("closed_pores", c.closed_pores)?;
    d.set_item("closed_pore_volume", c.closed_pore_volume)?;
    d.set_item("percolates", c.percolates.to_vec())?;
    d.set_item("euler8", l.euler8)?;
    d.set_item("kinds", l.kinds.into_pyarray(py))?;
    d.set_item("counts", l.counts.into_pyarray(py))?;
    d.set_item("flags", l.flags.into_pyarray(py))?;
    d.set_item("extents", l.extents.into_pyarray(py))?;
    d.set_item("region", l.region.to_vec())?;
    d.set_item("spans", l.spans.into_pyarray(py))?;
    d.set_item("bottom", l.bottom.into_pyarray(py))?;
    d.set_item("top", l.top.into_pyarray(py))?;
    Ok(d)
}

fn slab_of(d: &Bound<'_, PyDict>) -> PyResult<SlabLabels> {
    let get = |k: &str| -> PyResult<Bound<'_, PyAny>> {
        d.get_item(k)?
            .ok_or_else(|| errors::input(format!("slab labels lack '{k}'")))
    };
    let py = d.py();
    let vec_u8 = |k: &str| -> PyResult<Vec<u8>> {
        Ok(
            arrays::vector::<u8>(py, &get(k)?, &format!("slab labels' {k}"))?
                .as_slice()?
                .to_vec(),
        )
    };
    let vec_u32 = |k: &str| -> PyResult<Vec<u32>> {
        Ok(
            arrays::vector::<u32>(py, &get(k)?, &format!("slab labels' {k}"))?
                .as_slice()?
                .to_vec(),
        )
    };
    let p: Vec<bool> = get("percolates")?.extract()?;
    if p.len() != 3 {
        return Err(errors::input("slab labels: percolates needs 3 flags"));
    }
    Ok(SlabLabels {
        k0: get("k0")?.extract()?,
        k1: get("k1")?.extract()?,
        inner: Connectivity {
            solid_volumes: arrays::vector::<f64>(
                py,
                &get("solid_volumes")?,
                "slab labels' solid_volumes",
            )?
            .as_slice()?
            .to_vec(),
            pore_components: get("pore_components")?.extract()?,
            pore_volume: get("pore_volume")?.extract()?,
            open_pore_volume: get("open_pore_volume")?.extract()?,
            closed_pores: get("closed_pores")?.extract()?,
            closed_pore_volume: get("closed_pore_volume")?.extract()?,
            percolates: [p[0], p[1], p[2]],
            ..Connectivity::default()
        },
        euler8: get("euler8")?.extract()?,
        kinds: vec_u8("kinds")?,
        counts: arrays::vector::<u64>(py, &get("counts")?, "slab labels' counts")?
            .as_slice()?
            .to_vec(),
        flags: vec_u8("flags")?,
        extents: vec_u32("extents")?,
        region: {
            let r: Vec<u32> = get("region")?.extract()?;
            r.try_into()
                .map_err(|_| errors::input("slab labels: region needs 6 numbers"))?
        },
        spans: vec_u32("spans")?,
        bottom: vec_u32("bottom")?,
        top: vec_u32("top")?,
    })
}

/// Merges the parts into the report of `microfrep analyze --json` (JSON
/// text): `bricks` is a list of (ids, values, sampled) from surveys and
/// refinements, `labels` the slab label dicts (None: no connectivity).
#[pyfunction]
#[pyo3(signature = (bounds, resolution, voxel, depth, creased, bricks, labels, has_region, name, region_name=None, seconds=[0.0; 3]))]
#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn analysis_merge(
    py: Python<'_>,
    bounds: Box3,
    resolution: Option<usize>,
    voxel: Option<f64>,
    depth: u32,
    creased: usize,
    bricks: Vec<(Bound<'_, PyAny>, Bound<'_, PyAny>, Bound<'_, PyAny>)>,
    labels: Option<Vec<Bound<'_, PyDict>>>,
    has_region: bool,
    name: &str,
    region_name: Option<&str>,
    seconds: [f64; 3],
) -> PyResult<String> {
    let g = analysis_grid(bounds, resolution, voxel)?;
    let mut all = Vec::new();
    for (i, v, s) in &bricks {
        let i = arrays::vector::<u64>(py, i, "brick ids")?;
        let v = arrays::vector::<f64>(py, v, "brick values")?;
        let s = arrays::vector::<u8>(py, s, "brick sampled flags")?;
        all.extend(from_arrays(&i, &v, &s)?);
    }
    let slabs = labels
        .map(|ls| ls.iter().map(slab_of).collect::<PyResult<Vec<_>>>())
        .transpose()?;
    let (measures, connectivity) = py
        .allow_threads(|| {
            let m = partial::merge_measures(&g, depth, creased, all)?;
            let c = slabs
                .as_ref()
                .map(|s| partial::merge_labels(&g, s))
                .transpose()?;
            Ok::<_, microfrep::analysis::AnalysisError>((m, c))
        })
        .map_err(errors::analysis)?;
    let report = Report {
        grid: g,
        region: has_region,
        measures,
        connectivity,
        thickness: None,
        attributes: Vec::new(),
        seconds,
    };
    Ok(to_json(&report, name, region_name).to_string())
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(analysis_grid_info, m)?)?;
    m.add_function(wrap_pyfunction!(analysis_survey, m)?)?;
    m.add_function(wrap_pyfunction!(analysis_depth, m)?)?;
    m.add_function(wrap_pyfunction!(analysis_refine, m)?)?;
    m.add_function(wrap_pyfunction!(analysis_labels, m)?)?;
    m.add_function(wrap_pyfunction!(analysis_merge, m)?)?;
    Ok(())
}
