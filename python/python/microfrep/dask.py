"""Slicing and analysis past one machine, on any ``dask.distributed``
cluster (a ``LocalCluster``, dask-jobqueue on a batch system, Dask on
Kubernetes).

* :func:`slice_to` splits a stack into ranges of layers; workers compute
  each layer's bytes (PNG, SVG or CLI blocks) and the client assembles the
  stack under a temporary name, renamed when the last layer is in: the
  files are byte for byte those of ``microfrep slice`` (and of
  :meth:`microfrep.Shape.slice_to`).
* :func:`analyze` splits the voxel grid into z-slabs of whole bricks.
  Volume and area are measured per brick in the two passes of the
  one-process measure (a survey, then the creased bricks refined at the one
  depth the summed survey gives) and summed in brick order: the same bits
  as :meth:`microfrep.Shape.analyze`. Connectivity labels each slab
  (reading one voxel layer beyond each face) and joins the labels that
  touch across the faces with a union-find, as dask-image does for
  ``label``: component and cavity counts, percolation and the Euler
  characteristic are identical, volumes equal to rounding. Local thickness
  is not distributed (``"thickness": null``).

Tasks carry the model's recipe (its HyperFun text, file path or example
name and the arguments that built it), never compiled code: each worker
rebuilds the shape once and keeps it for the job's other tasks. Files the
model reads (meshes, scans, ``fields``) must be at the same path on every
worker (a shared file system). Workers must have the same microfrep.

Each worker evaluates on a rayon thread pool of all its machine's cores;
with several worker processes on one machine, give each a share, e.g.
``LocalCluster(n_workers=2, threads_per_worker=1, env={"RAYON_NUM_THREADS": "1"})``.

Progress: the tasks (``microfrep-slice-*``, ``microfrep-survey-*``, ...)
show in Dask's dashboard; the client draws a bar (tqdm if installed, else
plain lines on stderr) unless ``progress=False``.

Example::

    from dask.distributed import Client, LocalCluster
    import microfrep as mf, microfrep.dask as mfd

    client = Client(LocalCluster(n_workers=4))
    part = mf.load("part.stl")
    model = mf.fill(part, "gyroid", cell=1.5, density=0.25, skin=0.3)
    mfd.slice_to(model, "stack", layer=0.05, pixel=0.025, client=client)
    report = mfd.analyze(model, resolution=512, region=part, client=client)
"""

from __future__ import annotations

import math
import os
import sys
import time
import uuid
from typing import Optional

from . import _core
from ._model import AnalysisReport, Shape, _box

__all__ = ["slice_to", "analyze"]


def _client(client):
    try:
        import distributed
    except ImportError:
        raise _core.Error(
            "microfrep.dask needs dask.distributed: pip install 'microfrep[dask]'"
        ) from None
    if client is not None:
        return client
    try:
        return distributed.get_client()
    except ValueError:
        raise _core.Error(
            "no Dask client: create one (distributed.Client(...)) or pass client="
        ) from None


def _workers(client) -> int:
    try:
        n = sum(client.nthreads().values())
    except Exception:
        n = 0
    return max(1, n)


class _Bar:
    """A progress bar: tqdm when installed, else a line per tenth."""

    def __init__(self, total: int, what: str, enabled: bool):
        self.total, self.what, self.done = total, what, 0
        self.enabled = enabled
        self._bar = None
        self._shown = -1
        if enabled:
            try:
                from tqdm.auto import tqdm

                self._bar = tqdm(total=total, desc=what, unit="")
            except ImportError:
                self._bar = None

    def add(self, n: int):
        self.done += n
        if not self.enabled:
            return
        if self._bar is not None:
            self._bar.update(n)
            return
        tenth = 10 * self.done // max(1, self.total)
        if tenth != self._shown:
            self._shown = tenth
            print(f"{self.what}: {self.done}/{self.total}", file=sys.stderr, flush=True)

    def close(self):
        if self._bar is not None:
            self._bar.close()


def _ranges(n: int, step: int):
    return [(a, min(n, a + step)) for a in range(0, n, step)]


# -- slicing


def _slice_task(shape: Shape, fmt, aa, bounds, layer, pixel, k0, k1, out):
    data = shape._s.slice_layer_bytes(fmt, aa, bounds, layer, pixel, k0, k1, out)
    errors = shape._s.slice_census(bounds, layer, pixel, k0, k1)
    return k0, data, errors


def slice_to(
    shape: Shape,
    path,
    layer: float = 0.05,
    pixel: float = 0.025,
    format: str = "png",
    bounds=None,
    aa: bool = False,
    client=None,
    chunk: Optional[int] = None,
    progress: bool = True,
) -> dict:
    """:meth:`microfrep.Shape.slice_to` on a Dask cluster: the same files.

    ``chunk`` layers per task (default: about four tasks per worker thread,
    at most 64 layers). Returns the summary of ``microfrep slice --json``.
    If any task fails, the partial stack is removed and the error raised."""
    client = _client(client)
    out = os.fspath(path)
    layers, nx, ny, lo, hi = shape._s.slice_grid(float(layer), float(pixel), _box(bounds))
    b = (tuple(lo), tuple(hi))
    if chunk is None:
        chunk = max(1, min(64, math.ceil(layers / (4 * _workers(client)))))
    if int(chunk) < 1:
        raise _core.InputError(f"chunk {chunk} must be >= 1")
    writer = _core.StackWriter(out, format, aa, b, float(layer), float(pixel))
    tag = uuid.uuid4().hex[:8]
    from distributed import as_completed

    futures = [
        client.submit(
            _slice_task,
            shape,
            format,
            aa,
            b,
            float(layer),
            float(pixel),
            k0,
            k1,
            out,
            key=f"microfrep-slice-{tag}-{k0}",
            pure=False,
        )
        for k0, k1 in _ranges(layers, int(chunk))
    ]
    bar = _Bar(layers, "slicing", progress)
    errors = None
    try:
        for fut in as_completed(futures):
            k0, data, e = fut.result()
            for i, d in enumerate(data):
                writer.write(k0 + i, d)
            if e is not None:
                errors = (errors or 0) + e
            bar.add(len(data))
            fut.release()
        writer.commit()
    except BaseException:
        writer.abort()
        client.cancel(futures)
        raise
    finally:
        bar.close()
    return {
        "output": out,
        "layers": layers,
        "image_size": [nx, ny],
        "bounds": [list(lo), list(hi)],
        "runtime_errors": errors,
    }


# -- analysis


def _survey_task(shape, region, bounds, resolution, voxel, k0, k1):
    t = time.perf_counter()
    r = _core.analysis_survey(shape._s, region._s if region else None, bounds, resolution, voxel, k0, k1)
    return r, time.perf_counter() - t


def _refine_task(shape, region, bounds, resolution, voxel, depth, bricks):
    t = time.perf_counter()
    r = _core.analysis_refine(shape._s, region._s if region else None, bounds, resolution, voxel, depth, bricks)
    return r, time.perf_counter() - t


def _labels_task(shape, region, bounds, resolution, voxel, k0, k1):
    t = time.perf_counter()
    r = _core.analysis_labels(shape._s, region._s if region else None, bounds, resolution, voxel, k0, k1)
    return r, time.perf_counter() - t


def analyze(
    shape: Shape,
    resolution: Optional[int] = None,
    voxel: Optional[float] = None,
    bounds=None,
    region: Optional[Shape] = None,
    connectivity: bool = True,
    client=None,
    slab: Optional[int] = None,
    progress: bool = True,
) -> dict:
    """:meth:`microfrep.Shape.analyze` on a Dask cluster, without local
    thickness: the dict of ``microfrep analyze --json`` with volume, area
    and their errors equal to the one-process figures, and the same
    connectivity. ``slab`` voxel layers per task (rounded up to whole
    bricks of 16; default: about three slabs per worker thread).
    ``seconds`` holds the summed task times of each stage."""
    client = _client(client)
    b = _box(bounds)
    if b is None:
        b = shape.bounds()
    b = (tuple(b[0]), tuple(b[1]))
    dims, _, brick = _core.analysis_grid_info(b, resolution, voxel)
    nz = dims[2]
    nbz = math.ceil(nz / brick)
    if slab is None:
        per = max(1, math.ceil(nbz / (3 * _workers(client))))
    else:
        if int(slab) < 1:
            raise _core.InputError(f"slab {slab} must be >= 1")
        per = max(1, math.ceil(int(slab) / brick))
    slabs = [(k0, min(nz, k1)) for k0, k1 in _ranges(nbz * brick, per * brick)]
    tag = uuid.uuid4().hex[:8]
    args = (shape, region, b, resolution, voxel)
    surveys = [
        client.submit(_survey_task, *args, k0, k1, key=f"microfrep-survey-{tag}-{k0}", pure=False)
        for k0, k1 in slabs
    ]
    labels = (
        [
            client.submit(_labels_task, *args, k0, k1, key=f"microfrep-labels-{tag}-{k0}", pure=False)
            for k0, k1 in slabs
        ]
        if connectivity
        else []
    )
    total = len(surveys) * 2 + len(labels)
    bar = _Bar(total, "analysis", progress)
    seconds = [0.0, 0.0, 0.0]
    try:
        from distributed import as_completed

        parts = []
        creased = nodes = 0
        redo = []
        for fut in as_completed(surveys):
            ((ids, vals, sampled), rd, c, n), dt = fut.result()
            parts.append((ids, vals, sampled))
            redo.append(rd)
            creased += c
            nodes += n
            seconds[0] += dt
            bar.add(1)
        depth = _core.analysis_depth(creased, nodes)
        refines = [
            client.submit(_refine_task, *args, depth, rd, key=f"microfrep-refine-{tag}-{i}", pure=False)
            for i, rd in enumerate(redo)
            if rd
        ]
        bar.add(len(surveys) - len(refines))
        for fut in as_completed(refines):
            r, dt = fut.result()
            parts.append(r)
            seconds[0] += dt
            bar.add(1)
        slab_labels = None
        if connectivity:
            slab_labels = []
            for fut in as_completed(labels):
                r, dt = fut.result()
                slab_labels.append(r)
                seconds[1] += dt
                bar.add(1)
    except BaseException:
        client.cancel(surveys + labels)
        raise
    finally:
        bar.close()
    import json

    s = _core.analysis_merge(
        b,
        resolution,
        voxel,
        depth,
        creased,
        parts,
        slab_labels,
        region is not None,
        shape.name,
        region.name if region is not None else None,
        seconds,
    )
    return AnalysisReport(json.loads(s))
