"""The package as users get it: the wheel that scripts/test-python builds
installs and works in a fresh venv with no Rust toolchain on PATH, and the
tests (run from python/ or python/tests) import the installed package,
never the sources in python/python/microfrep."""

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import microfrep as mf

PYTHON_DIR = Path(__file__).resolve().parents[1]
SOURCES = PYTHON_DIR / "python" / "microfrep"


def _inside(path, folder) -> bool:
    try:
        Path(path).resolve().relative_to(Path(folder).resolve())
        return True
    except ValueError:
        return False


def test_the_tests_import_the_installed_package():
    assert SOURCES.is_dir(), "the sources moved: update this test and pyproject's python-source"
    assert not _inside(mf.__file__, PYTHON_DIR), f"imported the sources: {mf.__file__}"
    assert Path(mf._core.__file__).parent == Path(mf.__file__).parent


@pytest.mark.parametrize("cwd", [PYTHON_DIR, PYTHON_DIR / "tests"])
def test_python_run_from_the_checkout_imports_the_installed_package(cwd):
    # `python -c` puts the working directory first on sys.path: no folder
    # named microfrep may sit there (the old layout had python/microfrep,
    # which gave "No module named 'microfrep._core'").
    out = subprocess.run(
        [sys.executable, "-c", "import microfrep, microfrep._core; print(microfrep.__file__)"],
        cwd=cwd,
        capture_output=True,
        text=True,
    )
    assert out.returncode == 0, out.stderr
    assert Path(out.stdout.strip()).resolve() == Path(mf.__file__).resolve()


def _path_without_rust() -> str:
    keep = []
    for d in os.environ.get("PATH", "").split(os.pathsep):
        if d and not any(os.path.exists(os.path.join(d, t)) for t in ("cargo", "rustc", "rustup")):
            keep.append(d)
    return os.pathsep.join(keep)


CHECK = textwrap.dedent(
    """
    import json, shutil, sys
    import numpy as np
    assert shutil.which("cargo") is None and shutil.which("rustc") is None, (
        shutil.which("cargo"), shutil.which("rustc"))
    import microfrep as mf
    p = np.array([[0, 0, 0], [0.5, 0, 0], [2, 0, 0]], dtype=np.float32)
    v = mf.sphere((0, 0, 0), 1.0).eval(p)
    vertices, faces = mf.box((0, 0, 0), (1, 1, 1)).mesh(resolution=8)
    print(json.dumps({"file": mf.__file__, "values": v.tolist(),
                      "vertices": len(vertices), "faces": len(faces)}))
    """
)


def test_the_wheel_installs_and_runs_without_a_rust_toolchain(tmp_path):
    wheel = os.environ.get("MICROFREP_WHEEL")
    if not wheel:
        pytest.skip("MICROFREP_WHEEL is not set (scripts/test-python builds the wheel and sets it)")
    assert Path(wheel).is_file(), f"MICROFREP_WHEEL={wheel} does not exist"
    venv = tmp_path / "fresh"
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    py = venv / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if not k.startswith(("CARGO", "RUSTUP", "PYTHON", "VIRTUAL_ENV"))}
    env["PATH"] = str(venv / "bin") + os.pathsep + _path_without_rust()
    # Binaries only: the wheel itself, and numpy (its one dependency) from PyPI.
    pip = subprocess.run(
        [str(py), "-m", "pip", "install", "--quiet", "--disable-pip-version-check", "--only-binary=:all:", wheel],
        env=env,
        capture_output=True,
        text=True,
    )
    assert pip.returncode == 0, pip.stdout + pip.stderr
    out = subprocess.run([str(py), "-c", CHECK], env=env, cwd=tmp_path, capture_output=True, text=True)
    assert out.returncode == 0, out.stdout + out.stderr
    r = json.loads(out.stdout.strip().splitlines()[-1])
    assert _inside(r["file"], venv), r["file"]
    assert r["values"][0] == pytest.approx(1.0, abs=1e-6)
    assert r["values"][1] == pytest.approx(0.75, abs=1e-6)
    assert r["values"][2] == pytest.approx(-3.0, abs=1e-6)
    # A closed cube: Euler's V - E + F = 2 with E = 3F/2.
    assert r["faces"] >= 12 and r["vertices"] - r["faces"] // 2 == 2
