"""simulate.Run: a run advanced piece by piece takes the steps of one simulate call, bit for bit."""

import numpy as np
import pytest

from cobra_ref.gaits import gait
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import Run, simulate
from cobra_ref.start import initial_state
from cobra_ref.step import SimulationError, StepSettings

SETTINGS = StepSettings(dt=0.002)


@pytest.fixture(scope="module")
def scene():
    model, reference = cobra_model(), gait("J", frequency=1.0)
    q0, qd0 = initial_state(model, reference, SETTINGS)
    return model, reference, q0, qd0


def test_pieces_equal_one_call(scene):
    model, reference, q0, qd0 = scene
    whole = simulate(model, reference, 0.2, SETTINGS, q0, qd0)
    run = Run(model, SETTINGS, q0, qd0, "fast", 100)
    for n in (1, 24, 50, 25):  # 100 steps in four uneven pieces
        run.advance(reference, n)
    pieces = run.finish()
    assert run.t == pytest.approx(0.2)
    for name in ("t", "q", "qd", "tau", "box_pose"):
        np.testing.assert_array_equal(getattr(pieces, name), getattr(whole, name))
    np.testing.assert_array_equal(pieces.contacts["contact_force"], whole.contacts["contact_force"])


def test_a_run_started_mid_way_continues_the_motion(scene):
    # from the state and memory at 0.1 s, a new Run follows the first one closely (its new OSQP
    # instances start cold, so the last bits may differ)
    model, reference, q0, qd0 = scene
    first = Run(model, SETTINGS, q0, qd0, "fast", 100)
    first.advance(reference, 50)
    second = Run(model, SETTINGS, first.q, first.qd, "fast", 50, t0=first.t, memory=first.stepping.memory)
    first.advance(reference, 50)
    second.advance(reference, 50)
    a, b = first.finish(), second.finish()
    assert b.t[0] == pytest.approx(0.1) and b.t[-1] == pytest.approx(0.2)
    np.testing.assert_allclose(b.q[-1], a.q[-1], atol=1e-8)


def test_a_run_refuses_more_steps_than_it_holds(scene):
    model, reference, q0, qd0 = scene
    run = Run(model, SETTINGS, q0, qd0, "fast", 3)
    with pytest.raises(SimulationError, match="holds 3 steps"):
        run.advance(reference, 4)
