"""Park's material subspaces from Python: materials() with Subspace gives
the fractions of the bundled Fig. 6 femur example (written with
mfSubspace), subspaces override in order, and bad arguments are refused."""

import math
import pickle
from pathlib import Path

import numpy as np
import pytest

import microfrep as mf

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# The femur of Fig. 5/6 and its depth estimate, as two HyperFun objects.
FEMUR = """
femur(x[3], a[1]) {
  array p[3];
  newx = 0.5*x[1]*1.414 + 1 - 0.5*x[2];
  newy = 0.5*x[1] + 0.5*(-2 + x[2])*1.414;
  p[1] = 1 / max(x[2]*x[2]/7.5 + x[1]*x[1]/0.25 + x[3]*x[3]/0.25, 0.001);
  p[2] = 1 / max(newy*newy/0.6 + newx*newx/0.1 + x[3]*x[3]/0.1, 0.001);
  p[3] = 1 / max(((x[2] - 3.4)*4/3)^2 + ((x[1] - 0.6)*4/3)^2 + (x[3]*4/3)^2, 0.001);
  u = mfUnionA(p, 5);
  femur = u - 1;
}
depth(x[3], a[1]) {
  array p[3];
  newx = 0.5*x[1]*1.414 + 1 - 0.5*x[2];
  newy = 0.5*x[1] + 0.5*(-2 + x[2])*1.414;
  p[1] = 1 / max(x[2]*x[2]/7.5 + x[1]*x[1]/0.25 + x[3]*x[3]/0.25, 0.001);
  p[2] = 1 / max(newy*newy/0.6 + newx*newx/0.1 + x[3]*x[3]/0.1, 0.001);
  p[3] = 1 / max(((x[2] - 3.4)*4/3)^2 + ((x[1] - 0.6)*4/3)^2 + (x[3]*4/3)^2, 0.001);
  u = mfUnionA(p, 5);
  depth = mfDepth(1 - 1/sqrt(u));
}
"""


def random_points(n=1000, seed=7):
    rng = np.random.default_rng(seed)
    lo, hi = np.array([-1.3, -3.0, -0.9]), np.array([1.6, 4.3, 0.9])
    return lo + (hi - lo) * rng.random((n, 3))


def test_fig6_from_python_equals_the_example():
    part = mf.load_hyperfun(FEMUR, object="femur")
    depth = mf.load_hyperfun(FEMUR, object="depth").value
    # Bioceramic (1) fills the part; below a shell of depth 0.1, titanium (2)
    # graded over 0.2 of depth, bias 0.7 in the local depth coordinate w = z.
    bias = mf.clamp(mf.z, 0, 1) ** (math.log(0.7) / math.log(0.5))
    core = mf.Subspace.below_surface(depth, 0.1, 0.3, bias, material=2)
    model = mf.materials(part, 2, [core])
    assert model.attribute_names == ["s1", "s2"]
    example = mf.load(str(EXAMPLES / "park_fig6_femur_gradient.hf"))
    pts = random_points()
    got, want = model.attributes(pts), example.attributes(pts)
    inside = example.eval(pts, precise=True) >= 0
    assert 100 < inside.sum() < 900
    assert np.array_equal(model.eval(pts, precise=True) >= 0, inside)
    for k in ("s1", "s2"):
        assert np.allclose(got[k][inside], want[k][inside], rtol=0, atol=1e-9), k
        assert np.all(got[k][~inside] == 0.0), k
    s2 = got["s2"][inside]
    # Shell, graded layer and fully titanium core are all sampled.
    assert (s2 == 0).sum() > 20 and ((s2 > 0) & (s2 < 0.99)).sum() > 20 and (s2 > 0.99).sum() > 5
    assert np.allclose(got["s1"][inside] + s2, 1.0, atol=1e-12)
    # The model pickles (its recipe replays) with the same fractions.
    back = pickle.loads(pickle.dumps(model))
    assert np.array_equal(back.attributes(pts)["s2"], got["s2"])


def test_later_subspaces_override_and_boxes_map_to_the_unit_cube():
    part = mf.box((0, 0, 0), (1, 1, 1))
    # Material 2 graded along u in the box x > 0.5 (u = 0 at x = 0.5), then
    # a slab z > 0.75 of material 3 with base 2, over primary 1.
    ramp = mf.Subspace.in_box((0.5, 0, 0), (1, 1, 1), mf.x, material=2)
    slab = mf.Subspace(mf.z - 0.75, 1.0, material=3, base=2)
    m = mf.materials(part, 3, [ramp, slab])
    pts = np.array([[0.25, 0.5, 0.5], [0.75, 0.5, 0.5], [0.99, 0.5, 0.5], [0.25, 0.5, 0.9], [2.0, 0.5, 0.5]])
    a = m.attributes(pts)
    s = np.stack([a["s1"], a["s2"], a["s3"]], axis=1)
    assert np.allclose(s[0], [1, 0, 0])
    assert np.allclose(s[1], [0.5, 0.5, 0], atol=1e-6)
    assert np.allclose(s[2], [0.02, 0.98, 0], atol=1e-6)
    assert np.allclose(s[3], [0, 0, 1])
    assert np.allclose(s[4], [0, 0, 0])  # outside the part
    # The general form with local coordinates: w = 2 z, fraction w clamped.
    half = mf.Subspace(mf.z, mf.z, material=2, local=(mf.x, mf.y, 2 * mf.z))
    h = mf.materials(part, 2, [half]).attributes(np.array([[0.5, 0.5, 0.25], [0.5, 0.5, 0.75]]))
    assert np.allclose(h["s2"], [0.5, 1.0]) and np.allclose(h["s1"], [0.5, 0.0])


def test_bad_material_models_are_refused():
    part = mf.sphere((0, 0, 0), 1.0)
    ok = mf.Subspace(mf.x, 0.5, material=2)
    with pytest.raises(mf.InputError, match="count must be 1 to 255"):
        mf.materials(part, 0, [ok])
    with pytest.raises(mf.InputError, match="primary material 3 is not one of 1..2"):
        mf.materials(part, 2, [ok], primary=3)
    with pytest.raises(mf.InputError, match="material 2 is not one of 1..1"):
        mf.materials(part, 1, [ok])
    with pytest.raises(mf.InputError, match="graded and base material are both 2"):
        mf.materials(part, 2, [ok], primary=2)
    with pytest.raises(mf.InputError, match="material number from 1"):
        mf.Subspace(mf.x, 0.5, material=0)
    with pytest.raises(mf.InputError, match="not a Subspace"):
        mf.materials(part, 2, ["x > 0"])
    with pytest.raises(mf.InputError, match="depth_to 0.1 must be greater"):
        mf.Subspace.below_surface(mf.x, 0.2, 0.1, mf.z, material=2)
    with pytest.raises(mf.InputError, match="lo < hi"):
        mf.materials(part, 2, [mf.Subspace.in_box((0, 0, 0), (1, 0, 1), mf.x, material=2)])
