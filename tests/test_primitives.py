"""The planner's primitives and the reference they chain: worked examples of continuity and derivatives."""

import numpy as np
import pytest

from cobra_ref.gaits import Q_MAX, YAW, RollingGait
from cobra_ref.planning.primitives import BLEND_TIME, PlanReference, Primitive, PrimitiveError


def chained():
    """C from rest, then a tapered J-mirror, a stop, sidewinding: every kind of switch."""
    plan = PlanReference(Primitive("C"))
    plan.extend(Primitive("C", 0.5, 0.5), 0.0)
    plan.extend(Primitive("J-mirror", 0.6, 0.8, taper=0.3), 1.0)
    plan.extend(Primitive("stop"), 2.0)
    plan.extend(Primitive("sidewinding", 0.6, 0.5), 3.0)
    return plan


def test_one_primitive_from_rest_is_the_gait_with_its_ramp():
    # the same phase-rate ramp as gaits.RollingGait over BLEND_TIME: the same q, qd, qdd to rounding
    plan = PlanReference(Primitive("C", 0.5, 0.5))
    plan.extend(Primitive("C", 0.5, 0.5), 0.0)
    gait = RollingGait(shape="C", amplitude=0.5, frequency=0.5, ramp_time=BLEND_TIME)
    for t in (0.0, 0.1, 0.3, 1.7):
        for ours, theirs in zip(plan(t), gait(t)):
            np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12)


@pytest.mark.parametrize("t_switch", [1.0, 2.0, 3.0])
def test_a_switch_is_continuous_in_q_and_qd(t_switch):
    # across each switch q and qd change by no more than their rates allow over 2 e (no jump)
    plan, e = chained(), 1e-7
    before, after = plan(t_switch - e), plan(t_switch + e)
    assert np.abs(after[0] - before[0]).max() < 10 * 2 * e  # |qd| < 10 rad/s
    assert np.abs(after[1] - before[1]).max() < 200 * 2 * e  # |qdd| < 200 rad/s^2


@pytest.mark.parametrize("t", [0.1, 1.1, 1.3, 2.1, 3.2, 3.6])
def test_qd_and_qdd_are_the_derivatives_of_q(t):
    # central differences of q and qd, inside blends and after them
    plan, h = chained(), 1e-6
    q, qd, qdd = plan(t)
    np.testing.assert_allclose((plan(t + h)[0] - plan(t - h)[0]) / (2 * h), qd, atol=1e-7)
    np.testing.assert_allclose((plan(t + h)[1] - plan(t - h)[1]) / (2 * h), qdd, atol=1e-6)


def test_a_stop_holds_the_shape_and_comes_to_rest():
    plan = chained()
    q1, qd1, _ = plan(2.0 + BLEND_TIME + 0.1)
    q2, qd2, _ = plan(2.9)
    np.testing.assert_array_equal(q1, q2)
    assert np.abs(qd1).max() == 0.0 and np.abs(qd2).max() == 0.0


def test_a_mirrored_shape_negates_the_yaw_joints_only():
    a, b = PlanReference(Primitive("S", 0.5)), PlanReference(Primitive("S-mirror", 0.5))
    np.testing.assert_array_equal(a(0.0)[0][YAW], -b(0.0)[0][YAW])
    np.testing.assert_array_equal(a(0.0)[0][~YAW], b(0.0)[0][~YAW])


@pytest.mark.parametrize("t", [0.1, 0.9, 1.7])
def test_mirrored_sidewinding_negates_the_yaw_joints_of_sidewinding(t):
    # q, qd and qdd along the whole motion, from the start's blend on
    plans = []
    for family in ("sidewinding", "sidewinding-mirror"):
        plan = PlanReference(Primitive(family, 0.6, 0.5))
        plan.extend(Primitive(family, 0.6, 0.5), 0.0)
        plans.append(plan)
    for own, mirror in zip(plans[0](t), plans[1](t)):
        np.testing.assert_array_equal(own[YAW], -mirror[YAW])
        np.testing.assert_array_equal(own[~YAW], mirror[~YAW])


def test_the_taper_bends_one_end_more():
    # kappa_i = A (1 + b (s_i - 1/2)): with b = 0.5 the head bends 0.75 A, the tail 1.25 A
    q = PlanReference(Primitive("C", 0.4, taper=0.5))(0.0)[0]
    assert q[0] == pytest.approx(0.4 * 0.75) and q[10] == pytest.approx(0.4 * 1.25)


def test_a_plan_extended_as_it_runs_gives_the_replay_its_values():
    # the values up to each switch do not depend on what is appended later (bit for bit)
    full = chained()
    rebuilt = PlanReference.from_dict(full.to_dict())
    times = np.linspace(0.0, 4.0, 401)
    for t in times:
        for a, b in zip(full(t), rebuilt(t)):
            np.testing.assert_array_equal(a, b)
    partial = PlanReference(Primitive("C"))
    for t_start, primitive in zip(full.starts[:2], full.primitives[:2]):
        partial.extend(primitive, t_start)
    for t in times[times <= full.starts[2]]:  # up to the third primitive's start, two primitives suffice
        for a, b in zip(full(t), partial(t)):
            np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize("kwargs, field", [
    ({"family": "W"}, "family"), ({"amplitude": -0.1}, "amplitude"), ({"amplitude": "0.5"}, "amplitude"),
    ({"frequency": float("nan")}, "frequency"), ({"taper": 2.0}, "taper"),
    ({"amplitude": Q_MAX, "taper": 0.5}, "q_max"),
])
def test_bad_primitives_are_refused_by_name(kwargs, field):
    with pytest.raises(PrimitiveError, match=field):
        Primitive(**kwargs)


def test_a_plan_must_move_forward_in_time():
    plan = chained()
    with pytest.raises(PrimitiveError, match="after the last one"):
        plan.extend(Primitive("C"), 3.0)
    with pytest.raises(PrimitiveError, match="start shape"):
        PlanReference(Primitive("stop"))


def test_a_negative_frequency_rolls_the_same_shape_the_other_way():
    # phi -> -phi: cos is even, sin is odd, so the yaw joints are the forward run's, the pitch joints negated
    forward, back = PlanReference(), PlanReference()
    forward.extend(Primitive("C", 0.5, 0.5), 0.0)
    back.extend(Primitive("C", 0.5, -0.5), 0.0)
    for t in (0.3, 1.1):
        np.testing.assert_allclose(back(t)[0][YAW], forward(t)[0][YAW], atol=1e-15)
        np.testing.assert_allclose(back(t)[0][~YAW], -forward(t)[0][~YAW], atol=1e-15)
