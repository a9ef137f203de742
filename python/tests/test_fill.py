"""`mf.fill` is the CLI's fill: for every structure, on a HyperFun part and
on a mesh part, Python's model and `microfrep fill ... -o model.hf` loaded
back agree at 10^4 random points, and the measured report is the CLI's."""

import json
import os
import pickle
import subprocess
from pathlib import Path

import numpy as np
import pytest

import microfrep as mf

ROOT = Path(__file__).resolve().parents[2]
CLI = Path(os.environ.get("MICROFREP_CLI", ROOT / "target" / "release" / "microfrep"))

# (CLI name, sheet, density): the CLI's list of structures. Spherical pores
# on a cubic grid cannot go below 1 - pi/6 of solid.
STRUCTURES = [(k, False, 0.3) for k in ("gyroid", "schwarz-p", "schwarz-d", "neovius", "iwp", "fks")]
STRUCTURES += [(k, True, 0.3) for k in ("gyroid", "schwarz-p", "schwarz-d", "neovius", "iwp", "fks")]
STRUCTURES += [(k, False, 0.3) for k in ("sc", "bcc", "fcc", "octet", "kelvin", "diamond", "rods")]
STRUCTURES += [("pores", False, 0.6), ("irregular", False, 0.4)]
IDS = [f"{s}{'-sheet' if sh else ''}" for s, sh, _ in STRUCTURES]

CELL = 2.0
SKIN = 0.5
RADIUS = 4.0


def cli(*args) -> dict:
    if not CLI.exists():
        pytest.fail(f"the CLI {CLI} is missing: cargo build --release -p microfrep-cli (scripts/test-python builds it)")
    r = subprocess.run([str(CLI), *map(str, args)], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    return json.loads(r.stdout)


@pytest.fixture(scope="module")
def sphere_hf(tmp_path_factory):
    """A HyperFun ball of radius 4 mm (its value is no distance)."""
    p = tmp_path_factory.mktemp("parts") / "sphere.hf"
    p.write_text("my_model(x[3], a[1])\n{\n  my_model = 16 - (x[1]^2 + x[2]^2 + x[3]^2);\n}\n")
    return p


def icosphere(radius: float, levels: int):
    """A closed, outward-facing triangulated sphere (subdivided icosahedron)."""
    t = (1 + 5**0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t)]
    v += [(0, -1, -t), (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4)]
    f += [(11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8)]
    f += [(3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    verts = [np.array(p, float) / np.linalg.norm(p) for p in v]
    for _ in range(levels):
        mid = {}

        def m(a, b):
            k = (min(a, b), max(a, b))
            if k not in mid:
                c = verts[a] + verts[b]
                verts.append(c / np.linalg.norm(c))
                mid[k] = len(verts) - 1
            return mid[k]

        f = [g for a, b, c in f for g in ((a, m(a, b), m(a, c)), (b, m(b, c), m(a, b)), (c, m(a, c), m(b, c)), (m(a, b), m(b, c), m(a, c)))]
    return np.array(verts) * radius, np.array(f)


def write_stl(path: Path, v: np.ndarray, f: np.ndarray):
    tri = v[f].astype(np.float32)
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    rec = np.zeros(len(f), dtype=[("n", "<f4", 3), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"], rec["v"] = n, tri
    with open(path, "wb") as fh:
        fh.write(b"\0" * 80 + np.uint32(len(f)).tobytes() + rec.tobytes())


@pytest.fixture(scope="module")
def sphere_stl(tmp_path_factory):
    """A 1280-triangle mesh ball of radius 4 mm (a signed distance part)."""
    p = tmp_path_factory.mktemp("parts") / "ball.stl"
    v, f = icosphere(RADIUS, 3)
    assert np.all(np.einsum("ij,ij->i", np.cross(v[f[:, 1]] - v[f[:, 0]], v[f[:, 2]] - v[f[:, 0]]), v[f].mean(1)) > 0)
    write_stl(p, v, f)
    return p


def points(n=10_000, seed=7):
    # The part's box grown by 10 %: inside, on and outside the part.
    return np.random.default_rng(seed).uniform(-1.1 * RADIUS, 1.1 * RADIUS, (n, 3))


def cli_fill(part, structure, sheet, density, out, *extra):
    args = ["fill", part, "--structure", structure, "--cell", CELL, "--density", density, "--shell", SKIN]
    args += ["--sheet"] * sheet + list(extra) + ["-o", out, "--json"]
    return cli(*args)


@pytest.mark.parametrize("structure,sheet,density", STRUCTURES, ids=IDS)
def test_python_fill_equals_the_cli_on_a_hyperfun_part(tmp_path, sphere_hf, structure, sheet, density):
    py = mf.fill(mf.load(sphere_hf), structure, CELL, density, skin=SKIN, solid="sheet" if sheet else "network")
    out = tmp_path / "model.hf"
    cli_fill(sphere_hf, structure, sheet, density, out)
    # The same model: the same HyperFun text, and the same values. The
    # printed constants and the lowering of the text reorder a few
    # operations, so the reloaded graph is equal to a few ulps (about
    # 1e-16 seen), not bit for bit; f32 batches likewise to float rounding.
    assert py.hyperfun() == out.read_text()
    back = mf.load(out)
    p = points()
    a, b = py.eval(p, precise=True), back.eval(p, precise=True)
    assert not np.isnan(a).any() and not np.isnan(b).any()
    assert np.all(np.abs(a - b) <= 1e-12 * (1 + np.abs(a))), np.max(np.abs(a - b))
    af, bf = py.eval(p), back.eval(p)
    assert np.all(np.abs(af - bf) <= 1e-5 * (1 + np.abs(af))), np.max(np.abs(af - bf))
    assert np.array_equal(a >= 0, b >= 0)
    assert py.bounds() == mf.load(sphere_hf).bounds()
    # Not a trivial model: solid and empty points inside the ball, and a
    # skin just below its surface.
    r = np.linalg.norm(p, axis=1)
    inner = r < RADIUS - SKIN - 0.2
    solid = (a[inner] >= 0).mean()
    assert 0.05 < solid < 0.95, solid
    assert np.all(a[r > RADIUS + 0.05] < 0)
    shell = (r > RADIUS - 0.8 * SKIN) & (r < RADIUS - 0.2 * SKIN)
    assert shell.sum() > 10 and np.all(a[shell] >= 0)


@pytest.mark.parametrize("structure,sheet,density", STRUCTURES, ids=IDS)
def test_python_fill_equals_the_cli_on_a_mesh_part(tmp_path, sphere_stl, structure, sheet, density):
    part = mf.load(sphere_stl)
    py = mf.fill(part, structure, CELL, density, skin=SKIN, solid="sheet" if sheet else "network")
    out = tmp_path / "model.hf"
    cli_fill(sphere_stl, structure, sheet, density, out)
    # The same model, written through the same printer: the part is the
    # call part(x), bound to the mesh.
    assert py.binding == ("part", str(sphere_stl))
    assert py.hyperfun() == out.read_text()
    fields = dict([py.binding])
    back = mf.load(out, fields=fields)
    p = points()
    a = py.eval(p, precise=True)
    b = back.eval(p, precise=True)
    # Python's model evaluates the mesh distance sampled on the fill's
    # grid (step cell / 8 = 0.25 mm here, clamped to a band around the
    # surface); the .hf binds the exact mesh distance. The fill is min/max
    # of the part's distance and the structure, so the two differ by at
    # most the interpolation error of the sample, away from pores that
    # depend on the part (irregular pores are rebuilt from the exact
    # distance, here to the same pores). Measured: at most 0.027 mm (a
    # ninth of the grid step). The sample is also clamped two steps
    # outside the surface and below the skin's depth, where only the sign
    # matters: there the values differ, the solid does not. Within one step
    # of every surface of the model the values agree.
    assert not np.isnan(a).any() and not np.isnan(b).any()
    near = np.abs(b) < 0.25
    assert near.mean() > 0.05
    assert np.all(np.abs(a[near] - b[near]) <= 0.04), np.max(np.abs(a[near] - b[near]))
    sure = np.abs(a) > 0.04
    assert sure.mean() > 0.9 and np.array_equal(a[sure] >= 0, b[sure] >= 0)
    # Two loads of the .hf (the CLI's and Python's text) are one model.
    (tmp_path / "py.hf").write_text(py.hyperfun())
    again = mf.load(tmp_path / "py.hf", fields=fields)
    assert np.array_equal(again.eval(p), back.eval(p), equal_nan=True)


def test_the_report_is_the_clis(tmp_path, sphere_hf):
    py = mf.fill(mf.load(sphere_hf), "gyroid", CELL, 0.3, skin=SKIN)
    j = cli_fill(sphere_hf, "gyroid", False, 0.3, tmp_path / "model.hf")
    r = mf.fill_report(py)
    again = py.report()  # measuring is deterministic (but for its time)
    assert r.pop("measured").pop("seconds") > 0 and again.pop("measured").pop("seconds") > 0
    assert r == again
    r = py.report()
    for k in ("structure", "cell", "density", "volume_fraction", "skin", "thinnest", "pore_size", "connectivity"):
        assert r[k] == j[k], k
    assert {k: v for k, v in r["measured"].items() if k != "seconds"} == {
        k: v for k, v in j["measured"].items() if k != "seconds"
    }
    # And it is right: 30 % within its error bar, a 0.5 mm skin.
    assert abs(r["density"]["measured"] - 0.3) <= max(r["density"]["error"], 0.01)
    assert abs(r["skin"]["mean"] - SKIN) < 0.05 and r["skin"]["min"] > 0.4
    assert r["measured"]["seconds"] > 0
    with pytest.raises(mf.InputError, match="fill_report takes"):
        mf.fill_report(mf.sphere())


def test_graded_and_expression_densities(sphere_hf):
    part = mf.load(sphere_hf)
    a = mf.fill(part, "gyroid", CELL, grade=(0.2, 0.4, 2.0), skin=SKIN)
    b = mf.fill(part, "gyroid", CELL, {"surface": 0.2, "inner": 0.4, "depth": 2.0}, skin=SKIN)
    c = mf.fill(part, "gyroid", CELL, (0.2, 0.4, 2.0), skin=SKIN)
    # The grade as a HyperFun expression of the depth d below the surface.
    d = mf.fill(part, "gyroid", CELL, "0.2 + 0.2 * min(max((d - 0.5) / 2, 0), 1)", skin=SKIN)
    p = points(2000)
    va = a.eval(p, precise=True)
    for m in (b, c):
        assert np.array_equal(m.eval(p, precise=True), va)
    # The same grade; the expression reads the depth deeper (its cap is
    # the part's diagonal), which moves values only where the core is far
    # from its surface: inside and outside agree.
    vd = d.eval(p, precise=True)
    assert np.array_equal(vd >= 0, va >= 0)
    # An Expr density graded along z reaches its two ends.
    e = mf.fill(part, "gyroid", CELL, mf.lerp(0.2, 0.4, (mf.z + 4) / 8))
    # One cell each, wholly inside the ball: 0.25 and 0.35 on average.
    lo = e.analyze(resolution=48, bounds=(-1, -1, -3, 1, 1, -1), connectivity=False, thickness=False)
    hi = e.analyze(resolution=48, bounds=(-1, -1, 1, 1, 1, 3), connectivity=False, thickness=False)
    assert lo["volume_fraction"]["value"] < 0.28 < 0.32 < hi["volume_fraction"]["value"]


def test_pores_are_the_irregular_fill_and_pickle(sphere_hf):
    part = mf.load(sphere_hf)
    a = mf.pores(part, 2.0, 0.4, seed=3)
    b = mf.fill(part, "irregular", 2.0, 0.4, seed=3)
    p = points(3000)
    assert np.array_equal(a.eval(p), b.eval(p))
    assert a.design["pores"] > 8
    assert not np.array_equal(mf.pores(part, 2.0, 0.4, seed=4).eval(p), a.eval(p))
    for m in (a, b, mf.fill(part, "octet", CELL, 0.3, skin=SKIN).core):
        again = pickle.loads(pickle.dumps(m))
        assert np.array_equal(again.eval(p), m.eval(p), equal_nan=True)
    assert isinstance(pickle.loads(pickle.dumps(b)), mf.FilledModel)


def test_pore_controls_are_the_clis(tmp_path, sphere_hf):
    # Kou and Tan's controls: the same model as the CLI's with the same
    # options, another one than the defaults, and bad values named as
    # Python spells them.
    part = mf.load(sphere_hf)
    kw = dict(irregularity=0.0, parent_scale=1.8, subdivision="tmesh", opening=0.1)
    py = mf.pores(part, 2.0, 0.4, seed=2, **kw)
    out = tmp_path / "pores.hf"
    cli(
        "fill", sphere_hf, "--structure", "irregular", "--cell", 2.0, "--density", 0.4, "--seed", 2,
        "--irregularity", 0.0, "--parent-scale", 1.8, "--subdivision", "tmesh", "--opening", 0.1,
        "-o", out, "--json",
    )
    assert py.hyperfun() == out.read_text()
    assert "mfPoreFieldOpt(" in py.hyperfun()
    p = points(4000)
    back = mf.load(out)
    a, b = py.eval(p, precise=True), back.eval(p, precise=True)
    assert np.all(np.abs(a - b) <= 1e-12 * (1 + np.abs(a)))
    plain = mf.pores(part, 2.0, 0.4, seed=2).eval(p, precise=True)
    assert ((plain >= 0) != (a >= 0)).sum() > 20
    with pytest.raises(mf.InputError, match="parent_scale="):
        mf.pores(part, 2.0, 0.4, parent_scale=9.0)
    with pytest.raises(mf.InputError, match="irregularity="):
        mf.fill(part, "gyroid", 2.0, 0.3, irregularity=0.2)
    with pytest.raises(mf.InputError, match="subdivision"):
        mf.pores(part, 2.0, 0.4, subdivision="quadtree")
    # The paper's size per pore and hand-set t, as the CLI takes them.
    t = np.full((8, 3), 0.4)
    t[2, 1] = 0.3
    py = mf.pores(part, volume_per_pore=8.0, density=0.4, pore_t=t)
    out = tmp_path / "hand.hf"
    cli(
        "fill", sphere_hf, "--structure", "irregular", "--volume-per-pore", 8.0, "--density", 0.4,
        "--pore-t", ",".join(str(v) for v in t.ravel()), "-o", out, "--json",
    )
    assert py.hyperfun() == out.read_text()
    with pytest.raises(mf.InputError, match="pore_t"):
        mf.pores(part, 2.0, 0.4, pore_t=[0.4] * 5)
    with pytest.raises(mf.InputError, match="cell= or volume_per_pore="):
        mf.pores(part, 2.0, 0.4, volume_per_pore=8.0)


def test_fill_errors_are_the_packages(sphere_hf):
    part = mf.load(sphere_hf)
    with pytest.raises(mf.InputError, match="unknown structure 'foam'"):
        mf.fill(part, "foam", CELL, 0.3)
    with pytest.raises(mf.InputError, match="between 0 and 1"):
        mf.fill(part, "gyroid", CELL, 1.5)
    with pytest.raises(mf.InputError, match="larger than the part") as e:
        mf.fill(part, "gyroid", 50.0, 0.3)
    # Options are named as Python spells them, not as the CLI does.
    assert "cell= 50" in str(e.value) and "--" not in str(e.value), str(e.value)
    with pytest.raises(mf.InputError, match="skin= 40 leaves no core"):
        mf.fill(part, "gyroid", CELL, 0.3, skin=40.0)
    with pytest.raises(mf.InputError, match="no sheet form"):
        mf.fill(part, "octet", CELL, 0.3, solid="sheet")
    with pytest.raises(mf.InputError, match="give density or grade"):
        mf.fill(part, "gyroid", CELL, 0.3, grade=(0.2, 0.3, 1))
    with pytest.raises(mf.InputError, match="column"):
        mf.fill(part, "gyroid", CELL, "0.2 + * d")
    with pytest.raises(mf.InputError, match="seed"):
        mf.fill(part, "irregular", CELL, 0.4, seed=-1)
    with pytest.raises(mf.InputError, match="cannot go lower"):
        mf.fill(part, "pores", CELL, 0.3)
    with pytest.raises(mf.BoundsError):
        mf.fill(mf.gyroid(cell=1.0, density=0.3), "octet", CELL, 0.3)


def test_material_layers_are_channels_graded_by_depth(sphere_hf):
    # Park's subspaces below the surface of a 4 mm ball (its depth is a
    # Newton estimate of the distance, 4 - r): s1 rises from 0 at 0.5 mm to
    # 1 at 1.5 mm, and is 0 outside the ball.
    f = mf.fill(mf.load(sphere_hf), "gyroid", CELL, 0.3, material_layers=[(0.5, 1.0)])
    assert f.attribute_names == ["s1"]
    p = points(4000)
    depth = RADIUS - np.linalg.norm(p, axis=1)
    s1 = f.attributes(p)["s1"]
    want = np.where(depth < 0, 0.0, np.clip((depth - 0.5) / 1.0, 0.0, 1.0))
    keep = np.abs(depth) > 0.05
    # The depth of a formula part is a Newton estimate of the distance,
    # within 1 % below the skin's depth; s1 follows it over its 1 mm ramp.
    err = np.abs(s1[keep] - want[keep])
    assert np.all(err <= 0.005 + 0.012 * np.abs(depth[keep])), np.max(err)
    with pytest.raises(mf.InputError, match="material_layers="):
        mf.fill(mf.load(sphere_hf), "gyroid", CELL, 0.3, material_layers=[(0.5, -1.0)])


def test_rational_pore_weights_from_hyperfun_keep_the_porosity(tmp_path):
    # Kou and Tan's 2D pores with rational arcs (weight sqrt(2)/2: round
    # pores) through mfPores2Opt: the porosity is met (pixel count of the
    # slab's section), and the pores differ from the polynomial ones.
    def model(w):
        p = tmp_path / f"pores-{w}.hf"
        p.write_text(
            "my_model(x[3], a[1]) {\n  array v[3], o[4];\n  v = [0, 0, 0];\n"
            f"  o = [0.15, 1, 0, {w}];\n  b = hfBlock(x, v, 4, 4, 1);\n"
            "  my_model = mfPores2Opt(x, b, 1, 0.6, 1, o);\n}\n"
        )
        return mf.load(p)

    n = 800
    g = (np.arange(n) + 0.5) * 4.0 / n
    xx, yy = np.meshgrid(g, g)
    pts = np.column_stack([xx.ravel(), yy.ravel(), np.full(n * n, 0.5)])
    round_ = model(0.7071067811865476).eval(pts)
    plain = model(1).eval(pts)
    assert abs((round_ < 0).mean() - 0.6) < 0.003, (round_ < 0).mean()
    assert abs((plain < 0).mean() - 0.6) < 0.003, (plain < 0).mean()
    assert ((round_ < 0) != (plain < 0)).mean() > 0.005
