"""Shared fixtures: seeded rng, the smallest models that show each fact, the Agg backend, the
least-action problems of real steps."""

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


@pytest.fixture(scope="session")
def least_action_steps():
    """(problem, warm start) of every step of four short runs: C meeting its box, sidewinding, J
    with the rigid law (no stick-slip compliance, v_s = 0) and sidewinding with prescribed joints
    (no servo rows); and every tenth of those with servo rows once more with their torque bounds cut
    to 2 % and the start clipped to them, so that servo rows start and end saturated: the batched
    solves' worked examples."""
    from cobra_ref.fast.stepper import FastStepper
    from cobra_ref.gaits import gait
    from cobra_ref.simulate import simulate
    from cobra_ref.start import initial_state
    from cobra_ref.step import StepSettings

    collected = []
    prepare = FastStepper.prepare

    def keep(self, *args, **kwargs):
        prepared = prepare(self, *args, **kwargs)
        collected.append((prepared.system.problem, prepared.x_start))
        return prepared

    model = cr.cobra_model()
    runs = [("C", StepSettings(dt=1e-3), 1.5), ("sidewinding", StepSettings(dt=1e-3), 0.5),
            ("J", StepSettings(dt=1e-3, contact="rigid"), 0.3), ("sidewinding", StepSettings(dt=1e-3, servo="prescribed"), 0.3)]
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(FastStepper, "prepare", keep)
        for name, settings, duration in runs:
            reference = gait(name)
            simulate(model, reference, duration, settings, *initial_state(model, reference, settings))
    collected = [(p, x) for p, x in collected if len(p.c)]
    servoed = [(p, x) for p, x in collected if len(p.lo)][::10]
    for p, x in servoed:
        lo, hi, x = 0.02 * p.lo, 0.02 * p.hi, x.copy()
        x[3 * p.m:] = np.clip(x[3 * p.m:], lo, hi)
        collected.append((p._replace(lo=lo, hi=hi), x))
    return collected
