"""Models: expressions, shapes and everything that builds them.

Every public constructor records how it was called (its *recipe*: the
function's name and arguments, with shapes and expressions among them as
their own recipes). Pickling a shape or an expression stores that recipe,
never compiled code or a closure, and unpickling calls the same functions
again: this is how a model travels to a Dask worker, which rebuilds it from
its source (a HyperFun model's text, a file path, an example name, the
arguments of a primitive or a lattice).
"""

from __future__ import annotations

import base64
import functools
import html
import json
import math
import os
import threading
from collections import OrderedDict
from typing import Any, Callable, Iterator, Optional, Sequence, Tuple, Union

import numpy as np

from . import _core

Number = Union[int, float]
Field = Union["Expr", int, float]
Box = Tuple[Sequence[float], Sequence[float]]

_REGISTRY: dict = {}


def _recorded(fn: Callable) -> Callable:
    """Registers ``fn`` as a recipe step: its results remember the call."""
    name = fn.__name__

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        out = fn(*args, **kwargs)
        out._recipe = (name, args, kwargs)
        return out

    _REGISTRY[name] = wrapper
    return wrapper


# Rebuilt sources (a mesh's hierarchy, a scan's distance transform, a
# parsed HyperFun file) are kept per process, so a worker that runs many
# tasks of one job builds the model once.
_CACHE: "OrderedDict[str, Any]" = OrderedDict()
_CACHE_LOCK = threading.Lock()
_CACHED = {"_load_hyperfun_text"}


def _replay(name: str, args: tuple, kwargs: dict):
    """Calls recipe step ``name`` again (the unpickler of models)."""
    fn = _REGISTRY.get(name)
    if fn is None:
        raise _core.Error(f"unknown model step '{name}' (a newer microfrep pickled this model?)")
    if name not in _CACHED:
        return fn(*args, **kwargs)
    key = repr((name, args, sorted(kwargs.items())))
    with _CACHE_LOCK:
        hit = _CACHE.get(key)
        if hit is not None:
            _CACHE.move_to_end(key)
            return hit
    out = fn(*args, **kwargs)
    with _CACHE_LOCK:
        _CACHE[key] = out
        while len(_CACHE) > 8:
            _CACHE.popitem(last=False)
    return out


def _vec3(v, what: str) -> Tuple[float, float, float]:
    try:
        t = tuple(float(c) for c in v)
    except TypeError:
        raise _core.InputError(f"{what} must be 3 numbers, got {v!r}") from None
    if len(t) != 3 or not all(math.isfinite(c) for c in t):
        raise _core.InputError(f"{what} must be 3 finite numbers, got {v!r}")
    return t


def _box(bounds: Optional[Box]):
    """``(lo, hi)`` or six numbers ``xmin, ymin, zmin, xmax, ymax, zmax``."""
    if bounds is None:
        return None
    b = list(bounds)
    if len(b) == 6:
        lo, hi = b[:3], b[3:]
    elif len(b) == 2:
        lo, hi = b
    else:
        raise _core.InputError(
            f"bounds must be (lo, hi) or 6 numbers xmin,ymin,zmin,xmax,ymax,zmax, got {bounds!r}"
        )
    return (_vec3(lo, "bounds min"), _vec3(hi, "bounds max"))


def _axis(axis) -> int:
    names = {"x": 0, "y": 1, "z": 2}
    if isinstance(axis, str) and axis in names:
        return names[axis]
    if axis in (0, 1, 2):
        return int(axis)
    raise _core.InputError(f"axis {axis!r}: 'x', 'y', 'z' or 0, 1, 2")


# --------------------------------------------------------------------------
# Expressions


class Expr:
    """A real function of the point ``(x, y, z)``: a field, a density, a
    level, a radius. Built from :data:`x`, :data:`y`, :data:`z`, numbers,
    arithmetic (``+ - * / ** -e abs(e)``) and the functions of this module
    (:func:`sin`, :func:`sqrt`, :func:`minimum`, ...). A shape's value is
    ``shape.value``; :func:`from_expr` makes a shape of an expression."""

    __slots__ = ("_e", "_recipe")

    def __init__(self, e: "_core.Expr"):
        self._e = e
        self._recipe = None

    def __reduce__(self):
        if self._recipe is None:
            raise _core.Error("this expression has no recipe and cannot be pickled")
        return (_replay, self._recipe)

    def __repr__(self):
        c = self._e.as_const()
        return f"Expr({c})" if c is not None else f"Expr(<{self._e.node_count()} nodes>)"

    def _bin(self, op, other, swap=False):
        o = _expr(other)
        return binary(op, o, self) if swap else binary(op, self, o)

    def __add__(self, o):
        return self._bin("add", o)

    def __radd__(self, o):
        return self._bin("add", o, True)

    def __sub__(self, o):
        return self._bin("sub", o)

    def __rsub__(self, o):
        return self._bin("sub", o, True)

    def __mul__(self, o):
        return self._bin("mul", o)

    def __rmul__(self, o):
        return self._bin("mul", o, True)

    def __truediv__(self, o):
        return self._bin("div", o)

    def __rtruediv__(self, o):
        return self._bin("div", o, True)

    def __pow__(self, o):
        if isinstance(o, (int, float)) and o == 2:
            return unary("square", self)
        return self._bin("pow", o)

    def __rpow__(self, o):
        return self._bin("pow", o, True)

    def __mod__(self, o):
        return self._bin("mod", o)

    def __neg__(self):
        return unary("neg", self)

    def __abs__(self):
        return unary("abs", self)

    def __lt__(self, o):
        return self._bin("lt", o)

    def __le__(self, o):
        return self._bin("le", o)

    def __gt__(self, o):
        return self._bin("gt", o)

    def __ge__(self, o):
        return self._bin("ge", o)

    __hash__ = object.__hash__


def _expr(v) -> Expr:
    if isinstance(v, Expr):
        return v
    if isinstance(v, Shape):
        return v.value
    if isinstance(v, (int, float, np.floating, np.integer)) and not isinstance(v, bool):
        return constant(float(v))
    raise _core.InputError(f"expected a number or an Expr, got {type(v).__name__}")


@_recorded
def constant(v: float) -> Expr:
    """A constant expression."""
    return Expr(_core.constant(float(v)))


@_recorded
def var(axis) -> Expr:
    """The coordinate ``axis`` ('x', 'y', 'z' or 0, 1, 2)."""
    return Expr(_core.var(_axis(axis)))


@_recorded
def unary(op: str, a: Expr) -> Expr:
    """``op(a)`` for op in neg, abs, sign, sqrt, square, exp, log, sin, cos,
    tan, asin, acos, atan, sinh, cosh, tanh, floor, ceil, round, fract."""
    return Expr(_core.unary(op, _expr(a)._e))


@_recorded
def binary(op: str, a: Field, b: Field) -> Expr:
    """``a op b`` for op in add, sub, mul, div, pow, min, max, atan2, mod,
    lt, le, gt, ge (comparisons give 1 or 0)."""
    return Expr(_core.binary(op, _expr(a)._e, _expr(b)._e))


@_recorded
def where(cond: Field, a: Field, b: Field) -> Expr:
    """``a`` where ``cond`` is not 0, else ``b``."""
    return Expr(_core.select(_expr(cond)._e, _expr(a)._e, _expr(b)._e))


x = var("x")
y = var("y")
z = var("z")


def _fn(op):
    def f(a: Field) -> Expr:
        return unary(op, _expr(a))

    f.__name__ = op
    f.__doc__ = f"``{op}`` of an expression (or a number)."
    return f


sqrt = _fn("sqrt")
exp = _fn("exp")
log = _fn("log")
sin = _fn("sin")
cos = _fn("cos")
tan = _fn("tan")
asin = _fn("asin")
acos = _fn("acos")
atan = _fn("atan")
tanh = _fn("tanh")
floor = _fn("floor")


def minimum(a: Field, b: Field) -> Expr:
    """Pointwise minimum."""
    return binary("min", a, b)


def maximum(a: Field, b: Field) -> Expr:
    """Pointwise maximum."""
    return binary("max", a, b)


def clamp(a: Field, lo: Field, hi: Field) -> Expr:
    """``a`` held within ``[lo, hi]``."""
    return maximum(minimum(a, hi), lo)


def lerp(a: Field, b: Field, t: Field) -> Expr:
    """``a + (b - a) t``: e.g. a density graded along z."""
    return _expr(a) + (_expr(b) - _expr(a)) * _expr(t)


# --------------------------------------------------------------------------
# Shapes


class Shape:
    """A model (inside is ``f >= 0``, millimetres). Combine with ``|``
    (union), ``&`` (intersection), ``-`` (subtraction) and ``~``
    (complement): HyperFun's R-functions (``alpha = 0``); :func:`union` and
    friends take ``alpha`` (1 gives exact max/min) and blends. Evaluate with :meth:`eval`, mesh with :meth:`mesh`, slice with
    :meth:`slice_to`, measure with :meth:`analyze`. Shapes pickle as their
    recipe (see the module docs), so they can be sent to Dask workers."""

    __slots__ = ("_s", "_recipe", "_preview_cache")

    def __init__(self, s: "_core.Shape"):
        self._s = s
        self._recipe = None
        self._preview_cache = None

    def __reduce__(self):
        if self._recipe is None:
            raise _core.Error("this shape has no recipe and cannot be pickled")
        return (_replay, self._recipe)

    def __repr__(self):
        return f"Shape({self._s.name!r}, kind={self._s.kind!r})"

    # -- operators
    def __or__(self, o: "Shape") -> "Shape":
        return union(self, o)

    def __and__(self, o: "Shape") -> "Shape":
        return intersection(self, o)

    def __sub__(self, o: "Shape") -> "Shape":
        return subtraction(self, o)

    def __invert__(self) -> "Shape":
        return complement(self)

    # -- properties
    @property
    def value(self) -> Expr:
        """The value as an expression (to build on)."""
        e = Expr(self._s.value)
        e._recipe = ("_value_of", (self,), {})
        return e

    @property
    def name(self) -> str:
        """The source this shape came from, or 'model'."""
        return self._s.name

    @property
    def kind(self) -> str:
        """hyperfun, mesh, scan, example or built."""
        return self._s.kind

    @property
    def notes(self) -> list:
        """The loader's warnings (an open mesh, flipped triangles, ...)."""
        return list(self._s.notes)

    @property
    def attribute_names(self) -> list:
        """Names of the attribute channels (HyperFun ``s[k]`` as ``s1``, ...)."""
        return list(self._s.attribute_names)

    def bounds(self) -> Tuple[Tuple[float, float, float], Tuple[float, float, float]]:
        """The box holding the solid: given (an example's, a mesh's), or
        proven by interval arithmetic. Raises :class:`BoundsError` for an
        unbounded model (a lattice alone): intersect it with a part, or
        give bounds to the method that needs them."""
        lo, hi = self._s.bounds()
        return tuple(lo), tuple(hi)

    def with_bounds(self, bounds: Box) -> "Shape":
        """This shape with its box given (skips the interval search)."""
        return with_bounds(self, bounds)

    # -- evaluation
    def eval(self, points, precise: bool = False) -> np.ndarray:
        """Values at ``points`` (an N x 3 array, float32 or float64).

        The batch evaluator runs on all threads with the GIL released and
        returns float32; a C-contiguous float32 array is read in place (in
        cache-sized chunks), as are the columns of a Fortran-order one.
        ``precise=True`` evaluates in float64 with the reference point
        evaluator (the values ``microfrep eval`` prints), about ten times
        slower. NaN marks points where the model is undefined."""
        p = _points(points)
        return self._s.eval_precise(p) if precise else self._s.eval(p)

    def eval_grid(self, bounds: Box, shape: Sequence[int]) -> np.ndarray:
        """Values on a grid of ``shape = (nx, ny, nz)`` nodes from ``lo`` to
        ``hi`` inclusive (as ``numpy.linspace``): ``out[i, j, k]`` is the
        value at ``(x_i, y_j, z_k)``. The result is a view in x-fastest
        memory order (``np.ascontiguousarray`` gives C order)."""
        lo, hi = _box(bounds)
        dims = tuple(int(n) for n in shape)
        if len(dims) != 3:
            raise _core.InputError(f"shape must be (nx, ny, nz), got {shape!r}")
        flat = self._s.eval_grid_flat(lo, hi, dims)
        return flat.reshape(dims[2], dims[1], dims[0]).transpose(2, 1, 0)

    def gradient(self, points) -> np.ndarray:
        """Gradients (N x 3, float32) at ``points`` (forward mode)."""
        return self._s.value_gradient(_points(points))[:, 1:]

    def value_and_gradient(self, points) -> np.ndarray:
        """``[value, dx, dy, dz]`` per point (N x 4, float32)."""
        return self._s.value_gradient(_points(points))

    def attributes(self, points) -> dict:
        """Every attribute channel at ``points``: ``{name: values}``."""
        p = _points(points)
        return {n: self._s.attribute(n, p) for n in self._s.attribute_names}

    # -- fabrication
    def mesh(self, resolution: int = 256, bounds: Optional[Box] = None, cells: str = "cubes"):
        """A closed, manifold triangle mesh: ``(vertices, faces)``, N x 3
        float32 and M x 3 uint32, counter-clockwise seen from outside.
        ``resolution`` cells on the longest side of ``bounds`` (default:
        the model's own); ``cells`` is 'cubes' (marching cubes) or 'tets'."""
        return self._s.mesh(int(resolution), _box(bounds), cells)

    def mesh_to_file(
        self,
        path,
        resolution: int = 256,
        bounds: Optional[Box] = None,
        cells: str = "cubes",
        stream: bool = False,
        sharp: bool = False,
        tolerance: Optional[float] = None,
        tolerance_mm: Optional[float] = None,
    ) -> dict:
        """Meshes into ``path`` (.stl .obj .ply .3mf) as ``microfrep mesh``
        does (streamed to disk when the mesh would not fit in memory, or
        with ``stream``); returns the summary of ``microfrep mesh --json``
        (the same keys). ``sharp`` keeps creases and corners; ``tolerance``
        (in cells) or ``tolerance_mm`` merges flat regions within that
        distance of the surface, as ``--sharp`` and ``--tolerance`` do."""
        s = self._s.mesh_to_file(
            os.fspath(path),
            int(resolution),
            _box(bounds),
            cells,
            stream,
            bool(sharp),
            None if tolerance is None else float(tolerance),
            None if tolerance_mm is None else float(tolerance_mm),
        )
        return json.loads(s)

    def slice(self, layer: float, pixel: float, bounds: Optional[Box] = None, aa: bool = False) -> np.ndarray:
        """All layers as a ``layers x ny x nx`` uint8 array: 255 inside, 0
        outside (8-bit area coverage with ``aa``), image row 0 at the
        largest y, exactly the pixels of the PNG files of :meth:`slice_to`.
        Refused (:class:`MemoryLimitError`) if it would not fit in memory:
        use :meth:`iter_slices` or :meth:`slice_to`."""
        return self._s.slice_array(float(layer), float(pixel), _box(bounds), aa)

    def iter_slices(
        self, layer: float, pixel: float, bounds: Optional[Box] = None, aa: bool = False, batch: int = 16
    ) -> Iterator[Tuple[float, np.ndarray]]:
        """Yields ``(z, image)`` per layer (``ny x nx`` uint8), computing
        ``batch`` layers at a time on all threads."""
        b = _box(bounds)
        layers, _, _, lo, hi = self._s.slice_grid(float(layer), float(pixel), b)
        b = (tuple(lo), tuple(hi))
        for k0 in range(0, layers, batch):
            k1 = min(layers, k0 + batch)
            arr = self._s.slice_array(float(layer), float(pixel), b, aa, k0, k1)
            for i in range(k1 - k0):
                yield lo[2] + (k0 + i + 0.5) * float(layer), arr[i]

    def slice_to(
        self,
        path,
        layer: float = 0.05,
        pixel: float = 0.025,
        format: str = "png",
        bounds: Optional[Box] = None,
        aa: bool = False,
    ) -> dict:
        """Writes a printer stack as ``microfrep slice`` does: a directory
        of PNG (or SVG) layers and ``manifest.json``, or one Common Layer
        Interface file (``format='cli'``, a ``.cli`` path); the same bytes
        as the CLI, written under a temporary name and renamed when done.
        Returns the summary of ``microfrep slice --json``."""
        s = self._s.slice_to(os.fspath(path), float(layer), float(pixel), _box(bounds), format, aa)
        return json.loads(s)

    def render(
        self,
        size: Sequence[int] = (1024, 768),
        view: str = "iso",
        bounds: Optional[Box] = None,
        cutaway: bool = False,
        section=None,
    ) -> np.ndarray:
        """A ray-cast image (``height x width x 3`` uint8) seen from
        ``view`` (iso, front, top, side); ``cutaway`` removes the octant
        nearest the viewer; ``section='z=0.5'`` (or ``('z', 0.5)``) shows the
        value on that plane instead."""
        w, h = (int(v) for v in size)
        sec = None
        if section is not None:
            if isinstance(section, str):
                a, _, v = section.partition("=")
                try:
                    sec = (_axis(a.strip()), float(v))
                except ValueError:
                    raise _core.InputError(f"section '{section}': expected x=V, y=V or z=V") from None
            else:
                a, v = section
                sec = (_axis(a), float(v))
        return self._s.render(w, h, view, _box(bounds), cutaway, sec)

    def analyze(
        self,
        resolution: Optional[int] = None,
        voxel: Optional[float] = None,
        bounds: Optional[Box] = None,
        region: Optional["Shape"] = None,
        connectivity: bool = True,
        thickness: bool = True,
    ) -> dict:
        """Volume, volume fraction and porosity (inside ``region`` if
        given), surface area, specific surface, each with an error
        estimate; components, open-pore fraction, closed cavities,
        percolation, Euler characteristic; local thickness and pore size.
        The dict has the keys of ``microfrep analyze --json``. Default 256
        voxels on the longest side of the box."""
        r = region._s if region is not None else None
        s = self._s.analyze(resolution, voxel, _box(bounds), r, connectivity, thickness)
        return AnalysisReport(json.loads(s))

    # -- notebook display (IPython, Jupyter)
    def render_png(self, size: Sequence[int] = (256, 256), view: str = "iso", bounds: Optional[Box] = None) -> bytes:
        """The image of :meth:`render` as the bytes of a PNG file."""
        w, h = (int(v) for v in size)
        return self._s.render_png(w, h, view, _box(bounds))

    def _preview(self):
        """``(png or None, bounds or None, why no image or None)`` for the
        notebook display, computed once per shape; never raises: a shape
        without bounds, or one that cannot be rendered, is described."""
        cached = getattr(self, "_preview_cache", None)
        if cached is not None:
            return cached
        png, box, why = None, None, None
        try:
            lo, hi = self.bounds()
        except _core.BoundsError:
            why = (
                "bounds unknown: interval analysis cannot bound this model (it may be unbounded, "
                "like a bare lattice); give them with shape.with_bounds((lo, hi)) to see it"
            )
        except Exception as e:  # the display must not fail
            why = f"bounds unknown: {type(e).__name__}: {e}"
        else:
            box = (lo, hi)
            if not all(math.isfinite(v) for v in lo + hi):
                why = "bounds are not finite; give them with shape.with_bounds((lo, hi)) to see it"
            else:
                try:
                    png = self._s.render_png(_PREVIEW_SIZE, _PREVIEW_SIZE, "iso", box)
                except Exception as e:
                    why = f"no image: {type(e).__name__}: {e}"
        out = (png, box, why)
        try:
            self._preview_cache = out
        except AttributeError:
            pass
        return out

    def _repr_png_(self) -> Optional[bytes]:
        """A 256 x 256 iso view for IPython (None when there is none)."""
        return self._preview()[0]

    def _repr_html_(self) -> str:
        """The iso view and the bounds for Jupyter; a shape without bounds
        shows why there is no image."""
        png, box, why = self._preview()
        title = f"Shape {html.escape(repr(self.name))} ({html.escape(self.kind)})"
        if box is None:
            line = f"{title}: {html.escape(why)}"
        else:
            (x0, y0, z0), (x1, y1, z1) = box
            line = (
                f"{title}: bounds x {_num(x0)} .. {_num(x1)}, y {_num(y0)} .. {_num(y1)}, "
                f"z {_num(z0)} .. {_num(z1)} mm (size {_num(x1 - x0)} x {_num(y1 - y0)} x {_num(z1 - z0)})"
            )
            if why is not None:
                line += f"; {html.escape(why)}"
        img = ""
        if png is not None:
            b64 = base64.b64encode(png).decode("ascii")
            img = (
                f'<img src="data:image/png;base64,{b64}" width="{_PREVIEW_SIZE}" '
                f'height="{_PREVIEW_SIZE}" alt="{html.escape(self.name)}"/><br/>'
            )
        return f'<div class="microfrep-shape">{img}<span style="font-family: monospace">{line}</span></div>'


_PREVIEW_SIZE = 256


def _num(v) -> str:
    """A number as the CLI's reports print it: 7 significant digits."""
    if v is None:
        return "undefined"
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, int):
        return str(v)
    v = float(v)
    if math.isnan(v):
        return "undefined"
    return f"{v:.7g}"


def _pm(d, unit: str = "") -> str:
    """``{"value", "error"}`` as ``value ± error unit``."""
    v, e = d.get("value"), d.get("error")
    if v is None:
        return "undefined"
    out = _num(v)
    if e is not None and not (isinstance(e, float) and math.isnan(e)):
        out += f" ± {float(e):.2e}"
    return f"{out} {unit}".rstrip()


class AnalysisReport(dict):
    """What :meth:`Shape.analyze` returns: the dict of ``microfrep analyze
    --json``, shown in Jupyter as a table with one row per figure
    (:meth:`figures`) and the report's notes."""

    def figures(self) -> list:
        """``(figure, value, note)`` rows, in the order of the CLI's text
        report: volumes, fractions and area; connectivity and thickness
        when measured; then each attribute."""
        rows = []
        within = f"inside region {self['region']}" if self.get("region") else "the bounds"
        rows.append(("Volume", _pm(self["volume"], "mm³"), f"of the solid, {within}"))
        rows.append(("Region volume", _pm(self["region_volume"], "mm³"), within))
        rows.append(("Volume fraction", _pm(self["volume_fraction"]), "solid / region"))
        rows.append(("Porosity", _pm(self["porosity"]), "1 - volume fraction"))
        rows.append(("Surface area", _pm(self["area"], "mm²"), ""))
        rows.append(("Specific surface", _pm(self["specific_surface"], "1/mm"), "area / volume"))
        c = self.get("connectivity")
        if c:
            others = sum(c["solid_volumes"][1:])
            rows.append(
                ("Solid components", _num(c["solid_components"]), f"26-connected; volume outside the largest {_num(others)} mm³")
            )
            rows.append(("Pore components", _num(c["pore_components"]), "6-connected"))
            rows.append(
                ("Open pore fraction", _num(c["open_pore_fraction"]), "of the pore volume, open to the outside")
            )
            rows.append(("Closed pores", _num(c["closed_pores"]), f"volume {_num(c['closed_pore_volume'])} mm³"))
            p = c["percolates"]
            rows.append(("Percolation", ", ".join(f"{a} {_num(bool(p[a]))}" for a in "xyz"), "a pore component touches both faces of the box"))
            rows.append(("Euler characteristic", _num(c["euler_solid"]), f"of the solid; {_num(c['euler_surface'])} of its surface"))
        t = self.get("thickness")
        if t:
            for key, name in (("solid", "Thickness"), ("pore", "Pore size")):
                ph = t.get(key)
                if ph == "skipped" or ph is None:
                    continue
                if ph == "empty":
                    rows.append((name, "none", "empty phase"))
                elif ph.get("unbounded"):
                    rows.append((name, "unbounded", "the phase fills the grid"))
                else:
                    rows.append(
                        (
                            name,
                            f"mean {_num(ph['mean'])} mm",
                            f"median {_num(ph['median'])}, p10 {_num(ph['p10'])}, p90 {_num(ph['p90'])}, "
                            f"max {_num(ph['max'])} (local thickness, voxel {_num(t['voxel'])})",
                        )
                    )
        for a in self.get("attributes") or []:
            rows.append(
                (
                    f"Attribute {a['name']}",
                    f"mean {_num(a['mean'])}",
                    f"min {_num(a['min'])}, max {_num(a['max'])}, integral {_pm(a['integral'])}",
                )
            )
        return rows

    def _repr_html_(self) -> str:
        e = html.escape
        nx, ny, nz = self["dims"]
        (x0, y0, z0), (x1, y1, z1) = self["bounds"]
        vx = self["voxel"]
        caption = (
            f"analysis of {e(str(self.get('model')))}: {nx} x {ny} x {nz} voxels of "
            f"{' x '.join(_num(v) for v in vx)} mm in x {_num(x0)} .. {_num(x1)}, "
            f"y {_num(y0)} .. {_num(y1)}, z {_num(z0)} .. {_num(z1)}"
        )
        body = "".join(
            f"<tr><th style=\"text-align: left\">{e(f)}</th><td style=\"text-align: right\">{e(v)}</td>"
            f"<td style=\"text-align: left\">{e(n)}</td></tr>"
            for f, v, n in self.figures()
        )
        notes = "".join(f"<li>{e(str(n))}</li>" for n in self.get("notes") or [])
        return (
            f'<table class="microfrep-analysis"><caption>{caption}</caption>'
            f"<thead><tr><th>figure</th><th>value</th><th>note</th></tr></thead>"
            f"<tbody>{body}</tbody></table>" + (f"<ul>{notes}</ul>" if notes else "")
        )


def _points(points) -> np.ndarray:
    """``points`` as an array the evaluators read: integers and other
    real floats are converted to float64, a single point ``(3,)`` becomes
    one row; what is left wrong (the number of dimensions, the last axis)
    is reported by the Rust side, which names the problem."""
    if isinstance(points, np.ndarray):
        a = points
    else:
        try:
            a = np.asarray(points)
        except (ValueError, TypeError) as e:
            raise _core.InputError(
                f"points: cannot be made into an N x 3 array of numbers ({e}): "
                "give rows of 3 coordinates, all of the same length"
            ) from None
    if a.dtype != np.float32 and a.dtype != np.float64:
        if a.dtype.kind == "c":
            raise _core.InputError(f"points: dtype {a.dtype} (complex), expected real numbers (float32 or float64)")
        if a.dtype.kind not in "iuf":
            raise _core.InputError(
                f"points: dtype {a.dtype}, expected numbers (float32 or float64; integers are converted)"
            )
        a = a.astype(np.float64)
    elif not a.flags.aligned:
        a = a.copy()
    if a.ndim == 1 and a.shape[0] == 3:
        a = a.reshape(1, 3)
    return a


def _shape(s) -> Shape:
    if isinstance(s, Shape):
        return s
    if isinstance(s, Expr):
        return from_expr(s)
    raise _core.InputError(f"expected a Shape, got {type(s).__name__}")


@_recorded
def _value_of(s: Shape) -> Expr:
    return Expr(s._s.value)


@_recorded
def from_expr(e: Field, bounds: Optional[Box] = None) -> Shape:
    """A shape whose value is the expression ``e`` (inside where ``e >= 0``)."""
    s = _core.shape(_expr(e)._e)
    b = _box(bounds)
    if b is not None:
        s = s.with_bounds(*b)
    return Shape(s)


@_recorded
def with_bounds(s: Shape, bounds: Box) -> Shape:
    """``s`` with its box given."""
    lo, hi = _box(bounds)
    return Shape(s._s.with_bounds(lo, hi))


@_recorded
def with_attribute(s: Shape, name: str, value: Field) -> Shape:
    """``s`` with an attribute channel (a material fraction, a density)."""
    return Shape(s._s.with_attribute(str(name), _expr(value)._e))


# -- graded materials (Park et al.)


class Subspace:
    """A material subspace (Park, Crawford, Beaman, Sec. 2.3 and 3.1): a
    graded region with its own local coordinates ``u, v, w``, holding the
    fraction of one material written in those coordinates (``x``, ``y``,
    ``z`` of ``fraction`` stand for ``u``, ``v``, ``w``), the rest of the
    region being its ``base`` material (default: the model's primary).
    Materials count from 1, like the attributes ``s1, s2, ...``.

    ``Subspace(region, fraction, material, local=(x, y, z))`` is the
    general form (``region >= 0`` inside, ``local`` three expressions of
    the part point); :meth:`below_surface` and :meth:`in_box` are the
    paper's two kinds. Combine them with :func:`materials`."""

    def __init__(self, region: Field, fraction: Field, material: int, base: Optional[int] = None, local=None):
        self._kind = "general"
        self._args = (_expr(region), tuple(_expr(e) for e in (local or (x, y, z))))
        if len(self._args[1]) != 3:
            raise _core.InputError("Subspace: local must be three expressions (u, v, w)")
        self._fraction = _expr(fraction)
        self.material = _material_number(material, "material")
        self.base = None if base is None else _material_number(base, "base")

    @classmethod
    def below_surface(
        cls,
        depth: Field,
        depth_from: float,
        depth_to: float,
        fraction: Field,
        material: int,
        base: Optional[int] = None,
        uv=None,
    ) -> "Subspace":
        """The layer below a reference surface from ``depth_from`` down
        (``depth`` the depth below the surface, e.g. a distance), graded
        over ``depth_from .. depth_to``: ``w = clamp((depth - depth_from) /
        (depth_to - depth_from), 0, 1)``, ``u, v`` given by ``uv`` (default
        the part's ``x, y``). Above ``depth_from`` is a shell of constant
        depth of the base material."""
        if not float(depth_to) > float(depth_from):
            raise _core.InputError(f"Subspace.below_surface: depth_to {depth_to} must be greater than depth_from {depth_from}")
        s = cls.__new__(cls)
        s._kind = "depth"
        uv = tuple(_expr(e) for e in (uv or (x, y)))
        if len(uv) != 2:
            raise _core.InputError("Subspace.below_surface: uv must be two expressions")
        s._args = (_expr(depth), float(depth_from), float(depth_to) - float(depth_from), uv)
        s._fraction = _expr(fraction)
        s.material = _material_number(material, "material")
        s.base = None if base is None else _material_number(base, "base")
        return s

    @classmethod
    def in_box(cls, lo: Sequence[float], hi: Sequence[float], fraction: Field, material: int, base: Optional[int] = None) -> "Subspace":
        """The box ``lo .. hi`` mapped to local coordinates ``[0, 1]^3`` (the
        domain of a Bezier box field on the unit cube)."""
        s = cls.__new__(cls)
        s._kind = "box"
        s._args = (_vec3(lo, "lo"), _vec3(hi, "hi"))
        s._fraction = _expr(fraction)
        s.material = _material_number(material, "material")
        s.base = None if base is None else _material_number(base, "base")
        return s

    def __repr__(self):
        return f"Subspace({self._kind}, material={self.material}, base={self.base})"

    def _core(self) -> "_core.Subspace":
        m = self.material - 1
        b = None if self.base is None else self.base - 1
        f = self._fraction._e
        if self._kind == "general":
            region, local = self._args
            return _core.subspace(region._e, tuple(e._e for e in local), f, m, b)
        if self._kind == "depth":
            depth, start, ramp, uv = self._args
            return _core.subspace_below_surface(depth._e, start, ramp, tuple(e._e for e in uv), f, m, b)
        lo, hi = self._args
        return _core.subspace_in_box(list(lo), list(hi), f, m, b)


def _material_number(m, what: str) -> int:
    if isinstance(m, bool) or not isinstance(m, (int, np.integer)) or m < 1:
        raise _core.InputError(f"{what} must be a material number from 1, not {m!r}")
    return int(m)


@_recorded
def materials(part: Shape, count: int, subspaces: Sequence[Subspace] = (), primary: int = 1) -> Shape:
    """``part`` with one attribute per material, ``s1 .. s{count}``, its
    volume fractions (Park's material model): material ``primary`` fills
    the part and each :class:`Subspace` is laid over it in order, a later
    one overriding an earlier one where they overlap. Inside the part the
    fractions lie in [0, 1] and sum to 1; outside they are 0. Attributes
    the part already has are kept, the new ones follow them."""
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or not 1 <= count <= 255:
        raise _core.InputError(f"materials: count must be 1 to 255, not {count!r}")
    primary = _material_number(primary, "primary")
    if primary > count:
        raise _core.InputError(f"materials: primary material {primary} is not one of 1..{count}")
    subs = list(subspaces)
    for i, sub in enumerate(subs):
        if not isinstance(sub, Subspace):
            raise _core.InputError(f"materials: subspace {i + 1} is a {type(sub).__name__}, not a Subspace")
        for what, m in (("material", sub.material), ("base", sub.base)):
            if m is not None and m > count:
                raise _core.InputError(f"materials: subspace {i + 1}: {what} {m} is not one of 1..{count}")
        if (sub.base or primary) == sub.material:
            raise _core.InputError(f"materials: subspace {i + 1}: graded and base material are both {sub.material}")
    part = _shape(part)
    fr = _core.material_fractions(part._s.value, int(count), primary - 1, [s._core() for s in subs])
    out = part._s
    for k, e in enumerate(fr):
        out = out.with_attribute(f"s{k + 1}", e)
    return Shape(out)


# -- loading


def load(path, object: Optional[str] = None, params=None, fields=None) -> Shape:
    """Loads a model: a HyperFun file (``.hf``), a mesh (``.stl .obj .ply
    .3mf``, options ``:weld=TOL,sign=auto|winding|normal``), a scan
    (``.nrrd .nii .nii.gz .tif .raw`` or a folder of slices, with
    ``:iso=V``), or a built-in example name (:func:`examples`).

    HyperFun options: ``object`` (default ``my_model``, else the first),
    ``params`` for ``a[k]`` (a dict ``{k: v}`` with 1-based k, or a list of
    values for a[1], a[2], ...), ``fields`` binding sources as functions
    ``NAME(x)`` (``{"bone": "femur.stl"}``), as the CLI's ``--field``.
    Errors raise :class:`HyperFunError` (file:line:col with the source line
    and a caret) or :class:`LoadError`."""
    spec = os.fspath(path)
    ps = _params(params)
    fs = [(str(k), os.fspath(v)) for k, v in (fields or {}).items()]
    if not fs and spec.lower().endswith(".hf") and os.path.isfile(spec):
        try:
            with open(spec, encoding="utf-8") as f:
                text = f.read()
        except UnicodeDecodeError as e:
            raise _core.LoadError(f"{spec}: {e}") from None
        except OSError as e:
            raise _core.LoadError(f"{spec}: {e.strerror}") from None
        return _load_hyperfun_text(text, spec, object, ps)
    return _load(spec, object, ps, fs)


def _params(params):
    if params is None:
        return []
    if isinstance(params, dict):
        return [(int(k), float(v)) for k, v in params.items()]
    return [(i + 1, float(v)) for i, v in enumerate(params)]


@_recorded
def _load(spec: str, object, params, fields) -> Shape:
    return Shape(_core.load(spec, object, list(params), list(fields)))


_CACHED.add("_load")


@_recorded
def _load_hyperfun_text(text: str, file: str, object, params) -> Shape:
    return Shape(_core.load_hyperfun_text(text, file, object, list(params)))


def load_hyperfun(text: str, name: str = "<string>", object: Optional[str] = None, params=None) -> Shape:
    """A HyperFun model from its source text; ``name`` names it in error
    messages (``name:line:col``)."""
    return _load_hyperfun_text(text, name, object, _params(params))


def examples() -> dict:
    """The built-in example models: ``{name: description}``."""
    return dict(_core.examples())


# -- set operations


def _alpha(a) -> "_core.Expr":
    return _expr(a)._e


@_recorded
def union(a: Shape, b: Shape, alpha: Field = 0.0) -> Shape:
    """R-function union ``(f1 + f2 + sqrt(f1^2 + f2^2 - 2 alpha f1 f2)) /
    (1 + alpha)``: ``alpha = 0`` (the default) is HyperFun's ``|``, smooth
    where the operands meet; ``alpha = 1`` is exactly ``max``."""
    return Shape(_core.shape(_core.set_op("union", _shape(a).value._e, _shape(b).value._e, _alpha(alpha))))


@_recorded
def intersection(a: Shape, b: Shape, alpha: Field = 0.0) -> Shape:
    """R-function intersection: ``alpha = 0`` is HyperFun's ``&``,
    ``alpha = 1`` exactly ``min``."""
    return Shape(
        _core.shape(_core.set_op("intersection", _shape(a).value._e, _shape(b).value._e, _alpha(alpha)))
    )


@_recorded
def subtraction(a: Shape, b: Shape, alpha: Field = 0.0) -> Shape:
    """R-function subtraction ``a \\ b``."""
    return Shape(
        _core.shape(_core.set_op("subtraction", _shape(a).value._e, _shape(b).value._e, _alpha(alpha)))
    )


@_recorded
def complement(a: Shape) -> Shape:
    """Everything outside ``a`` (``-f``)."""
    return Shape(_core.shape(_core.unary("neg", _shape(a).value._e)))


def _blend(op):
    def f(a: Shape, b: Shape, a0: Field = 1.0, a1: Field = 1.0, a2: Field = 1.0, alpha: Field = 0.0) -> Shape:
        e = _core.blend_op(
            op,
            _shape(a).value._e,
            _shape(b).value._e,
            _expr(a0)._e,
            _expr(a1)._e,
            _expr(a2)._e,
            _alpha(alpha),
        )
        return Shape(_core.shape(e))

    f.__name__ = f"blend_{op}"
    f.__doc__ = (
        f"Blended {op} (Pasko): the R-function {op} plus the displacement "
        "``a0 / (1 + (f1/a1)^2 + (f2/a2)^2)``: ``a0`` sets the blend's size, "
        "``a1`` and ``a2`` its reach along each operand."
    )
    return _recorded(f)


blend_union = _blend("union")
blend_intersection = _blend("intersection")
blend_subtraction = _blend("subtraction")


@_recorded
def offset(a: Shape, d: Field) -> Shape:
    """``f + d``: grown by ``d`` where ``f`` is a distance (meshes, scans,
    struts), a level shift elsewhere."""
    return Shape(_core.shape(_core.binary("add", _shape(a).value._e, _expr(d)._e)))


# -- transforms


def _remap(s: Shape, px, py, pz) -> Shape:
    return Shape(_core.shape(_core.remap(s.value._e, (px._e, py._e, pz._e))))


@_recorded
def translate(s: Shape, v: Sequence[float]) -> Shape:
    """``s`` moved by ``v``."""
    t = _vec3(v, "translation")
    return _remap(_shape(s), x - t[0], y - t[1], z - t[2])


@_recorded
def scale(s: Shape, f) -> Shape:
    """``s`` scaled about the origin by ``f`` (a number or 3 numbers; the
    value is not rescaled)."""
    k = (float(f),) * 3 if isinstance(f, (int, float)) else _vec3(f, "scale")
    if any(c == 0 for c in k):
        raise _core.InputError(f"scale {f!r} must not be 0")
    return _remap(_shape(s), x / k[0], y / k[1], z / k[2])


@_recorded
def rotate(s: Shape, axis, degrees: float) -> Shape:
    """``s`` rotated about ``axis`` ('x', 'y', 'z') by ``degrees``
    (counter-clockwise looking down the axis)."""
    a = _axis(axis)
    t = math.radians(float(degrees))
    c, sn = math.cos(t), math.sin(t)
    p = [x, y, z]
    i, j = [(1, 2), (2, 0), (0, 1)][a]
    q = list(p)
    # The inverse rotation of the point.
    q[i] = c * p[i] + sn * p[j]
    q[j] = -sn * p[i] + c * p[j]
    return _remap(_shape(s), *q)


# -- primitives


def _prim(name, c, v=None, axis=0, r=None, r2=None, bounds=None) -> Shape:
    e = _core.primitive(
        name,
        _vec3(c, "centre"),
        None if v is None else _vec3(v, "size"),
        axis,
        None if r is None else _expr(r)._e,
        None if r2 is None else _expr(r2)._e,
    )
    s = _core.shape(e)
    if bounds is not None:
        s = s.with_bounds(*bounds)
    return Shape(s)


@_recorded
def sphere(center: Sequence[float] = (0, 0, 0), radius: Field = 1.0) -> Shape:
    """Ball ``r^2 - |p - c|^2``."""
    c = _vec3(center, "centre")
    b = None
    if isinstance(radius, (int, float)):
        r = float(radius)
        if not r > 0:
            raise _core.InputError(f"sphere: radius {radius} must be > 0")
        b = (tuple(v - r for v in c), tuple(v + r for v in c))
    return _prim("sphere", c, r=radius, bounds=b)


@_recorded
def box(min: Sequence[float], max: Sequence[float]) -> Shape:
    """Axis-aligned box from corner ``min`` to corner ``max`` (HyperFun's
    hfBlock)."""
    lo, hi = _vec3(min, "box min"), _vec3(max, "box max")
    size = tuple(h - l for l, h in zip(lo, hi))
    if any(s <= 0 for s in size):
        raise _core.InputError(f"box: min {lo} must be below max {hi} on every axis")
    return _prim("box", lo, v=size, bounds=(lo, hi))


@_recorded
def cylinder(center: Sequence[float] = (0, 0, 0), axis="z", radius: Field = 1.0) -> Shape:
    """Infinite cylinder along ``axis`` through ``center`` (intersect with a
    box or half-spaces to cap it)."""
    return _prim("cylinder", center, axis=_axis(axis), r=radius)


@_recorded
def torus(center: Sequence[float] = (0, 0, 0), axis="z", major: Field = 1.0, minor: Field = 0.25) -> Shape:
    """Torus about ``axis`` with radii ``major`` (of the centre circle) and
    ``minor`` (of the tube)."""
    return _prim("torus", center, axis=_axis(axis), r=major, r2=minor)


@_recorded
def ellipsoid(center: Sequence[float] = (0, 0, 0), axes: Sequence[float] = (1, 1, 1)) -> Shape:
    """Ellipsoid with semi-axes ``axes``."""
    return _prim("ellipsoid", center, v=axes)


@_recorded
def half_space(point: Sequence[float], normal: Sequence[float]) -> Shape:
    """The half-space behind the plane through ``point`` with outward
    ``normal``."""
    return _prim("half_space", point, v=normal)


# -- microstructures

TPMS_KINDS = ("gyroid", "schwarz-p", "schwarz-d", "neovius", "schoen-iwp", "fischer-koch-s")
STRUT_KINDS = ("sc", "bcc", "fcc", "octet", "kelvin", "diamond")


def _density(d):
    if isinstance(d, (int, float)) and not isinstance(d, bool):
        d = float(d)
        if not 0.0 < d < 1.0:
            raise _core.InputError(f"density {d} must be between 0 and 1 (exclusive)")
        return d
    return _expr(d)


@_recorded
def tpms(
    kind: str,
    cell: Field,
    level: Optional[Field] = None,
    density: Optional[Field] = None,
    solid: str = "network",
) -> Shape:
    """A triply periodic minimal surface solid (``kind`` in
    :data:`TPMS_KINDS`) with cells of size ``cell``: a network solid
    ``f < level`` or a sheet ``|f| < level`` (``solid='sheet'``). Give the
    ``level`` directly, or the target volume fraction ``density`` (a number,
    solved once per process, or an expression of x, y, z for a graded
    structure, interpolated between solved densities). Unbounded: intersect
    it with a part (:func:`fill`)."""
    if (level is None) == (density is None):
        if level is None and density is None:
            level = 0.0
        else:
            raise _core.InputError("tpms: give level or density, not both")
    kind = kind.replace("_", "-")
    if density is not None:
        d = _density(density)
        if isinstance(d, float):
            level = _core.tpms_level(kind, solid, d)
        else:
            level = Expr(_core.graded_level("tpms", kind, d._e, solid))
    return Shape(_core.shape(_core.tpms_solid(kind, solid, _expr(cell)._e, _expr(level)._e)))


def _tpms_named(kind):
    def f(cell: Field, level: Optional[Field] = None, density: Optional[Field] = None, sheet: bool = False) -> Shape:
        return tpms(kind, cell, level=level, density=density, solid="sheet" if sheet else "network")

    f.__name__ = kind.replace("-", "_")
    f.__doc__ = f"The {kind} TPMS solid: see :func:`tpms` (``sheet=True`` for the sheet solid)."
    return f


gyroid = _tpms_named("gyroid")
schwarz_p = _tpms_named("schwarz-p")
schwarz_d = _tpms_named("schwarz-d")
neovius = _tpms_named("neovius")
schoen_iwp = _tpms_named("schoen-iwp")
fischer_koch_s = _tpms_named("fischer-koch-s")


@_recorded
def struts(kind: str, cell: Field, radius: Optional[Field] = None, density: Optional[Field] = None) -> Shape:
    """A strut lattice (``kind`` in :data:`STRUT_KINDS`) of cubic cells of
    size ``cell``: capsules of ``radius`` (length units) between its nodes,
    or the radius that gives volume fraction ``density`` (a number, or an
    expression for a graded lattice). Unbounded: intersect it with a part."""
    if (radius is None) == (density is None):
        raise _core.InputError("struts: give radius or density (one of them)")
    kind = kind.replace("_", "-")
    if density is not None:
        d = _density(density)
        if isinstance(d, float):
            r = _core.strut_radius(kind, d) * _expr(cell)
        else:
            r = Expr(_core.graded_level("struts", kind, d._e)) * _expr(cell)
    else:
        r = _expr(radius)
    return Shape(_core.shape(_core.strut_solid(kind, _expr(cell)._e, r._e)))


def _struts_named(kind):
    def f(cell: Field, radius: Optional[Field] = None, density: Optional[Field] = None) -> Shape:
        return struts(kind, cell, radius=radius, density=density)

    f.__name__ = kind
    f.__doc__ = f"The {kind} strut lattice: see :func:`struts`."
    return f


sc = _struts_named("sc")
bcc = _struts_named("bcc")
fcc = _struts_named("fcc")
octet = _struts_named("octet")
kelvin = _struts_named("kelvin")
diamond = _struts_named("diamond")


@_recorded
def pores(
    part: Shape,
    cell: Optional[float] = None,
    density: Field = None,
    seed: int = 1,
    bounds: Optional[Box] = None,
    irregularity: Optional[float] = None,
    parent_scale: Optional[float] = None,
    subdivision: Optional[str] = None,
    opening: Optional[float] = None,
    pore_t=None,
    volume_per_pore: Optional[float] = None,
) -> "FilledModel":
    """Irregular pores (Kou and Tan) in ``part``: cells of edge ``cell``,
    each with a pore made so that the part keeps relative density
    ``density`` (a number, or an expression for graded pores); ``seed``
    fixes the randomness. ``bounds`` default to the part's. The paper's
    controls, as :func:`fill` takes them: ``irregularity``,
    ``parent_scale``, ``subdivision`` ('octree' or 'tmesh'), ``opening``,
    ``pore_t``; ``volume_per_pore`` (the paper's m/P, mm^3) sizes the
    cells instead of ``cell`` (cells of edge its cube root).
    The same as ``fill(part, "irregular", cell, density, seed=seed, ...)``."""
    if (cell is None) == (volume_per_pore is None):
        raise _core.InputError("pores: give cell= or volume_per_pore=, one of them")
    if volume_per_pore is not None:
        v = float(volume_per_pore)
        if not (np.isfinite(v) and v > 0):
            raise _core.InputError(f"pores: volume_per_pore {volume_per_pore!r} must be a positive volume (mm^3)")
        cell = float(np.cbrt(v))  # as the CLI computes it (libm cbrt)
    if density is None:
        raise _core.InputError("pores: give a density (the part's solid fraction)")
    return fill(
        part,
        "irregular",
        cell,
        density,
        seed=seed,
        bounds=bounds,
        irregularity=irregularity,
        parent_scale=parent_scale,
        subdivision=subdivision,
        opening=opening,
        pore_t=pore_t,
    )


class FilledModel(Shape):
    """What :func:`fill` returns: the filled model, a :class:`Shape` like
    any other (evaluate, mesh, slice, analyze it), that also holds the fill
    it was built from: :meth:`report` measures it as ``microfrep fill``
    does, :meth:`hyperfun` writes it as ``microfrep fill -o model.hf``."""

    __slots__ = ("_filled",)

    def __init__(self, filled: "_core.Filled"):
        super().__init__(filled.model)
        self._filled = filled

    @property
    def notes(self) -> list:
        """Warnings of the part and the fill."""
        return list(self._filled.notes)

    @property
    def structure(self) -> str:
        """The structure's name as the CLI prints it ('gyroid sheet', ...)."""
        return self._filled.structure

    @property
    def design(self) -> dict:
        """Designed sizes known in closed form: ``strut_radius`` (a
        constant-density strut lattice) and ``pores`` / ``dropped_cells``
        (irregular pores), else None."""
        r, p = self._filled.design
        return {
            "strut_radius": r,
            "pores": None if p is None else p[0],
            "dropped_cells": None if p is None else p[1],
        }

    @property
    def binding(self) -> Optional[Tuple[str, str]]:
        """``(name, source)`` to bind when loading :meth:`hyperfun`'s text
        (``mf.load(path, fields=[binding])``) for a mesh or scan part."""
        b = self._filled.binding
        return None if b is None else tuple(b)

    @property
    def core(self) -> Shape:
        """The part below the skin (the part itself without a skin)."""
        return _fill_component(self, "core")

    @property
    def infill(self) -> Shape:
        """The structure alone inside the core."""
        return _fill_component(self, "infill")

    @property
    def skin(self) -> Optional[Shape]:
        """The skin alone, or None."""
        return None if self._filled.skin is None else _fill_component(self, "skin")

    def hyperfun(self) -> str:
        """The model as HyperFun source, the text ``microfrep fill ... -o
        model.hf`` writes: loading it gives the same values (a mesh or scan
        part is called as ``part(x)``: bind it with :attr:`binding`)."""
        return self._filled.hyperfun()

    def report(
        self,
        voxels_across: Optional[float] = None,
        min_boxes: Optional[int] = None,
        max_boxes: Optional[int] = None,
        target_error: Optional[float] = None,
        thickness_boxes: Optional[int] = None,
        connectivity_voxels: Optional[int] = None,
        rays: Optional[int] = None,
    ) -> dict:
        """Measures what was built, as ``microfrep fill`` does (the same
        defaults): infill density with its error, skin thickness along
        normals, thinnest wall or strut and pore size (local thickness),
        solid components, open pores and whether the skin seals them. The
        dict has the keys of ``microfrep fill --json`` except ``output`` and
        ``written``; ``measured`` says where and at what voxel it measured
        and how long it took (``seconds``)."""
        s = self._filled.measure(
            voxels_across=None if voxels_across is None else float(voxels_across),
            min_boxes=None if min_boxes is None else int(min_boxes),
            max_boxes=None if max_boxes is None else int(max_boxes),
            target_error=None if target_error is None else float(target_error),
            thickness_boxes=None if thickness_boxes is None else int(thickness_boxes),
            connectivity_voxels=None if connectivity_voxels is None else int(connectivity_voxels),
            rays=None if rays is None else int(rays),
        )
        return json.loads(s)


@_recorded
def _fill_component(model: FilledModel, which: str) -> Shape:
    return Shape(getattr(model._filled, which))


def fill_report(model: FilledModel, **options) -> dict:
    """The measured report of a filled model: ``model.report(**options)``
    (see :meth:`FilledModel.report`)."""
    if not isinstance(model, FilledModel):
        raise _core.InputError(
            f"fill_report takes what mf.fill (or mf.pores) returned, got {type(model).__name__}"
        )
    return model.report(**options)


def _grade(g) -> Tuple[float, float, float]:
    """``(surface, inner, depth)``, or a dict with those keys."""
    if isinstance(g, dict):
        keys = {"surface", "inner", "depth"}
        if set(g) != keys:
            raise _core.InputError(f"grade: a dict with the keys surface, inner, depth, got {sorted(g)}")
        g = (g["surface"], g["inner"], g["depth"])
    try:
        t = tuple(float(v) for v in g)
    except (TypeError, ValueError):
        raise _core.InputError(f"grade: (surface, inner, depth) numbers, got {g!r}") from None
    if len(t) != 3:
        raise _core.InputError(f"grade: (surface, inner, depth), got {g!r}")
    return t


@_recorded
def fill(
    part: Shape,
    structure: str,
    cell: Field,
    density: Any = None,
    skin: Optional[float] = None,
    solid: str = "network",
    seed: int = 1,
    grade=None,
    bounds: Optional[Box] = None,
    irregularity: Optional[float] = None,
    parent_scale: Optional[float] = None,
    subdivision: Optional[str] = None,
    opening: Optional[float] = None,
    material_layers: Optional[Sequence[Tuple[float, float]]] = None,
    pore_t=None,
) -> FilledModel:
    """``part`` filled with a microstructure, as ``microfrep fill`` builds
    it (the one fill of the library: the same model and the same values).

    ``structure``: a TPMS (gyroid, schwarz-p, schwarz-d, neovius, iwp or
    schoen-iwp, fks or fischer-koch-s; ``solid='sheet'`` for the sheet), a
    strut lattice (sc, bcc, fcc, octet, kelvin, diamond), 'rods', 'pores'
    (spherical) or 'irregular' (Kou-Tan pores, ``seed`` fixes them).
    ``cell``: the cell size (millimetres). ``density``: the volume fraction
    of the structure in the core, a number, an expression of x, y, z (an
    :class:`Expr`), a HyperFun expression text of ``x[1..3]`` and ``d``
    (the depth below the part's surface, such as ``"0.2 + 0.01 * d"``), or
    a grade ``(surface, inner, depth)`` (also as ``grade=``, or a dict
    with those keys): ``surface`` just below the skin, ``inner`` from
    ``depth`` further in. ``skin``: a solid wall of that thickness in
    millimetres (a true distance for every part: a mesh's or scan's
    distance, a Newton estimate of it for a formula). ``bounds`` replace
    the part's box. Kou and Tan's controls of the irregular pores:
    ``irregularity`` (0 to 0.5, default 0.15), ``parent_scale`` (the
    parent polyhedron over the cell, 4/3 to 2, default 1.6) and
    ``subdivision`` ('octree', the default, or 'tmesh') and ``opening``
    (0 to 0.25, default 0.05: how far pores below 0.6274 porosity reach
    past their cell's faces, so that they open into their neighbours),
    ``pore_t`` (Eq. 9's t of the 8 derived points, 24 numbers or 8 x 3,
    in [0, 1]: the pores' shape set by hand, scaled to each cell's
    porosity). ``material_layers``: Park's material subspaces below the surface, a
    list of ``(depth, ramp)`` in millimetres; layer k is material k, its
    fraction rising from 0 at ``depth`` to 1 at ``depth + ramp`` (later
    layers over earlier ones), material 0 the rest; they are the model's
    attribute channels s1..sK.

    Returns a :class:`FilledModel`: the model on the part's box, with
    :meth:`~FilledModel.report` (the measured figures) and
    :meth:`~FilledModel.hyperfun`."""
    p = _shape(part)
    if solid not in ("network", "sheet"):
        raise _core.InputError(f"fill: solid '{solid}' (network, sheet)")
    if isinstance(cell, Expr):
        c = cell._e.as_const()
        if c is None:
            raise _core.InputError("fill: cell must be a number (one cell size for the whole part)")
    elif isinstance(cell, (int, float, np.floating, np.integer)) and not isinstance(cell, bool):
        c = float(cell)
    else:
        raise _core.InputError(f"fill: cell must be a number, got {type(cell).__name__}")
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
        raise _core.InputError(f"fill: seed {seed!r} must be a whole number from 0 to 2^53")
    kw: dict = {}
    if grade is not None:
        if density is not None:
            raise _core.InputError("fill: give density or grade, not both")
        kw["grade"] = _grade(grade)
    elif density is None:
        raise _core.InputError(
            "fill: give a density (a number, an expression, a HyperFun expression text of x[1..3] "
            "and d) or grade=(surface, inner, depth)"
        )
    elif isinstance(density, str):
        kw["density_text"] = density
    elif isinstance(density, (dict, tuple, list)):
        kw["grade"] = _grade(density)
    elif isinstance(density, (int, float, np.floating, np.integer)) and not isinstance(density, bool):
        kw["density"] = float(density)
    elif isinstance(density, (Expr, Shape)):
        kw["density_field"] = _expr(density)._e
    else:
        raise _core.InputError(f"fill: density must be a number, an Expr, a text or a grade, got {type(density).__name__}")
    if skin is not None:
        if isinstance(skin, bool) or not isinstance(skin, (int, float, np.floating, np.integer)):
            raise _core.InputError(f"fill: skin must be a thickness in millimetres, got {skin!r}")
        skin = float(skin)
    f = _core.fill_part(
        p._s,
        str(structure),
        c,
        sheet=solid == "sheet",
        skin=skin,
        seed=int(seed),
        bounds=_box(bounds),
        irregularity=None if irregularity is None else float(irregularity),
        parent_scale=None if parent_scale is None else float(parent_scale),
        subdivision=subdivision,
        opening=None if opening is None else float(opening),
        material_layers=None if material_layers is None else [(float(d), float(r)) for d, r in material_layers],
        pore_t=None if pore_t is None else [float(v) for v in np.asarray(pore_t, dtype=float).ravel()],
        **kw,
    )
    return FilledModel(f)
