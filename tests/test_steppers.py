"""The two steppers of ``cobra_ref.steppers`` take the same steps on the COBRA robot.

Worked example: COBRA and its box, settled at rest in the C gait's t = 0 shape, rolling for
0.1 s at dt = 2 ms (50 steps) under each contact law (compliant, rigid) and each joint servo
(position, prescribed). The reference stepper (the readable :func:`cobra_ref.step.step`) and the
fast stepper (batched chain and contacts, certified QP solves) build the same least-action
problem each step and solve it to OSQP's tolerance, so their runs agree far below any physical
scale: the configurations [m, rad], velocities [m/s, rad/s] and the impulses the solver solves
for, the joints' tau dt and the contacts' p [N s], to 1e-9 (torques themselves, impulses over
dt, to 1e-9 / dt).
"""

import numpy as np
import pytest

from cobra_ref.gaits import gait
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import simulate
from cobra_ref.start import initial_state
from cobra_ref.step import LAWS, SERVOS, StepSettings, joint_coordinates
from cobra_ref.steppers import STEPPERS, ReferenceStepper, make_stepper

DT, DURATION = 2e-3, 0.1


@pytest.fixture(scope="module")
def cobra():
    return cobra_model()


@pytest.mark.parametrize("servo", SERVOS)
@pytest.mark.parametrize("law", LAWS)
def test_fast_and_reference_runs_agree_on_cobra(cobra, law, servo):
    """The same 50 steps from the same settled start: q, qd, the joint impulses tau dt and the
    contact impulses (the contact log's forces times dt) agree to 1e-9, contact by contact."""
    settings = StepSettings(dt=DT, contact=law, servo=servo)
    q0, qd0 = initial_state(cobra, gait("C"), settings)
    runs = {name: simulate(cobra, gait("C"), DURATION, settings, q0, qd0, stepper=name) for name in STEPPERS}
    fast, reference = runs["fast"], runs["reference"]
    assert fast.meta["stepper"] == "fast" and reference.meta["stepper"] == "reference"
    assert len(fast.tau) == len(reference.tau) == round(DURATION / DT)
    for name in ("q", "qd"):
        np.testing.assert_allclose(getattr(fast, name), getattr(reference, name), rtol=0, atol=1e-9, err_msg=name)
    np.testing.assert_allclose(fast.tau * DT, reference.tau * DT, rtol=0, atol=1e-9)
    for key in ("contact_step", "contact_kind", "contact_body"):  # the same contacts carry load
        np.testing.assert_array_equal(fast.contacts[key], reference.contacts[key])
    np.testing.assert_allclose(fast.contacts["contact_force"] * DT, reference.contacts["contact_force"] * DT,
                               rtol=0, atol=1e-9)


def test_the_prescribed_servo_stepped_side_by_side(cobra):
    """Prescribed joints, both steppers from the same state every whole step: each step's results
    agree to 1e-9, and the joints land exactly on their reference (qd+ is the secant to it)."""
    settings = StepSettings(dt=DT, servo="prescribed", touchdown_substeps=1)
    reference_gait = gait("C")
    q, qd = initial_state(cobra, reference_gait, settings)
    fast, readable = make_stepper("fast", cobra, settings), make_stepper("reference", cobra, settings)
    assert isinstance(readable, ReferenceStepper)
    joints = joint_coordinates(cobra)
    for k in range(25):
        a, b = fast.step(q, qd, k * DT, reference_gait), readable.step(q, qd, k * DT, reference_gait)
        for name in ("q", "qd", "p", "w"):
            np.testing.assert_allclose(getattr(a, name), getattr(b, name), rtol=0, atol=1e-9,
                                       err_msg=f"{name}, step {k}")
        np.testing.assert_allclose(a.tau * DT, b.tau * DT, rtol=0, atol=1e-9, err_msg=f"tau dt, step {k}")
        np.testing.assert_allclose([a.kinetic, a.potential, a.work_actuators],
                                   [b.kinetic, b.potential, b.work_actuators], rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(a.q[joints.q], a.q_ref, rtol=0, atol=1e-12)
        q, qd = a.q, a.qd
    assert set(fast.timing) == {"dynamics", "contacts", "qp", "rest"} and set(readable.timing) == {"total"}


def test_make_stepper_refuses_an_unknown_name(cobra):
    with pytest.raises(ValueError, match="stepper must be one of fast, reference, got 'quick'"):
        make_stepper("quick", cobra)
