//! `mf.fill` and `mf.pores`: the facade's typed fill (`microfrep::fill`),
//! the one the CLI and the studio call, with no fill of its own here. The
//! part is the caller's shape (a mesh or scan loaded by `mf.load` is found
//! to be a signed distance from its root field and sampled once, as the
//! CLI does); the result keeps the built fill, so its measured report and
//! its HyperFun form come from what was built.

use crate::errors;
use crate::model::{check_box, PyExpr, PyShape};
use microfrep::fill::{
    self, Density, FillError, FillOptions, Filled, MeasureOptions, Part, Structure,
};
use microfrep::Bounds;
use pyo3::prelude::*;

/// A filled part: the model and what it was built from.
#[pyclass(name = "Filled", module = "microfrep._core", frozen)]
pub struct PyFilled {
    f: Filled,
    /// The part's name, for messages.
    part: String,
}

/// A fill error as the package's exceptions: loading errors as
/// `LoadError`, options out of range as `InputError`, a structure that
/// cannot be built as `StructureError`.
/// An option of the fill as `mf.fill` spells it.
fn python_option(name: &str) -> String {
    match name {
        "shell" => "skin=".into(),
        "density-grade" => "grade=".into(),
        "density-expr" => "density= (an expression text)".into(),
        "sheet" => "solid='sheet'".into(),
        "material-layer" => "material_layers=".into(),
        "volume-per-pore" => "volume_per_pore=".into(),
        n => format!("{}=", n.replace('-', "_")),
    }
}

fn fill_error(py: Python<'_>, e: FillError, part: &str) -> PyErr {
    match e {
        FillError::Load(l) => errors::load(py, l, part, None),
        e @ FillError::Option(_) => {
            errors::input(format!("fill: {}", e.message_with(&python_option)))
        }
        e @ FillError::Build(_) => {
            errors::structure_msg(format!("fill: {}", e.message_with(&python_option)))
        }
    }
}

/// The density from the Python arguments: a number, a field (`Expr`), a
/// HyperFun expression of `x[1..3]` and `d` (text), or a grade
/// `(at_surface, at_depth, depth)`; exactly one of them.
fn density_of(
    number: Option<f64>,
    field: Option<&PyExpr>,
    text: Option<String>,
    grade: Option<(f64, f64, f64)>,
) -> PyResult<Density> {
    let given = number.is_some() as u8
        + field.is_some() as u8
        + text.is_some() as u8
        + grade.is_some() as u8;
    if given != 1 {
        return Err(errors::input(
            "fill: give one density: a number, an expression, a HyperFun expression text, or \
             grade=(surface, inner, depth)",
        ));
    }
    Ok(if let Some(r) = number {
        Density::Constant(r)
    } else if let Some(e) = field {
        // A constant expression is a constant density (checked as one).
        match e.e.as_const() {
            Some(r) => Density::Constant(r),
            None => Density::Field(e.e.clone()),
        }
    } else if let Some(t) = text {
        Density::Expression(t)
    } else {
        let (at_surface, at_depth, depth) = grade.expect("one density is given");
        Density::Graded {
            at_surface,
            at_depth,
            depth,
        }
    })
}

/// Fills `part` (see the Python `fill`).
#[pyfunction]
#[pyo3(signature = (part, structure, cell, sheet=false, density=None, density_field=None,
    density_text=None, grade=None, skin=None, seed=1, bounds=None, irregularity=None,
    parent_scale=None, subdivision=None, opening=None, material_layers=None, pore_t=None))]
#[allow(clippy::too_many_arguments)]
fn fill_part(
    py: Python<'_>,
    part: &PyShape,
    structure: &str,
    cell: f64,
    sheet: bool,
    density: Option<f64>,
    density_field: Option<PyRef<'_, PyExpr>>,
    density_text: Option<String>,
    grade: Option<(f64, f64, f64)>,
    skin: Option<f64>,
    seed: u64,
    bounds: Option<([f64; 3], [f64; 3])>,
    irregularity: Option<f64>,
    parent_scale: Option<f64>,
    subdivision: Option<String>,
    opening: Option<f64>,
    material_layers: Option<Vec<(f64, f64)>>,
    pore_t: Option<Vec<f64>>,
) -> PyResult<PyFilled> {
    let hand_t = match pore_t {
        None => None,
        Some(t) if t.len() == 24 => Some(std::array::from_fn(|s| std::array::from_fn(|k| t[3 * s + k]))),
        Some(t) => {
            return Err(errors::input(format!(
                "fill: pore_t takes 24 numbers (t of the 8 derived points on x, y, z), got {}",
                t.len()
            )))
        }
    };
    let tmesh = match subdivision.as_deref() {
        None | Some("octree") => false,
        Some("tmesh") => true,
        Some(o) => {
            return Err(errors::input(format!(
                "fill: subdivision '{o}' is 'octree' or 'tmesh'"
            )))
        }
    };
    let s = Structure::parse(structure, sheet).ok_or_else(|| {
        errors::input(format!(
            "fill: unknown structure '{structure}' (TPMS: gyroid, schwarz-p, schwarz-d, \
             neovius, iwp, fks, as networks or with solid='sheet'; struts: sc, bcc, fcc, \
             octet, kelvin, diamond; rods, pores, irregular)"
        ))
    })?;
    if sheet && !matches!(s, Structure::Tpms { .. }) {
        return Err(errors::input(format!(
            "fill: solid='sheet' is for TPMS; '{structure}' has no sheet form"
        )));
    }
    let opts = FillOptions {
        structure: s,
        cell,
        density: density_of(density, density_field.as_deref(), density_text, grade)?,
        skin,
        seed,
        pores: microfrep::fill::PoreControls {
            irregularity,
            parent_scale,
            tmesh,
            opening,
            hand_t,
        },
        material_layers: material_layers
            .unwrap_or_default()
            .into_iter()
            .map(|(depth, ramp)| microfrep::fill::MaterialLayer { depth, ramp })
            .collect(),
    };
    // The box as every other method finds it (an unbounded part is a
    // BoundsError naming the model), or the one given.
    let b = match bounds {
        Some((lo, hi)) => {
            check_box(lo, hi)?;
            Bounds::new(lo, hi)
        }
        None => part.frame(py, None)?,
    };
    let shape = part.s.clone();
    let loaded_data = matches!(part.kind, "mesh" | "scan");
    let name = part.name.clone();
    let notes = part.notes.clone();
    let built = py.allow_threads(move || -> Result<Filled, FillError> {
        let mut p = Part::from_shape(shape, Some(b))?;
        // A mesh or scan part is written in HyperFun as a call bound to
        // its source, as the CLI names it.
        if p.distance && loaded_data {
            p.source = Some(name);
        }
        p.notes = notes;
        fill::fill(&p, &opts, &|_, _, _| {})
    });
    let f = built.map_err(|e| fill_error(py, e, &part.name))?;
    Ok(PyFilled {
        f,
        part: part.name.clone(),
    })
}

impl PyFilled {
    /// One of the fill's shapes, named after the part in messages.
    fn shape(&self, s: microfrep::Shape, what: &str) -> PyShape {
        PyShape {
            name: format!("{what} of {}", self.part),
            ..PyShape::built(s)
        }
    }
}

#[pymethods]
impl PyFilled {
    /// The filled model (skin and infill inside the part), on the part's box.
    #[getter]
    fn model(&self) -> PyShape {
        PyShape {
            notes: self.f.notes.clone(),
            ..self.shape(self.f.model.clone(), "fill")
        }
    }
    /// The core: the part below the skin (the part itself without one).
    #[getter]
    fn core(&self) -> PyShape {
        self.shape(self.f.core.clone(), "core")
    }
    /// The infill alone inside the core.
    #[getter]
    fn infill(&self) -> PyShape {
        self.shape(self.f.infill.clone(), "infill")
    }
    /// The skin alone, if any.
    #[getter]
    fn skin(&self) -> Option<PyShape> {
        self.f.skin.clone().map(|s| self.shape(s, "skin"))
    }
    /// Warnings of the part and the fill.
    #[getter]
    fn notes(&self) -> Vec<String> {
        self.f
            .notes
            .iter()
            .map(|n| microfrep::fill::with_option_names(n, &python_option))
            .collect()
    }
    /// The structure's name as the CLI prints it.
    #[getter]
    fn structure(&self) -> String {
        self.f.options.structure.name()
    }
    /// Designed sizes: (strut radius or None, (pores made, cells dropped) or None).
    #[getter]
    fn design(&self) -> (Option<f64>, Option<(usize, usize)>) {
        (self.f.design.strut_radius, self.f.design.pores)
    }
    /// The `--field` binding the HyperFun form needs, if any: (name, source).
    #[getter]
    fn binding(&self) -> Option<(String, String)> {
        self.f.binding()
    }
    /// The model as HyperFun source, as `microfrep fill ... -o model.hf` writes it.
    fn hyperfun(&self, py: Python<'_>) -> PyResult<String> {
        self.f.hyperfun().map_err(|e| fill_error(py, e, &self.part))
    }
    /// Measures what was built; the report as JSON with the keys of
    /// `microfrep fill --json` (less what the output wrote).
    #[pyo3(signature = (voxels_across=None, min_boxes=None, max_boxes=None, target_error=None,
        thickness_boxes=None, connectivity_voxels=None, rays=None))]
    #[allow(clippy::too_many_arguments)]
    fn measure(
        &self,
        py: Python<'_>,
        voxels_across: Option<f64>,
        min_boxes: Option<usize>,
        max_boxes: Option<usize>,
        target_error: Option<f64>,
        thickness_boxes: Option<usize>,
        connectivity_voxels: Option<u64>,
        rays: Option<usize>,
    ) -> PyResult<String> {
        let d = MeasureOptions::default();
        let mo = MeasureOptions {
            voxels_across: voxels_across.unwrap_or(d.voxels_across),
            min_boxes: min_boxes.unwrap_or(d.min_boxes),
            max_boxes: max_boxes.unwrap_or(d.max_boxes),
            target_error: target_error.unwrap_or(d.target_error),
            thickness_boxes: thickness_boxes.unwrap_or(d.thickness_boxes),
            connectivity_voxels: connectivity_voxels.unwrap_or(d.connectivity_voxels),
            rays: rays.unwrap_or(d.rays),
        };
        let f = &self.f;
        let r = py
            .allow_threads(|| f.measure(&mo, &|_, _, _| {}))
            .map_err(|e| fill_error(py, e, &self.part))?;
        let j = r.to_json(f);
        Ok(j.to_string())
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyFilled>()?;
    m.add_function(wrap_pyfunction!(fill_part, m)?)?;
    Ok(())
}
