"""Shared fixtures: seeded rng, the smallest models that show each fact, the Agg backend."""

import os

os.environ.setdefault("MPLBACKEND", "Agg")

import numpy as np
import pytest

import cobra_ref as cr


@pytest.fixture
def rng():
    return np.random.default_rng(20240412)


@pytest.fixture(scope="session")
def cobra():
    """COBRA (12 bodies, 11 joints) with the box: nq = 25, nv = 23."""
    return cr.cobra_model()


@pytest.fixture(scope="session")
def cobra_robot():
    """COBRA alone: nq = 18, nv = 17 (the paper's M is 17 x 17)."""
    return cr.cobra_model(with_box=False)


@pytest.fixture(scope="session")
def chain3():
    """Fixed-base 3-link chain, joints Rz, Ry, Rz."""
    return cr.chain(3)


@pytest.fixture(scope="session")
def floating_chain4():
    """Free-floating 4-link chain (free joint + Ry, Rz, Ry)."""
    return cr.chain(4, floating=True)


# one BLAS thread: the steps work on 23 x 23 matrices, where OpenBLAS's threads only cost time
# (and tests run two at a time on a 2-core machine); results are bit-identical
from cobra_ref.infra.executors import limit_blas_threads  # noqa: E402

limit_blas_threads(1)
