//! Evaluation on NumPy arrays: values, precise values, grids, gradients and
//! attributes, on all threads with the GIL released.
//!
//! Points come as an `N x 3` array of float32 or float64 in any layout. The
//! batch evaluator takes separate x, y and z slices: where the array's
//! columns are contiguous (Fortran order, or a transposed `3 x N` array)
//! they are used in place; otherwise (the usual C-order rows) each thread
//! gathers one chunk of a few thousand points at a time into buffers that
//! stay in cache, and the input is never copied whole.

use crate::arrays;
use crate::errors;
use crate::model::PyShape;
use microfrep::core::eval::BLOCK;
use microfrep::core::{BatchEval, GradBatchEval, PointEval, Tape};
use numpy::ndarray::{ArrayView2, Axis};
use numpy::{IntoPyArray, PyArray1, PyArray2, PyArrayMethods, PyReadonlyArray2};
use pyo3::prelude::*;
use rayon::prelude::*;

/// Points per task: several blocks, so per-task overhead stays small.
const CHUNK: usize = BLOCK * 16;

/// A view of the input points.
#[derive(Clone, Copy)]
enum Points<'a> {
    F32(ArrayView2<'a, f32>),
    F64(ArrayView2<'a, f64>),
}

impl Points<'_> {
    fn len(&self) -> usize {
        match self {
            Points::F32(v) => v.nrows(),
            Points::F64(v) => v.nrows(),
        }
    }

    /// The x, y and z columns as slices, when they are contiguous f32.
    fn columns(&self) -> Option<[&[f32]; 3]> {
        match self {
            Points::F32(v) => {
                let c = |a: usize| v.index_axis(Axis(1), a).to_slice();
                Some([c(0)?, c(1)?, c(2)?])
            }
            Points::F64(_) => None,
        }
    }

    /// Points `s..e` into `x`, `y`, `z` (as f32).
    fn gather(&self, s: usize, e: usize, x: &mut Vec<f32>, y: &mut Vec<f32>, z: &mut Vec<f32>) {
        x.clear();
        y.clear();
        z.clear();
        match self {
            Points::F32(v) => {
                if let Some(flat) = v.as_slice() {
                    for p in flat[3 * s..3 * e].chunks_exact(3) {
                        x.push(p[0]);
                        y.push(p[1]);
                        z.push(p[2]);
                    }
                } else {
                    for i in s..e {
                        x.push(v[[i, 0]]);
                        y.push(v[[i, 1]]);
                        z.push(v[[i, 2]]);
                    }
                }
            }
            Points::F64(v) => {
                for i in s..e {
                    x.push(v[[i, 0]] as f32);
                    y.push(v[[i, 1]] as f32);
                    z.push(v[[i, 2]] as f32);
                }
            }
        }
    }

    /// Point `i` in f64.
    fn at(&self, i: usize) -> [f64; 3] {
        match self {
            Points::F32(v) => [v[[i, 0]] as f64, v[[i, 1]] as f64, v[[i, 2]] as f64],
            Points::F64(v) => [v[[i, 0]], v[[i, 1]], v[[i, 2]]],
        }
    }
}

/// Borrows `obj` as points and runs `f` on them with the GIL released.
/// An array that is not `N x 3` float32 or float64 is refused with what is
/// wrong with it (see `arrays::check_points`).
fn with_points<R: Send>(
    py: Python<'_>,
    obj: &Bound<'_, PyAny>,
    f: impl FnOnce(Points) -> R + Send,
) -> PyResult<R> {
    arrays::check_points(py, obj)?;
    if let Ok(a) = obj.downcast::<numpy::PyArray2<f32>>() {
        let r: PyReadonlyArray2<f32> = a
            .try_readonly()
            .map_err(|e| errors::input(format!("points: {e}")))?;
        let v = r.as_array();
        return Ok(py.allow_threads(|| f(Points::F32(v))));
    }
    if let Ok(a) = obj.downcast::<numpy::PyArray2<f64>>() {
        let r: PyReadonlyArray2<f64> = a
            .try_readonly()
            .map_err(|e| errors::input(format!("points: {e}")))?;
        let v = r.as_array();
        return Ok(py.allow_threads(|| f(Points::F64(v))));
    }
    Err(errors::input(format!(
        "points: {} cannot be read as an N x 3 array of float32 or float64",
        obj.repr().map(|r| r.to_string()).unwrap_or_default()
    )))
}

/// Output `k` of `tape` at every point, in f32, on all threads.
fn eval_tape(tape: &Tape, k: usize, pts: Points, out: &mut [f32]) {
    if let (0, Points::F32(v)) = (k, pts) {
        if let Some(flat) = v.as_slice() {
            return eval_rows(tape, flat, out);
        }
    }
    let cols = pts.columns();
    out.par_chunks_mut(CHUNK).enumerate().for_each_init(
        || (BatchEval::new(tape), Vec::new(), Vec::new(), Vec::new()),
        |(ev, xs, ys, zs), (ci, o)| {
            let s = ci * CHUNK;
            let e = s + o.len();
            match cols {
                Some([x, y, z]) => ev.eval_output(k, &x[s..e], &y[s..e], &z[s..e], o),
                None => {
                    pts.gather(s, e, xs, ys, zs);
                    ev.eval_output(k, xs, ys, zs, o);
                }
            }
        },
    );
}

/// The value at C-order rows `x y z`: each block of points is split into
/// the evaluator's own x, y, z lanes (in L1 cache) and evaluated there, so
/// the rows are read once and nothing else is written but the output.
fn eval_rows(tape: &Tape, flat: &[f32], out: &mut [f32]) {
    out.par_chunks_mut(CHUNK).enumerate().for_each_init(
        || BatchEval::new(tape),
        |ev, (ci, o)| {
            let s = ci * CHUNK;
            for (bi, ob) in o.chunks_mut(BLOCK).enumerate() {
                let at = s + bi * BLOCK;
                let rows = &flat[3 * at..3 * (at + ob.len())];
                let (lx, ly, lz) = ev.coords_mut();
                for (i, p) in rows.chunks_exact(3).enumerate() {
                    lx[i] = p[0];
                    ly[i] = p[1];
                    lz[i] = p[2];
                }
                ob.copy_from_slice(ev.eval_loaded(ob.len()));
            }
        },
    );
}

fn check_len(n: usize, per: usize, what: &str) -> PyResult<()> {
    errors::check_memory((n * per) as f64, what)
}

#[pymethods]
impl PyShape {
    /// Values at the points (f32 batch evaluation); NaN where the model
    /// is undefined.
    fn eval<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let tape = self.s.tape().clone();
        let out = with_points(py, points, |p| {
            check_len(p.len(), 4, "the values")?;
            let mut out = vec![0.0f32; p.len()];
            eval_tape(&tape, 0, p, &mut out);
            Ok::<_, PyErr>(out)
        })??;
        Ok(out.into_pyarray(py))
    }

    /// Values at the points in f64 (the point evaluator: the reference
    /// values `microfrep eval` prints).
    fn eval_precise<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let tape = self.s.tape().clone();
        let out = with_points(py, points, |p| {
            check_len(p.len(), 8, "the values")?;
            let mut out = vec![0.0f64; p.len()];
            out.par_chunks_mut(CHUNK).enumerate().for_each_init(
                || PointEval::new(&tape),
                |ev, (ci, o)| {
                    for (j, v) in o.iter_mut().enumerate() {
                        *v = ev.eval(p.at(ci * CHUNK + j));
                    }
                },
            );
            Ok::<_, PyErr>(out)
        })??;
        Ok(out.into_pyarray(py))
    }

    /// Values and gradients `[v, dx, dy, dz]` per point (N x 4, f32).
    fn value_gradient<'py>(
        &self,
        py: Python<'py>,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray2<f32>>> {
        let tape = self.s.tape().clone();
        let (n, out) = with_points(py, points, |p| {
            check_len(p.len(), 16, "the gradients")?;
            let mut out = vec![[0.0f32; 4]; p.len()];
            out.par_chunks_mut(CHUNK).enumerate().for_each_init(
                || {
                    (
                        GradBatchEval::new(&tape),
                        Vec::new(),
                        Vec::new(),
                        Vec::new(),
                    )
                },
                |(ev, xs, ys, zs), (ci, o)| {
                    let s = ci * CHUNK;
                    p.gather(s, s + o.len(), xs, ys, zs);
                    ev.eval(xs, ys, zs, o);
                },
            );
            Ok::<_, PyErr>((p.len(), out.into_iter().flatten().collect::<Vec<f32>>()))
        })??;
        out.into_pyarray(py)
            .reshape([n, 4])
            .map_err(|e| errors::input(e.to_string()))
    }

    /// Attribute `name` at the points (f32).
    fn attribute<'py>(
        &self,
        py: Python<'py>,
        name: &str,
        points: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        let k = self
            .s
            .attributes()
            .iter()
            .position(|a| a.name == name)
            .ok_or_else(|| {
                let names: Vec<&str> = self
                    .s
                    .attributes()
                    .iter()
                    .map(|a| a.name.as_str())
                    .collect();
                errors::input(format!(
                    "model '{}' has no attribute '{name}' (it has: {})",
                    self.name,
                    if names.is_empty() {
                        "none".to_string()
                    } else {
                        names.join(", ")
                    }
                ))
            })?;
        let out_k = self.s.attribute_output(k);
        let tape = self.s.outputs().clone();
        let out = with_points(py, points, |p| {
            check_len(p.len(), 4, "the attribute values")?;
            let mut out = vec![0.0f32; p.len()];
            eval_tape(&tape, out_k, p, &mut out);
            Ok::<_, PyErr>(out)
        })??;
        Ok(out.into_pyarray(py))
    }

    /// Values on the grid of `dims` nodes from `lo` to `hi` inclusive,
    /// x fastest: a flat array of `nz * ny * nx` values.
    fn eval_grid_flat<'py>(
        &self,
        py: Python<'py>,
        lo: [f64; 3],
        hi: [f64; 3],
        dims: [usize; 3],
    ) -> PyResult<Bound<'py, PyArray1<f32>>> {
        for a in 0..3 {
            if dims[a] == 0 {
                return Err(errors::input(format!("grid dims {dims:?} must be >= 1")));
            }
            if !(lo[a].is_finite() && hi[a].is_finite() && lo[a] <= hi[a]) {
                return Err(errors::input(format!(
                    "grid bounds on axis {a} are {} .. {}: give finite numbers, min <= max",
                    lo[a], hi[a]
                )));
            }
        }
        let n = dims
            .iter()
            .try_fold(1usize, |acc, &d| acc.checked_mul(d))
            .ok_or_else(|| errors::input(format!("grid {dims:?} is too large")))?;
        errors::check_memory(4.0 * n as f64, &format!("a grid of {dims:?} values"))?;
        let step: [f64; 3] = std::array::from_fn(|a| {
            if dims[a] > 1 {
                (hi[a] - lo[a]) / (dims[a] - 1) as f64
            } else {
                0.0
            }
        });
        let tape = self.s.tape().clone();
        let out = py.allow_threads(|| microfrep::core::eval::eval_grid_par(&tape, dims, lo, step));
        Ok(out.into_pyarray(py))
    }
}

/// The Rust batch evaluation of a shape's value on separate x, y, z arrays
/// (`eval_points_par`), for the bench's comparison.
#[pyfunction]
fn eval_points_par<'py>(
    py: Python<'py>,
    shape: &PyShape,
    x: &Bound<'py, PyAny>,
    y: &Bound<'py, PyAny>,
    z: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray1<f32>>> {
    let x = arrays::vector::<f32>(py, x, "x")?;
    let y = arrays::vector::<f32>(py, y, "y")?;
    let z = arrays::vector::<f32>(py, z, "z")?;
    let (x, y, z) = (x.as_slice()?, y.as_slice()?, z.as_slice()?);
    if x.len() != y.len() || x.len() != z.len() {
        return Err(errors::input("x, y and z differ in length"));
    }
    let tape = shape.s.tape().clone();
    let out = py.allow_threads(|| microfrep::core::eval::eval_points_par(&tape, x, y, z));
    Ok(out.into_pyarray(py))
}

/// Threads of the pool the evaluations run on.
#[pyfunction]
fn threads() -> usize {
    rayon::current_num_threads()
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(eval_points_par, m)?)?;
    m.add_function(wrap_pyfunction!(threads, m)?)?;
    Ok(())
}
