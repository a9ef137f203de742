"""microfrep: procedural function-based microstructures from Python.

Models are real functions of the point (FRep: inside is ``f >= 0``, units
are millimetres), written in HyperFun or built here, compiled once and
evaluated on all cores with the GIL released. NumPy arrays in and out.

>>> import microfrep as mf
>>> part = mf.sphere((0, 0, 0), 5.0)
>>> lattice = mf.gyroid(cell=2.0, density=0.3)
>>> model = mf.fill(part, "gyroid", cell=2.0, density=0.3, skin=0.4)
>>> v = model.eval([[0.0, 0.0, 4.9]])   # inside the skin
>>> bool(v[0] >= 0)
True

Loading: :func:`load` (HyperFun files, meshes, scans, examples),
:func:`load_hyperfun` (source text). Building: :class:`Shape` operators
``| & - ~``, :func:`union` / :func:`intersection` / :func:`subtraction`
with R-function ``alpha``, blends, primitives (:func:`sphere`, :func:`box`,
:func:`cylinder`, :func:`torus`, :func:`half_space`, :func:`ellipsoid`),
TPMS (:func:`tpms`, :func:`gyroid`, ...), strut lattices (:func:`struts`,
:func:`octet`, ...), irregular pores (:func:`pores`) and :func:`fill` (the
CLI's fill, measured with :func:`fill_report`), graded materials
(:func:`materials` with :class:`Subspace`, Park's material subspaces);
expressions of :data:`x`, :data:`y`, :data:`z` for graded fields. Work:
``Shape.eval / eval_grid / gradient / attributes / mesh / mesh_to_file /
slice / slice_to / render / analyze``; in Jupyter a shape shows a small
rendered image and its bounds, an :class:`AnalysisReport` a table.
Distributed slicing and analysis: :mod:`microfrep.dask`. Errors:
:class:`Error` and its subclasses.
"""

from ._core import (
    AnalysisError,
    BoundsError,
    Error,
    HyperFunError,
    InputError,
    LoadError,
    MemoryLimitError,
    MeshError,
    RenderError,
    SliceError,
    StructureError,
)
from ._model import (
    STRUT_KINDS,
    TPMS_KINDS,
    AnalysisReport,
    Expr,
    Shape,
    acos,
    asin,
    atan,
    bcc,
    binary,
    blend_intersection,
    blend_subtraction,
    blend_union,
    box,
    clamp,
    complement,
    constant,
    cos,
    cylinder,
    diamond,
    ellipsoid,
    examples,
    exp,
    fcc,
    FilledModel,
    fill,
    fill_report,
    fischer_koch_s,
    floor,
    from_expr,
    gyroid,
    half_space,
    intersection,
    kelvin,
    lerp,
    load,
    load_hyperfun,
    log,
    materials,
    maximum,
    minimum,
    neovius,
    octet,
    offset,
    pores,
    rotate,
    sc,
    scale,
    schoen_iwp,
    schwarz_d,
    schwarz_p,
    sin,
    sphere,
    sqrt,
    struts,
    Subspace,
    subtraction,
    tan,
    tanh,
    torus,
    tpms,
    translate,
    unary,
    union,
    var,
    where,
    with_attribute,
    with_bounds,
    x,
    y,
    z,
)

__version__ = "0.1.0"


def threads() -> int:
    """Threads the Rust evaluators use (rayon's pool: all cores, or
    ``RAYON_NUM_THREADS``)."""
    from . import _core

    return _core.threads()


__all__ = [n for n in dir() if not n.startswith("_")]
