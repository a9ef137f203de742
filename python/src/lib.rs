//! The extension module `microfrep._core`: the Rust side of the Python
//! package `microfrep`. The Python layer (`python/python/microfrep/`) wraps
//! these classes and functions, records how each model was built (so a
//! model can be pickled and rebuilt on a Dask worker) and holds the
//! documented API; this module is kept thin: conversions, the GIL released
//! around every long call, and errors turned into the package's exception
//! classes.
//!
//! Build it as a wheel with `scripts/test-python` (maturin, into
//! `target/wheels`) or install it from source with `pip install ./python`
//! (from the repository root), and use it through the Python package, not
//! this module directly. The crate is a `cdylib` needing a Python interpreter, so its
//! example is Python rather than a Rust doc test (the package's own tests,
//! `python/tests/`, exercise these calls):
//!
//! ```python
//! import numpy as np
//! import microfrep as mf
//!
//! ball = mf.sphere((0, 0, 0), 1.0)                  # millimetres; inside is f >= 0
//! values = ball.eval(np.array([[0, 0, 0], [2, 0, 0]], dtype=np.float32))
//! assert values[0] > 0 > values[1]                  # centre inside, far point outside
//! vertices, faces = ball.mesh(resolution=32)        # NumPy arrays
//! ```

#![warn(missing_docs)]

use pyo3::create_exception;
use pyo3::exceptions::PyException;
use pyo3::prelude::*;

mod arrays;
mod errors;
mod fab;
mod fill;
mod materials;
mod model;
mod parts;
mod points;

create_exception!(
    _core,
    Error,
    PyException,
    "Base class of every microfrep error."
);
create_exception!(
    _core,
    HyperFunError,
    Error,
    "A HyperFun model with errors; the message lists each with file:line:col, the source line and a caret; `.locations` holds (file, line, column, message) tuples."
);
create_exception!(
    _core,
    LoadError,
    Error,
    "A model source that cannot be loaded (missing file, malformed mesh or scan, bad options)."
);
create_exception!(
    _core,
    InputError,
    Error,
    "An argument out of range or of the wrong shape."
);
create_exception!(
    _core,
    BoundsError,
    Error,
    "The model's bounds cannot be found (an unbounded model): give bounds."
);
create_exception!(
    _core,
    MemoryLimitError,
    Error,
    "A job predicted to need more memory than the process may use."
);
create_exception!(_core, MeshError, Error, "Meshing or writing a mesh failed.");
create_exception!(
    _core,
    SliceError,
    Error,
    "Slicing or writing a slice stack failed."
);
create_exception!(_core, RenderError, Error, "Rendering failed.");
create_exception!(_core, AnalysisError, Error, "Analysis failed.");
create_exception!(
    _core,
    StructureError,
    Error,
    "A microstructure that cannot be built (a density out of reach, a bad cell)."
);

/// The shape class, shared by the modules.
pub use model::PyShape;

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("Error", py.get_type::<Error>())?;
    m.add("HyperFunError", py.get_type::<HyperFunError>())?;
    m.add("LoadError", py.get_type::<LoadError>())?;
    m.add("InputError", py.get_type::<InputError>())?;
    m.add("BoundsError", py.get_type::<BoundsError>())?;
    m.add("MemoryLimitError", py.get_type::<MemoryLimitError>())?;
    m.add("MeshError", py.get_type::<MeshError>())?;
    m.add("SliceError", py.get_type::<SliceError>())?;
    m.add("RenderError", py.get_type::<RenderError>())?;
    m.add("AnalysisError", py.get_type::<AnalysisError>())?;
    m.add("StructureError", py.get_type::<StructureError>())?;
    model::register(m)?;
    points::register(m)?;
    fab::register(m)?;
    parts::register(m)?;
    fill::register(m)?;
    materials::register(m)?;
    Ok(())
}
