"""Errors are microfrep.Error subclasses with the CLI's messages."""

import numpy as np
import pytest

import microfrep as mf


BROKEN = """my_model(x[3], a[1])
{
  r = x[1]*x[1] + ;
  my_model = 1 - r;
}
"""


def test_hyperfun_errors_carry_file_line_and_column(tmp_path):
    p = tmp_path / "broken.hf"
    p.write_text(BROKEN)
    with pytest.raises(mf.HyperFunError) as e:
        mf.load(p)
    msg = str(e.value)
    assert f"{p}:3:" in msg, msg
    assert "r = x[1]*x[1] + ;" in msg and "^" in msg, msg
    assert msg.rstrip().endswith("1 error(s)"), msg
    (file, line, col, text), *_ = e.value.locations
    assert (file, line) == (str(p), 3) and col > 10 and text
    assert isinstance(e.value, mf.Error)


def test_hyperfun_text_errors_name_the_source():
    with pytest.raises(mf.HyperFunError, match=r"design\.hf:3:\d+"):
        mf.load_hyperfun(BROKEN, name="design.hf")
    with pytest.raises(mf.HyperFunError, match="no_such"):
        mf.load_hyperfun("my_model(x[3], a[1]) { my_model = no_such(x[1]); }")


def test_load_errors():
    with pytest.raises(mf.LoadError, match="toriball"):
        mf.load("no-such-model")
    with pytest.raises(mf.LoadError, match="HyperFun"):
        mf.load("toriball", object="x")


def test_unbounded_models_ask_for_bounds():
    with pytest.raises(mf.BoundsError, match="bounds"):
        mf.gyroid(cell=1.0).mesh(resolution=16)
    v, f = mf.gyroid(cell=1.0).mesh(resolution=16, bounds=(0, 0, 0, 1, 1, 1))
    assert len(f) > 100


def test_bad_arguments():
    s = mf.sphere()
    with pytest.raises(mf.InputError, match="bounds"):
        s.mesh(bounds=((0, 0, 0), (0, 1, 1)))
    with pytest.raises(mf.InputError, match="density"):
        mf.gyroid(cell=1.0, density=1.5)
    with pytest.raises(mf.InputError, match="unknown TPMS"):
        mf.tpms("gyroidd", 1.0)
    with pytest.raises(mf.InputError, match="format"):
        s.slice_to("x", format="bmp")
    with pytest.raises(mf.InputError, match="layer"):
        s.slice(layer=0.0, pixel=0.1)
    with pytest.raises(mf.Error, match="view"):
        s.render(view="back")
    with pytest.raises(mf.InputError, match="resolution"):
        s.analyze(resolution=0)


def test_huge_outputs_are_refused_before_allocation():
    s = mf.sphere()
    with pytest.raises(mf.MemoryLimitError):
        s.eval_grid(((-1, -1, -1), (1, 1, 1)), (100000, 100000, 100))
    with pytest.raises((mf.MemoryLimitError, mf.InputError)):
        s.slice(layer=1e-4, pixel=1e-4)


def test_existing_output_is_not_overwritten(tmp_path):
    out = tmp_path / "stack"
    out.mkdir()
    with pytest.raises(mf.Error, match="exists"):
        mf.sphere().slice_to(out, layer=0.5, pixel=0.1)


def test_a_mesh_that_loses_thin_features_is_refused_and_nothing_written(tmp_path):
    # At resolution 64 the tori-ball block's bars fall between the samples
    # (12 % of the volume is lost); the job refuses instead of writing it.
    out = tmp_path / "t.stl"
    with pytest.raises(mf.MeshError, match="finer --resolution"):
        mf.load("toriball").mesh_to_file(out, resolution=64)
    assert not out.exists()


# -- arrays: each message names what is wrong, and only that


def _msg(fn, *args):
    with pytest.raises(mf.InputError) as e:
        fn(*args)
    return str(e.value)


def test_a_3d_array_is_blamed_for_its_dimensions_not_its_dtype():
    s = mf.sphere()
    for dt in (np.float32, np.float64):
        m = _msg(s.eval, np.zeros((2, 3, 4), dtype=dt))
        assert m == "points: 3 dimensions (shape (2, 3, 4)), expected 2 (an N x 3 array, one row per point)", m
        assert "dtype" not in m and "float32 or float64" not in m


def test_a_1d_array_that_is_not_one_point():
    s = mf.sphere()
    m = _msg(s.eval, np.zeros(4, dtype=np.float32))
    assert m.startswith("points: 1 dimension (shape (4,)), expected 2"), m
    m = _msg(s.gradient, np.zeros(6))
    assert m.endswith(": .reshape(-1, 3) makes rows of x, y, z"), m
    with pytest.raises(mf.InputError, match=r"^points: 0 dimensions \(shape \(\)\), expected 2"):
        s.eval(np.float32(1.0))
    # One point of 3 coordinates is one row.
    assert s.eval(np.zeros(3)).tolist() == [1.0]


def test_the_wrong_number_of_coordinates_names_the_last_axis():
    s = mf.sphere()
    with pytest.raises(mf.InputError, match=r"^points: last axis of length 2 \(shape \(5, 2\)\), expected 3 \(x, y, z\)$"):
        s.eval(np.zeros((5, 2), dtype=np.float32))
    with pytest.raises(mf.InputError, match=r"last axis of length 4 \(shape \(3, 4\)\), expected 3 \(x, y, z\): a 3 x N array\? pass its transpose, points.T$"):
        s.value_and_gradient(np.zeros((3, 4)))
    with pytest.raises(mf.InputError, match=r"last axis of length 0 \(shape \(7, 0\)\)"):
        s.eval(np.zeros((7, 0)))
    # 3 x 3 is taken as three points.
    assert s.eval(np.zeros((3, 3))).tolist() == [1.0, 1.0, 1.0]


def test_the_dtype_is_named():
    core = mf.sphere()._s  # the extension itself: no conversion in Python
    with pytest.raises(mf.InputError, match=r"^points: dtype int8, expected float32 or float64$"):
        core.eval(np.zeros((4, 3), dtype=np.int8))
    with pytest.raises(mf.InputError, match=r"^points: dtype float16, expected float32 or float64$"):
        core.eval_precise(np.zeros((4, 3), dtype=np.float16))
    with pytest.raises(
        mf.InputError,
        match=r"^points: dtype >f4 is float32 in non-native byte order, expected native float32 or float64 \(convert with \.astype\(np\.float32\)\)$",
    ):
        core.eval(np.zeros((4, 3), dtype=">f4"))
    # Both problems at once are both named.
    m = _msg(core.eval, np.zeros((2, 3, 4), dtype=np.int32))
    assert m == "points: dtype int32, expected float32 or float64; 3 dimensions (shape (2, 3, 4)), expected 2 (an N x 3 array, one row per point)", m
    # Through the package, integers and other real floats are converted.
    s = mf.sphere()
    assert s.eval(np.zeros((2, 3), dtype=np.int8)).tolist() == [1.0, 1.0]
    assert s.eval(np.array([[0.5, 0, 0]], dtype=">f4")).tolist() == [0.75]
    with pytest.raises(mf.InputError, match=r"^points: dtype complex128 \(complex\), expected real numbers"):
        s.eval(np.zeros((2, 3), dtype=complex))
    with pytest.raises(mf.InputError, match=r"^points: dtype <U1, expected numbers"):
        s.eval([["a", "b", "c"]])
    with pytest.raises(mf.InputError, match=r"^points: dtype bool, expected numbers"):
        s.eval(np.zeros((2, 3), dtype=bool))


def test_not_an_array_and_ragged_rows():
    core = mf.sphere()._s
    with pytest.raises(mf.InputError, match=r"^points: a list, expected a NumPy array \(N x 3, float32 or float64\)$"):
        core.eval([[0.0, 0.0, 0.0]])
    with pytest.raises(mf.InputError, match=r"^points: cannot be made into an N x 3 array of numbers .*rows of 3 coordinates"):
        mf.sphere().eval([[0, 0, 0], [1, 2]])


def test_any_layout_is_read_but_unaligned_memory_is_named():
    s = mf.sphere()
    p = np.random.default_rng(1).uniform(-1, 1, (50, 3))
    want = s.eval(p)
    # Strided, transposed, reversed, read-only: all fine.
    ro = p.copy()
    ro.flags.writeable = False
    for q in (np.asfortranarray(p), p[::-1][::-1], p.T.copy().T, ro):
        assert np.array_equal(s.eval(q), want)
    assert np.array_equal(s.eval(p[::-1]), want[::-1])
    # A float64 view at an odd byte offset of a buffer is not aligned.
    raw = np.zeros(50 * 3 * 8 + 1, dtype=np.uint8)
    odd = raw[1:].view(np.float64).reshape(50, 3)
    odd[:] = p
    assert not odd.flags.aligned
    with pytest.raises(mf.InputError, match=r"^points: data not aligned in memory, expected an aligned array"):
        s._s.eval(odd)
    assert np.array_equal(s.eval(odd), want)  # the package copies it


def test_the_batch_columns_name_their_problem():
    from microfrep import _core

    s = mf.sphere()._s
    x = np.zeros(8, dtype=np.float32)
    assert _core.eval_points_par(s, x, x, x).tolist() == [1.0] * 8
    with pytest.raises(mf.InputError, match=r"^y: dtype float64, expected float32$"):
        _core.eval_points_par(s, x, np.zeros(8), x)
    with pytest.raises(mf.InputError, match=r"^z: 2 dimensions \(shape \(2, 4\)\), expected 1$"):
        _core.eval_points_par(s, x, x, np.zeros((2, 4), dtype=np.float32))
    with pytest.raises(mf.InputError, match=r"^x: not contiguous \(strides \[8\] bytes\), expected a contiguous array"):
        _core.eval_points_par(s, np.zeros(16, dtype=np.float32)[::2], x, x)
    with pytest.raises(mf.InputError, match=r"^x: a tuple, expected a NumPy array \(one-dimensional, float32\)$"):
        _core.eval_points_par(s, (0.0,), x, x)
    # An unaligned column (as unpickled buffers can be) is read from a copy.
    raw = np.zeros(8 * 4 + 1, dtype=np.uint8)
    odd = raw[1:].view(np.float32)
    assert not odd.flags.aligned
    assert _core.eval_points_par(s, odd, x, x).tolist() == [1.0] * 8
