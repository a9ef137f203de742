//! Models: loading, expressions, set operations, primitives and
//! microstructures, each returning a `Shape` (or an `Expr` for fields).

use crate::errors;
use microfrep::core::frep::{self, Blend};
use microfrep::core::Expr;
use microfrep::shapes as prims;
use microfrep::structures::density::{DensitySolver, LevelTable, STRUT_CELLS, TPMS_CELLS};
use microfrep::structures::struts::{strut_lattice, StrutLattice};
use microfrep::structures::tpms::{tpms, Solid, Tpms};
use microfrep::{Bounds, LoadOptions, Shape};
use pyo3::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// A real function of the point (x, y, z): a field, a density, a level.
#[pyclass(name = "Expr", module = "microfrep._core", frozen)]
#[derive(Clone)]
pub struct PyExpr {
    pub e: Expr,
}

/// A compiled model (inside is `f >= 0`).
#[pyclass(name = "Shape", module = "microfrep._core", frozen)]
#[derive(Clone)]
pub struct PyShape {
    /// The model itself: its value, attribute channels and bounds.
    pub s: Shape,
    /// What it is called in messages: the source, or "model".
    pub name: String,
    /// Notes of the loader (an open mesh, flipped triangles, ...).
    pub notes: Vec<String>,
    /// The source kind: hyperfun, mesh, scan, example, or built.
    pub kind: &'static str,
}

impl PyShape {
    /// Wraps a shape built from Python operations rather than loaded from a
    /// source: named "model" in messages, without loader notes, kind "built".
    pub fn built(s: Shape) -> PyShape {
        PyShape {
            s,
            name: "model".into(),
            notes: Vec::new(),
            kind: "built",
        }
    }

    /// The box to work in: `bounds` if given, else the model's own (the
    /// CLI's rule, so a stack sliced here frames the same box).
    pub fn frame(&self, py: Python<'_>, bounds: Option<([f64; 3], [f64; 3])>) -> PyResult<Bounds> {
        if let Some((lo, hi)) = bounds {
            check_box(lo, hi)?;
            return Ok(Bounds::new(lo, hi));
        }
        let s = self.s.clone();
        py.allow_threads(move || s.bounds())
            .map_err(|e| errors::bounds(&self.name, e))
    }
}

/// Six finite numbers with min < max on every axis.
pub fn check_box(lo: [f64; 3], hi: [f64; 3]) -> PyResult<()> {
    for a in 0..3 {
        if !(lo[a].is_finite() && hi[a].is_finite() && lo[a] < hi[a]) {
            return Err(errors::input(format!(
                "bounds: axis {a} is {} .. {}; give finite numbers with min < max",
                lo[a], hi[a]
            )));
        }
        if lo[a].abs() > 1e15 || hi[a].abs() > 1e15 {
            return Err(errors::input(
                "bounds are beyond what the sampling grids can represent (|v| <= 1e15)",
            ));
        }
    }
    Ok(())
}

#[pymethods]
impl PyShape {
    /// The value expression.
    #[getter]
    fn value(&self) -> PyExpr {
        PyExpr {
            e: self.s.value().clone(),
        }
    }
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.notes.clone()
    }
    #[getter]
    fn kind(&self) -> &'static str {
        self.kind
    }
    /// Names of the attribute channels.
    #[getter]
    fn attribute_names(&self) -> Vec<String> {
        self.s.attributes().iter().map(|a| a.name.clone()).collect()
    }
    /// The model's box: given, or proven by interval subdivision.
    fn bounds(&self, py: Python<'_>) -> PyResult<([f64; 3], [f64; 3])> {
        let b = self.frame(py, None)?;
        Ok((b.min, b.max))
    }
    /// This shape with its box given.
    fn with_bounds(&self, lo: [f64; 3], hi: [f64; 3]) -> PyResult<PyShape> {
        check_box(lo, hi)?;
        Ok(PyShape {
            s: self.s.clone().with_bounds(Bounds::new(lo, hi)),
            ..self.clone()
        })
    }
    /// This shape with one more attribute channel.
    fn with_attribute(&self, name: &str, e: &PyExpr) -> PyShape {
        PyShape {
            s: self.s.clone().with_attribute(name, e.e.clone()),
            ..self.clone()
        }
    }
    /// This shape under another name (for messages and reports).
    fn named(&self, name: String) -> PyShape {
        PyShape {
            name,
            ..self.clone()
        }
    }
    /// Nodes of the expression graph.
    fn node_count(&self) -> usize {
        self.s.value().node_count()
    }
}

#[pymethods]
impl PyExpr {
    /// The constant value, if the expression is one.
    fn as_const(&self) -> Option<f64> {
        self.e.as_const()
    }
    fn node_count(&self) -> usize {
        self.e.node_count()
    }
}

/// Loads `spec` (`PATH[:key=value,...]` or an example name).
#[pyfunction]
#[pyo3(signature = (spec, object=None, params=Vec::new(), fields=Vec::new()))]
fn load(
    py: Python<'_>,
    spec: &str,
    object: Option<String>,
    params: Vec<(usize, f64)>,
    fields: Vec<(String, String)>,
) -> PyResult<PyShape> {
    let opts = LoadOptions {
        object,
        params,
        fields,
        memory_limit: None,
    };
    let r = py.allow_threads(|| microfrep::load(spec, &opts));
    let l = r.map_err(|e| errors::load(py, e, spec, None))?;
    let kind = match l.kind {
        microfrep::SourceKind::HyperFun => "hyperfun",
        microfrep::SourceKind::Mesh => "mesh",
        microfrep::SourceKind::Scan => "scan",
        microfrep::SourceKind::Data => "data",
        microfrep::SourceKind::Example => "example",
    };
    Ok(PyShape {
        s: l.shape,
        name: spec.to_string(),
        notes: l.notes,
        kind,
    })
}

/// Loads a HyperFun model from its text; `file` names it in messages.
#[pyfunction]
#[pyo3(signature = (text, file, object=None, params=Vec::new()))]
fn load_hyperfun_text(
    py: Python<'_>,
    text: &str,
    file: &str,
    object: Option<String>,
    params: Vec<(usize, f64)>,
) -> PyResult<PyShape> {
    microfrep::install_library();
    let lo = microfrep::hyperfun::LoadOptions {
        object,
        params,
        fields: Vec::new(),
    };
    let m = py
        .allow_threads(|| microfrep::hyperfun::load_with_options(text, file, &lo))
        .map_err(|d| errors::hyperfun(py, &d, text, file))?;
    Ok(PyShape {
        s: m.shape(),
        name: file.to_string(),
        notes: Vec::new(),
        kind: "hyperfun",
    })
}

/// The built-in examples: (name, description).
#[pyfunction]
fn examples() -> Vec<(String, String)> {
    microfrep::structures::examples::all()
        .into_iter()
        .map(|e| (e.name.to_string(), e.description.to_string()))
        .collect()
}

#[pyfunction]
fn var(axis: usize) -> PyResult<PyExpr> {
    let e = match axis {
        0 => Expr::x(),
        1 => Expr::y(),
        2 => Expr::z(),
        _ => return Err(errors::input(format!("axis {axis}: 0, 1 or 2"))),
    };
    Ok(PyExpr { e })
}

#[pyfunction]
fn constant(v: f64) -> PyResult<PyExpr> {
    if !v.is_finite() {
        return Err(errors::input(format!("{v} is not a finite number")));
    }
    Ok(PyExpr {
        e: Expr::constant(v),
    })
}

#[pyfunction]
fn unary(op: &str, a: &PyExpr) -> PyResult<PyExpr> {
    let a = &a.e;
    let e = match op {
        "neg" => a.neg(),
        "abs" => a.abs(),
        "sign" => a.sign(),
        "sqrt" => a.sqrt(),
        "square" => a.square(),
        "exp" => a.exp(),
        "log" => a.ln(),
        "sin" => a.sin(),
        "cos" => a.cos(),
        "tan" => a.tan(),
        "asin" => a.asin(),
        "acos" => a.acos(),
        "atan" => a.atan(),
        "sinh" => a.sinh(),
        "cosh" => a.cosh(),
        "tanh" => a.tanh(),
        "floor" => a.floor(),
        "ceil" => a.ceil(),
        "round" => a.round(),
        "fract" => a.fract(),
        _ => return Err(errors::input(format!("unknown function '{op}'"))),
    };
    Ok(PyExpr { e })
}

#[pyfunction]
fn binary(op: &str, a: &PyExpr, b: &PyExpr) -> PyResult<PyExpr> {
    let (a, b) = (&a.e, &b.e);
    let e = match op {
        "add" => a + b,
        "sub" => a - b,
        "mul" => a * b,
        "div" => a / b,
        "pow" => a.pow(b.clone()),
        "min" => a.min(b.clone()),
        "max" => a.max(b.clone()),
        "atan2" => a.atan2(b.clone()),
        "mod" => a.modulo(b.clone()),
        "lt" => a.lt(b.clone()),
        "le" => a.le(b.clone()),
        "gt" => a.gt(b.clone()),
        "ge" => a.ge(b.clone()),
        _ => return Err(errors::input(format!("unknown operation '{op}'"))),
    };
    Ok(PyExpr { e })
}

/// `cond != 0 ? a : b`.
#[pyfunction]
fn select(cond: &PyExpr, a: &PyExpr, b: &PyExpr) -> PyExpr {
    PyExpr {
        e: Expr::select(cond.e.clone(), a.e.clone(), b.e.clone()),
    }
}

/// The expression with x, y, z replaced by `p`.
#[pyfunction]
fn remap(a: &PyExpr, p: (PyExpr, PyExpr, PyExpr)) -> PyExpr {
    PyExpr {
        e: a.e.remap(&[p.0.e, p.1.e, p.2.e]),
    }
}

/// A shape of a value expression.
#[pyfunction]
fn shape(e: &PyExpr) -> PyShape {
    PyShape::built(Shape::new(e.e.clone()))
}

#[derive(Clone, Copy)]
enum SetKind {
    Union,
    Intersection,
    Subtraction,
}

fn set_kind(op: &str) -> PyResult<SetKind> {
    Ok(match op {
        "union" => SetKind::Union,
        "intersection" => SetKind::Intersection,
        "subtraction" => SetKind::Subtraction,
        _ => return Err(errors::input(format!("unknown set operation '{op}'"))),
    })
}

/// R-function set operation of two values.
#[pyfunction]
fn set_op(op: &str, a: &PyExpr, b: &PyExpr, alpha: &PyExpr) -> PyResult<PyExpr> {
    let (a, b, al) = (&a.e, &b.e, alpha.e.clone());
    let e = match set_kind(op)? {
        SetKind::Union => frep::union(a, b, al),
        SetKind::Intersection => frep::intersection(a, b, al),
        SetKind::Subtraction => frep::subtraction(a, b, al),
    };
    Ok(PyExpr { e })
}

/// Blended set operation (Pasko's displacement `a0 / (1 + (f1/a1)^2 +
/// (f2/a2)^2)` added to the R-function).
#[pyfunction]
fn blend_op(
    op: &str,
    a: &PyExpr,
    b: &PyExpr,
    a0: &PyExpr,
    a1: &PyExpr,
    a2: &PyExpr,
    alpha: &PyExpr,
) -> PyResult<PyExpr> {
    let bl = Blend::new(a0.e.clone(), a1.e.clone(), a2.e.clone());
    let (a, b, al) = (&a.e, &b.e, alpha.e.clone());
    let e = match set_kind(op)? {
        SetKind::Union => frep::blend_union(a, b, &bl, al),
        SetKind::Intersection => frep::blend_intersection(a, b, &bl, al),
        SetKind::Subtraction => frep::blend_subtraction(a, b, &bl, al),
    };
    Ok(PyExpr { e })
}

fn p3(c: [f64; 3]) -> microfrep::core::transform::P3 {
    prims::v3(c)
}

fn axis_of(a: usize) -> PyResult<usize> {
    if a > 2 {
        return Err(errors::input(format!("axis {a}: 0 (x), 1 (y) or 2 (z)")));
    }
    Ok(a)
}

/// Primitives of `microfrep::shapes` (HyperFun's hf* forms).
#[pyfunction]
#[pyo3(signature = (name, c, v=None, axis=0, r=None, r2=None))]
fn primitive(
    name: &str,
    c: [f64; 3],
    v: Option<[f64; 3]>,
    axis: usize,
    r: Option<PyExpr>,
    r2: Option<PyExpr>,
) -> PyResult<PyExpr> {
    let p = Expr::xyz();
    let need = |x: Option<PyExpr>, what: &str| {
        x.map(|x| x.e)
            .ok_or_else(|| errors::input(format!("{name}: {what} is required")))
    };
    let e = match name {
        "sphere" => prims::sphere(&p, &p3(c), need(r, "the radius")?),
        "ellipsoid" => prims::ellipsoid(&p, &p3(c), &p3(v.unwrap_or([1.0; 3]))),
        "box" => {
            let w = v.ok_or_else(|| errors::input("box: the size is required"))?;
            if w.iter().any(|s| s.is_nan() || *s <= 0.0) {
                return Err(errors::input(format!("box: sizes {w:?} must be > 0")));
            }
            prims::block(&p, &p3(c), &p3(w))
        }
        "cylinder" => prims::cylinder(&p, &p3(c), axis_of(axis)?, need(r, "the radius")?),
        "cone" => prims::cone(&p, &p3(c), axis_of(axis)?, need(r, "the slope")?),
        "torus" => prims::torus(
            &p,
            &p3(c),
            axis_of(axis)?,
            need(r, "the major radius")?,
            need(r2, "the minor radius")?,
        ),
        "half_space" => {
            let n = v.ok_or_else(|| errors::input("half_space: the normal is required"))?;
            if n.iter().all(|x| *x == 0.0) || n.iter().any(|x| !x.is_finite()) {
                return Err(errors::input(format!(
                    "half_space: the normal {n:?} must be finite and not zero"
                )));
            }
            prims::half_space(&p, c, n)
        }
        _ => return Err(errors::input(format!("unknown primitive '{name}'"))),
    };
    Ok(PyExpr { e })
}

fn tpms_kind(name: &str) -> PyResult<Tpms> {
    Tpms::ALL
        .into_iter()
        .find(|t| t.name() == name.replace('_', "-"))
        .ok_or_else(|| {
            let names: Vec<&str> = Tpms::ALL.iter().map(|t| t.name()).collect();
            errors::input(format!(
                "unknown TPMS '{name}' (known: {})",
                names.join(", ")
            ))
        })
}

fn solid_kind(name: &str) -> PyResult<Solid> {
    match name {
        "network" => Ok(Solid::Network),
        "sheet" => Ok(Solid::Sheet),
        _ => Err(errors::input(format!(
            "unknown TPMS solid '{name}' (network, sheet)"
        ))),
    }
}

fn strut_kind(name: &str) -> PyResult<StrutLattice> {
    let n = match name {
        "sc" | "cubic" => "simple-cubic",
        n => n,
    };
    StrutLattice::ALL
        .into_iter()
        .find(|t| t.name() == n.replace('_', "-"))
        .ok_or_else(|| {
            let names: Vec<&str> = StrutLattice::ALL.iter().map(|t| t.name()).collect();
            errors::input(format!(
                "unknown strut lattice '{name}' (known: sc, {})",
                names.join(", ")
            ))
        })
}

/// The TPMS solid with cells of size `cell` at level `level` (both may be
/// fields).
#[pyfunction]
fn tpms_solid(kind: &str, solid: &str, cell: &PyExpr, level: &PyExpr) -> PyResult<PyExpr> {
    let e = tpms(
        tpms_kind(kind)?,
        solid_kind(solid)?,
        &Expr::xyz(),
        cell.e.clone(),
        level.e.clone(),
    );
    Ok(PyExpr { e })
}

/// The strut lattice with cells of size `cell` and strut radius `r`.
#[pyfunction]
fn strut_solid(kind: &str, cell: &PyExpr, r: &PyExpr) -> PyResult<PyExpr> {
    let e = strut_lattice(strut_kind(kind)?, &Expr::xyz(), cell.e.clone(), r.e.clone());
    Ok(PyExpr { e })
}

/// Densities of the level tables (those of the `mf*` HyperFun library).
const DENSITIES: [f64; 22] = [
    0.02, 0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.35, 0.4, 0.45, 0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8,
    0.85, 0.9, 0.95, 0.97, 0.98,
];

type Solvers = Mutex<HashMap<String, Arc<DensitySolver>>>;

/// One density solver per structure and process, built on first use.
fn solver(
    key: &str,
    make: impl FnOnce() -> PyResult<DensitySolver>,
) -> PyResult<Arc<DensitySolver>> {
    static CACHE: OnceLock<Solvers> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(s) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(key) {
        return Ok(s.clone());
    }
    let s = Arc::new(make()?);
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(key.to_string(), s.clone());
    Ok(s)
}

fn tpms_solver(kind: Tpms, solid: Solid) -> PyResult<Arc<DensitySolver>> {
    solver(&format!("tpms/{}/{solid:?}", kind.name()), || {
        DensitySolver::tpms(kind, solid, TPMS_CELLS).map_err(errors::structure)
    })
}

fn strut_solver(kind: StrutLattice) -> PyResult<Arc<DensitySolver>> {
    solver(&format!("struts/{}", kind.name()), || {
        DensitySolver::struts(kind, STRUT_CELLS).map_err(errors::structure)
    })
}

fn check_density(d: f64) -> PyResult<()> {
    if !(d > 0.0 && d < 1.0) {
        return Err(errors::input(format!(
            "density {d} must be between 0 and 1 (exclusive)"
        )));
    }
    Ok(())
}

/// The level of a TPMS solid whose volume fraction is `density`.
#[pyfunction]
fn tpms_level(py: Python<'_>, kind: &str, solid: &str, density: f64) -> PyResult<f64> {
    check_density(density)?;
    let (k, s) = (tpms_kind(kind)?, solid_kind(solid)?);
    py.allow_threads(|| tpms_solver(k, s)?.solve(density).map_err(errors::structure))
}

/// The strut radius, in cell units, of a lattice of volume fraction
/// `density`.
#[pyfunction]
fn strut_radius(py: Python<'_>, kind: &str, density: f64) -> PyResult<f64> {
    check_density(density)?;
    let k = strut_kind(kind)?;
    py.allow_threads(|| strut_solver(k)?.solve(density).map_err(errors::structure))
}

/// A density field as a level field, piecewise linear between solved
/// densities (the `mf*` library's tables).
#[pyfunction]
#[pyo3(signature = (family, kind, density, solid="network"))]
fn graded_level(
    py: Python<'_>,
    family: &str,
    kind: &str,
    density: &PyExpr,
    solid: &str,
) -> PyResult<PyExpr> {
    let table = match family {
        "tpms" => {
            let (k, s) = (tpms_kind(kind)?, solid_kind(solid)?);
            py.allow_threads(|| {
                let sv = tpms_solver(k, s)?;
                LevelTable::build(&DENSITIES, |d| sv.solve(d)).map_err(errors::structure)
            })?
        }
        "struts" => {
            let k = strut_kind(kind)?;
            py.allow_threads(|| {
                let sv = strut_solver(k)?;
                let (mut ds, mut rs) = (Vec::new(), Vec::new());
                for d in DENSITIES {
                    match sv.solve(d) {
                        Ok(r) => {
                            ds.push(d);
                            rs.push(r);
                        }
                        Err(microfrep::structures::Error::Unreachable { .. }) => break,
                        Err(e) => return Err(errors::structure(e)),
                    }
                }
                if ds.len() < 2 {
                    return Err(errors::structure_msg(format!(
                        "the {kind} lattice reaches too few densities to grade"
                    )));
                }
                LevelTable::build(&ds, |d| {
                    let i = ds.iter().position(|&x| x == d).unwrap_or(0);
                    Ok(rs[i])
                })
                .map_err(errors::structure)
            })?
        }
        _ => return Err(errors::input(format!("unknown family '{family}'"))),
    };
    Ok(PyExpr {
        e: table.piecewise(&density.e),
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyExpr>()?;
    m.add_class::<PyShape>()?;
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(load_hyperfun_text, m)?)?;
    m.add_function(wrap_pyfunction!(examples, m)?)?;
    m.add_function(wrap_pyfunction!(var, m)?)?;
    m.add_function(wrap_pyfunction!(constant, m)?)?;
    m.add_function(wrap_pyfunction!(unary, m)?)?;
    m.add_function(wrap_pyfunction!(binary, m)?)?;
    m.add_function(wrap_pyfunction!(select, m)?)?;
    m.add_function(wrap_pyfunction!(remap, m)?)?;
    m.add_function(wrap_pyfunction!(shape, m)?)?;
    m.add_function(wrap_pyfunction!(set_op, m)?)?;
    m.add_function(wrap_pyfunction!(blend_op, m)?)?;
    m.add_function(wrap_pyfunction!(primitive, m)?)?;
    m.add_function(wrap_pyfunction!(tpms_solid, m)?)?;
    m.add_function(wrap_pyfunction!(strut_solid, m)?)?;
    m.add_function(wrap_pyfunction!(tpms_level, m)?)?;
    m.add_function(wrap_pyfunction!(strut_radius, m)?)?;
    m.add_function(wrap_pyfunction!(graded_level, m)?)?;
    Ok(())
}
