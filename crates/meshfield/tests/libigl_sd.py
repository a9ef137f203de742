"""libigl's side of the signed-distance comparisons (the optional test
crates/meshfield/tests/libigl.rs and the bench suite `parts`).

usage: libigl_sd.py V.f64 F.i64 P.f64 OUT.f64 [REPEAT [EXACT]]

V: vertex positions, F: triangle indices, P: query points, all raw little
endian, 3 per row. Computes igl.signed_distance with the fast winding number
sign (libigl: negative inside) and writes the distances with microfrep's sign
(positive inside) to OUT. With EXACT = 1 it also writes, to OUT.exact, the
unsigned distances of igl.point_mesh_squared_distance: the magnitudes that
signed_distance returns with this sign type are not exact (off by up to
~5e-4 of the diagonal on a 5120-triangle sphere). Prints one JSON line:
seconds of the fastest of REPEAT calls of signed_distance (default 1;
threads from IGL_NUM_THREADS), queries per second, peak resident memory.
"""

import json
import resource
import sys
import time

import numpy as np


def main():
    vpath, fpath, ppath, out = sys.argv[1:5]
    repeat = int(sys.argv[5]) if len(sys.argv) > 5 else 1
    exact = len(sys.argv) > 6 and sys.argv[6] == "1"
    import igl

    V = np.fromfile(vpath, dtype="<f8").reshape((-1, 3))
    F = np.fromfile(fpath, dtype="<i8").reshape((-1, 3))
    P = np.fromfile(ppath, dtype="<f8").reshape((-1, 3))
    best = float("inf")
    S = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        S = igl.signed_distance(
            P, V, F, sign_type=igl.SIGNED_DISTANCE_TYPE_FAST_WINDING_NUMBER
        )[0]
        best = min(best, time.perf_counter() - t0)
    (-np.asarray(S, dtype="<f8")).tofile(out)
    if exact:
        d2 = igl.point_mesh_squared_distance(P, V, F)[0]
        np.sqrt(np.asarray(d2, dtype="<f8")).tofile(out + ".exact")
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"seconds": best, "qps": len(P) / best, "peak_mib": peak}))


if __name__ == "__main__":
    main()
