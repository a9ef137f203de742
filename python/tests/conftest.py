"""Shared fixtures: a two-worker Dask cluster (one rayon thread each, so
the two processes share this machine's cores) and model helpers."""

import os

import pytest


@pytest.fixture(scope="session")
def client():
    distributed = pytest.importorskip("distributed")
    cluster = distributed.LocalCluster(
        n_workers=2,
        threads_per_worker=1,
        processes=True,
        dashboard_address=None,
        env={"RAYON_NUM_THREADS": "1"},
    )
    c = distributed.Client(cluster)
    yield c
    c.close()
    cluster.close()


@pytest.fixture
def ball_hf(tmp_path):
    """A HyperFun ball of radius sqrt(a[1])."""
    p = tmp_path / "ball.hf"
    p.write_text("my_model(x[3], a[1])\n{\n  my_model = a[1] - (x[1]^2 + x[2]^2 + x[3]^2);\n}\n")
    return p


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)
