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
