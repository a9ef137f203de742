"""The peer of `microfrep fill` in the bench suite `parts`: what a user
would script instead to fill a mesh part with a gyroid inside a skin and
write an STL, with PyPI packages only.

usage: fill_pipeline.py MESH.stl N CELL DENSITY SKIN OUT.stl

1. trimesh reads the mesh (vertices merged, so the surface is closed);
2. libigl's signed distance (pseudo-normal sign: the mesh is closed and
   welded, the fastest correct sign) at the nodes of a grid with N cells on
   the box's longest side, padded by two cells, z-slab by z-slab so the
   query points never all sit in memory at once;
3. a NumPy gyroid network of cell CELL whose level is the DENSITY quantile
   of the gyroid over one cell (so the network holds that volume
   fraction), joined to a SKIN-thick wall: max(min(d, skin - d),
   min(d - skin, gyroid)) with d the distance, positive inside;
4. scikit-image's marching cubes at level 0;
5. trimesh writes the binary STL.

Prints one JSON line: the grid, triangles and seconds per step (imports
included in `total`, which starts at the first line of this script).
"""

import time

T0 = time.perf_counter()

import json  # noqa: E402
import sys  # noqa: E402

import igl  # noqa: E402
import numpy as np  # noqa: E402
import trimesh  # noqa: E402
from skimage import measure  # noqa: E402


def gyroid(x, y, z, k):
    """sin kx cos ky + sin ky cos kz + sin kz cos kx on the grid x (i) by
    y (j) by z (k), broadcast from the three axes (no meshgrid copies)."""
    sx, cx = np.sin(k * x)[:, None, None], np.cos(k * x)[:, None, None]
    sy, cy = np.sin(k * y)[None, :, None], np.cos(k * y)[None, :, None]
    sz, cz = np.sin(k * z)[None, None, :], np.cos(k * z)[None, None, :]
    return (sx * cy + sy * cz + sz * cx).astype(np.float32)


def main():
    path, n, cell, density, skin, out = sys.argv[1:7]
    n, cell, density, skin = int(n), float(cell), float(density), float(skin)
    steps = {}
    t = time.perf_counter()
    steps["imports"] = t - T0
    mesh = trimesh.load(path, force="mesh")
    V = np.asarray(mesh.vertices, dtype=np.float64)
    F = np.asarray(mesh.faces, dtype=np.int64)
    steps["read"] = time.perf_counter() - t

    lo, hi = V.min(axis=0), V.max(axis=0)
    h = (hi - lo).max() / n
    lo = lo - 2 * h
    dims = np.ceil((hi + 2 * h - lo) / h).astype(int) + 1
    axes = [lo[a] + h * np.arange(dims[a]) for a in range(3)]

    t = time.perf_counter()
    sd = np.empty(tuple(dims), dtype=np.float32)
    gx, gy = np.meshgrid(axes[0], axes[1], indexing="ij")
    plane = np.stack([gx.ravel(), gy.ravel(), np.zeros(gx.size)], axis=1)
    slab = max(1, int(4_000_000 // plane.shape[0]))
    for k0 in range(0, dims[2], slab):
        ks = axes[2][k0 : k0 + slab]
        P = np.tile(plane, (len(ks), 1))
        P[:, 2] = np.repeat(ks, plane.shape[0])
        S = igl.signed_distance(P, V, F, sign_type=igl.SIGNED_DISTANCE_TYPE_PSEUDONORMAL)[0]
        # libigl is negative inside; the model is positive inside.
        sd[:, :, k0 : k0 + len(ks)] = (-S).reshape(len(ks), dims[1], dims[0]).transpose(2, 1, 0)
    steps["signed_distance"] = time.perf_counter() - t

    t = time.perf_counter()
    k = 2 * np.pi / cell
    u = np.linspace(0, cell, 64, endpoint=False)
    level = np.quantile(gyroid(u, u, u, k), density)
    g = level - gyroid(*axes, k)
    model = np.maximum(np.minimum(sd, skin - sd), np.minimum(sd - skin, g))
    del g
    steps["gyroid_and_skin"] = time.perf_counter() - t

    t = time.perf_counter()
    verts, faces, _, _ = measure.marching_cubes(model, level=0.0, spacing=(h, h, h))
    verts += lo
    steps["marching_cubes"] = time.perf_counter() - t

    t = time.perf_counter()
    trimesh.Trimesh(verts, faces, process=False).export(out)
    steps["write_stl"] = time.perf_counter() - t

    print(
        json.dumps(
            {
                "dims": [int(d) for d in dims],
                "cell_mm": float(h),
                "triangles": int(len(faces)),
                "steps": steps,
                "total": time.perf_counter() - T0,
            }
        )
    )


if __name__ == "__main__":
    main()
