"""Evaluation on NumPy arrays against closed forms, in every layout."""

import math
import os
import subprocess
import threading
import time

import numpy as np
import pytest

import microfrep as mf


def pts(n=20000, seed=0, lo=-1.5, hi=1.5):
    return np.random.default_rng(seed).uniform(lo, hi, (n, 3)).astype(np.float32)


def test_sphere_matches_closed_form_in_every_layout():
    s = mf.sphere((0.5, -0.25, 0.0), 1.2)
    p = pts()
    want = 1.44 - ((p[:, 0] - 0.5) ** 2 + (p[:, 1] + 0.25) ** 2 + p[:, 2] ** 2)
    v = s.eval(p)
    assert v.dtype == np.float32 and v.shape == (len(p),)
    assert np.max(np.abs(v - want)) < 2e-6
    # Fortran order (columns read in place), float64, strided rows, lists.
    assert np.array_equal(s.eval(np.asfortranarray(p)), v)
    assert np.array_equal(s.eval(p.astype(np.float64)), v)
    assert np.array_equal(s.eval(p[::3]), v[::3])
    assert np.array_equal(s.eval(p.T.copy().T), v)
    assert np.array_equal(s.eval(p[:5].tolist()), v[:5])
    exact = s.eval(p.astype(np.float64), precise=True)
    p64 = p.astype(np.float64)
    want64 = 1.44 - ((p64[:, 0] - 0.5) ** 2 + (p64[:, 1] + 0.25) ** 2 + p64[:, 2] ** 2)
    assert exact.dtype == np.float64 and np.max(np.abs(exact - want64)) < 1e-12


def test_gyroid_matches_its_formula():
    g = mf.gyroid(cell=0.8, level=0.3)
    p = pts(5000).astype(np.float64)
    k = 2 * math.pi / 0.8
    X, Y, Z = (k * p[:, i] for i in range(3))
    f = np.sin(X) * np.cos(Y) + np.sin(Y) * np.cos(Z) + np.sin(Z) * np.cos(X)
    assert np.max(np.abs(g.eval(p, precise=True) - (0.3 - f))) < 1e-12
    assert np.max(np.abs(g.eval(p) - (0.3 - f))) < 1e-5
    sheet = mf.gyroid(cell=0.8, level=0.3, sheet=True)
    assert np.max(np.abs(sheet.eval(p, precise=True) - (0.3 - np.abs(f)))) < 1e-12


def test_hyperfun_parameters_and_expressions(ball_hf):
    s = mf.load(ball_hf, params={1: 2.0})
    p = np.array([[0.0, 0.0, 0.0], [1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    assert list(s.eval(p, precise=True)) == [2.0, 0.0, -1.0]
    assert s.kind == "hyperfun" and s.name == str(ball_hf)
    # The same model as an expression.
    e = mf.from_expr(2.0 - (mf.x**2 + mf.y**2 + mf.z**2))
    assert list(e.eval(p, precise=True)) == [2.0, 0.0, -1.0]


def test_eval_grid_is_eval_on_linspace_nodes():
    s = mf.load("toriball")
    g = s.eval_grid(((-1, -1, -1), (1, 1, 1)), (9, 7, 5))
    assert g.shape == (9, 7, 5)
    xs, ys, zs = np.linspace(-1, 1, 9), np.linspace(-1, 1, 7), np.linspace(-1, 1, 5)
    P = np.stack(np.meshgrid(xs, ys, zs, indexing="ij"), -1).reshape(-1, 3).astype(np.float32)
    assert np.max(np.abs(g.reshape(-1) - s.eval(P))) < 1e-6


def test_gradient_and_attributes():
    s = mf.sphere((0, 0, 0), 1.0)
    p = pts(1000)
    gr = s.gradient(p)
    assert gr.shape == (1000, 3)
    assert np.max(np.abs(gr + 2 * p)) < 1e-5
    a = mf.with_attribute(s, "density", 0.2 + 0.1 * mf.z)
    assert a.attribute_names == ["density"]
    d = a.attributes(p)["density"]
    assert np.max(np.abs(d - (0.2 + 0.1 * p[:, 2]))) < 1e-6


def test_bad_points_are_refused():
    s = mf.sphere()
    with pytest.raises(mf.InputError, match=r"last axis of length 2 \(shape \(4, 2\)\), expected 3"):
        s.eval(np.zeros((4, 2), np.float32))
    with pytest.raises(mf.InputError, match="numbers"):
        s.eval(np.array([["a", "b", "c"]]))
    assert np.isnan(s.eval(np.array([[np.nan, 0, 0]], np.float32))[0])


def test_gil_is_released_during_evaluation():
    s = mf.load("toriball")
    p = pts(2_000_000, lo=-1, hi=1)
    span = []
    done = threading.Event()

    def work():
        t = time.perf_counter()
        s.eval(p, precise=True)  # one long call
        span.extend([t, time.perf_counter()])
        done.set()

    ticks = []
    th = threading.Thread(target=work)
    th.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0.001)
    th.join()
    t0, t1 = span
    during = np.array([t for t in ticks if t0 <= t <= t1])
    # This thread kept running while the one call worked: no gap near the
    # call's length, as there would be if it held the GIL.
    assert t1 - t0 > 0.05, t1 - t0
    gaps = np.diff(np.concatenate([[t0], during, [t1]]))
    assert len(during) > 10 and gaps.max() < 0.3 * (t1 - t0), (len(during), gaps.max(), t1 - t0)


def test_precise_values_match_the_cli():
    """Cross-check with `microfrep eval` (set MICROFREP_CLI to the binary)."""
    cli = os.environ.get("MICROFREP_CLI")
    if not cli:
        pytest.skip("MICROFREP_CLI not set: CLI cross-check skipped")
    p = pts(50, seed=3, lo=-1, hi=1).astype(np.float64)
    text = "\n".join(" ".join(repr(float(c)) for c in q) for q in p) + "\n"
    out = subprocess.run([cli, "eval", "toriball"], input=text, capture_output=True, text=True, check=True)
    want = [float(line.split()[0]) for line in out.stdout.strip().splitlines()]
    got = mf.load("toriball").eval(p, precise=True)
    assert len(want) == len(got) and all(a == b for a, b in zip(got, want))
