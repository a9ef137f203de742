"""Benchmarks of the Python package; prints `RESULT <case> key=value ...`.

Run by `bench/run python` (which finds the venv of scripts/test-python), or
directly: python python/bench/bench.py [eval] [dask].

* eval: `Shape.eval` on a 10^7 x 3 float32 array (C order: rows gathered
  per chunk; Fortran order: columns read in place) against the Rust batch
  evaluation of the same model on separate x, y, z arrays
  (`eval_points_par`), in this process, same threads: ratio = Rust time /
  Python time (1.0: no overhead; target >= 0.9).
* dask: a 400-layer PNG stack and a 256^3 analysis of the tori-ball block
  on LocalClusters of 1 and 2 workers (one rayon thread each), against one
  process on all threads; the analysis checked equal to the one-process
  figures.
"""

import os
import shutil
import sys
import tempfile
import time

import numpy as np

import microfrep as mf
from microfrep import _core


def best(f, reps=7):
    ts = []
    for _ in range(reps):
        t = time.perf_counter()
        f()
        ts.append(time.perf_counter() - t)
    return min(ts)


def bench_eval():
    n = 10_000_000
    s = mf.load("toriball")
    p = np.random.default_rng(0).uniform(-1, 1, (n, 3)).astype(np.float32)
    xs, ys, zs = (np.ascontiguousarray(p[:, i]) for i in range(3))
    pf = np.asfortranarray(p)
    s.eval(p[:1000])
    t_rust = best(lambda: _core.eval_points_par(s._s, xs, ys, zs))
    t_c = best(lambda: s.eval(p))
    t_f = best(lambda: s.eval(pf))
    assert np.array_equal(s.eval(p), _core.eval_points_par(s._s, xs, ys, zs))
    print(
        f"RESULT python_eval model=toriball points={n} threads={mf.threads()} "
        f"rust_s={t_rust:.4f} c_order_s={t_c:.4f} f_order_s={t_f:.4f} "
        f"rust_mpts={n / t_rust / 1e6:.1f} c_order_mpts={n / t_c / 1e6:.1f} "
        f"ratio_c={t_rust / t_c:.3f} ratio_f={t_rust / t_f:.3f}",
        flush=True,
    )


def bench_dask():
    import microfrep.dask as mfd
    from distributed import Client, LocalCluster

    s = mf.load("toriball")
    tmp = tempfile.mkdtemp(prefix="mf-bench-")
    try:
        t = time.perf_counter()
        s.slice_to(os.path.join(tmp, "ref"), layer=0.005, pixel=0.005)
        t_slice = time.perf_counter() - t
        t = time.perf_counter()
        ref = s.analyze(resolution=256, thickness=False)
        t_an = time.perf_counter() - t
        print(f"RESULT python_local threads={mf.threads()} slice400_s={t_slice:.2f} analyze256_s={t_an:.2f}", flush=True)
        for workers in (1, 2):
            with LocalCluster(
                n_workers=workers,
                threads_per_worker=1,
                dashboard_address=None,
                env={"RAYON_NUM_THREADS": "1"},
            ) as cluster, Client(cluster) as client:
                client.run(lambda: __import__("microfrep").load("toriball"))
                out = os.path.join(tmp, f"w{workers}")
                t = time.perf_counter()
                mfd.slice_to(s, out, layer=0.005, pixel=0.005, client=client, progress=False)
                ts = time.perf_counter() - t
                same = all(
                    open(os.path.join(out, f), "rb").read() == open(os.path.join(tmp, "ref", f), "rb").read()
                    for f in os.listdir(out)
                )
                t = time.perf_counter()
                r = mfd.analyze(s, resolution=256, client=client, progress=False)
                ta = time.perf_counter() - t
                vol = abs(r["volume"]["value"] - ref["volume"]["value"]) / ref["volume"]["value"]
                area = abs(r["area"]["value"] - ref["area"]["value"]) / ref["area"]["value"]
                c1, c2 = ref["connectivity"], r["connectivity"]
                counts = all(c1[k] == c2[k] for k in ("solid_components", "pore_components", "closed_pores", "percolates", "euler_solid"))
                print(
                    f"RESULT python_dask workers={workers} slice400_s={ts:.2f} slice_identical={same} "
                    f"analyze256_s={ta:.2f} volume_rel={vol:.1e} area_rel={area:.1e} counts_equal={counts}",
                    flush=True,
                )
    finally:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    which = sys.argv[1:] or ["eval", "dask"]
    if "eval" in which:
        bench_eval()
    if "dask" in which:
        bench_dask()
