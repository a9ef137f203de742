"""Model building: set operations, transforms, structures, pickling."""

import math
import pickle

import numpy as np
import pytest

import microfrep as mf

P = np.array([[0.0, 0.0, 0.0], [0.9, 0.0, 0.0], [1.5, 0.0, 0.0], [0.0, 0.0, 0.55], [3.0, 3.0, 3.0]])


def inside(s, p=P):
    return list(s.eval(p, precise=True) >= 0)


def test_set_operations_follow_membership():
    a = mf.sphere((0, 0, 0), 1.0)
    b = mf.half_space((0, 0, 0.5), (0, 0, 1))  # z <= 0.5
    ia, ib = inside(a), inside(b)
    assert inside(a | b) == [u or v for u, v in zip(ia, ib)]
    assert inside(a & b) == [u and v for u, v in zip(ia, ib)]
    assert inside(a - b) == [u and not v for u, v in zip(ia, ib)]
    assert inside(~a) == [not u for u in ia]
    # alpha = 0 (the default, HyperFun's &): f1 + f2 - sqrt(f1^2 + f2^2);
    # alpha = 1: exactly min.
    f1, f2 = a.eval(P, precise=True), b.eval(P, precise=True)
    want = f1 + f2 - np.sqrt(f1**2 + f2**2)
    assert np.allclose((a & b).eval(P, precise=True), want, atol=1e-12)
    assert np.array_equal(mf.intersection(a, b, alpha=1.0).eval(P, precise=True), np.minimum(f1, f2))
    assert np.array_equal(mf.union(a, b, alpha=1.0).eval(P, precise=True), np.maximum(f1, f2))
    bl = mf.blend_union(a, b, 0.2, 1.0, 1.0)
    want = f1 + f2 + np.sqrt(f1**2 + f2**2) + 0.2 / (1 + f1**2 + f2**2)
    assert np.allclose(bl.eval(P, precise=True), want, atol=1e-12)


def test_primitives_and_transforms():
    bx = mf.box((0, 0, 0), (1, 2, 3))
    assert bx.bounds() == ((0, 0, 0), (1, 2, 3))
    assert inside(bx, np.array([[0.5, 1.9, 2.9], [1.1, 1, 1]])) == [True, False]
    t = mf.translate(mf.sphere((0, 0, 0), 0.5), (2, 0, 0))
    assert inside(t, np.array([[2.4, 0, 0], [0.4, 0, 0]])) == [True, False]
    r = mf.rotate(bx, "z", 90)  # (x, y) -> (-y, x): the box now spans x in [-2, 0]
    assert inside(r, np.array([[-1.9, 0.5, 1], [0.5, 1.9, 1]])) == [True, False]
    tor = mf.torus((0, 0, 0), "z", 1.0, 0.25)
    assert inside(tor, np.array([[1.0, 0, 0], [0, 0, 0], [0, 1.2, 0]])) == [True, False, True]
    cyl = mf.cylinder((0, 0, 0), "x", 0.5)
    assert inside(cyl, np.array([[100, 0.4, 0], [0, 0.6, 0]])) == [True, False]


def test_density_solved_tpms_and_struts_hit_their_targets():
    for s, d in [
        (mf.gyroid(cell=1.0, density=0.3), 0.3),
        (mf.schwarz_p(cell=1.0, density=0.2, sheet=True), 0.2),
        (mf.octet(cell=1.0, density=0.2), 0.2),
    ]:
        r = s.analyze(resolution=64, bounds=(0.13, 0.27, 0.31, 2.13, 2.27, 2.31), connectivity=False, thickness=False)
        assert abs(r["volume_fraction"]["value"] - d) < 0.01, (d, r["volume_fraction"])


def test_graded_density_follows_its_field():
    dens = mf.lerp(0.15, 0.45, mf.z / 4.0)
    g = mf.gyroid(cell=1.0, density=dens)
    for z0, want in [(0.0, 0.15 + 0.3 * 0.5 / 4), (3.0, 0.15 + 0.3 * 3.5 / 4)]:
        r = g.analyze(resolution=64, bounds=(0, 0, z0, 2, 2, z0 + 1), connectivity=False, thickness=False)
        assert abs(r["volume_fraction"]["value"] - want) < 0.005, (z0, r["volume_fraction"])


def test_fill_keeps_a_skin_and_the_lattice_density():
    part = mf.box((0, 0, 0), (6, 6, 6))
    m = mf.fill(part, "gyroid", cell=1.5, density=0.25, skin=0.3)
    # Box value is a product of slabs, not a distance: check points on the
    # way in along a face normal (value grows monotonically inward).
    near = np.array([[3.0, 3.0, 0.01], [0.01, 3.0, 3.0]])
    assert all(m.eval(near, precise=True) >= 0)
    r = m.analyze(resolution=96, connectivity=False, thickness=False)
    assert 0.25 < r["volume_fraction"]["value"] < 0.6
    inner = m.analyze(resolution=64, bounds=(2, 2, 2, 5, 5, 5), connectivity=False, thickness=False)
    assert abs(inner["volume_fraction"]["value"] - 0.25) < 0.02


def test_irregular_pores_reach_the_density():
    part = mf.box((0, 0, 0), (4, 4, 4))
    m = mf.fill(part, "irregular", cell=1.0, density=0.5)
    r = m.analyze(resolution=96, connectivity=False, thickness=False)
    assert abs(r["volume_fraction"]["value"] - 0.5) < 0.03, r["volume_fraction"]


def test_shapes_pickle_as_their_recipe(ball_hf):
    p = np.random.default_rng(1).uniform(-1, 1, (500, 3))
    models = [
        mf.load("toriball"),
        mf.load(ball_hf, params=[0.5]),
        mf.fill(mf.sphere((0, 0, 0), 1.0), "kelvin", cell=0.5, density=0.2, skin=0.1),
        mf.gyroid(cell=0.4, density=mf.lerp(0.1, 0.4, (mf.x + 1) / 2)) & mf.sphere(),
        mf.translate(mf.torus(), (0.1, 0, 0)) | mf.box((0, 0, 0), (0.5, 0.5, 0.5)),
    ]
    for m in models:
        b = pickle.dumps(m)
        assert b"CFUNCTYPE" not in b and len(b) < 20000
        again = pickle.loads(b)
        assert np.array_equal(again.eval(p, precise=True), m.eval(p, precise=True), equal_nan=True)
    # A HyperFun model travels as its text: it rebuilds without the file.
    hf = pickle.dumps(models[1])
    ball_hf.unlink()
    assert np.array_equal(pickle.loads(hf).eval(p), models[1].eval(p))
