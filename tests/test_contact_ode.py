"""Dropping a ball: our step against the ODE of the compliant contact law, as dt falls.

The law (assumption A12, ``cobra_ref.compliance``) is the unilateral spring-damper
F = max(0, k delta - d z') while the ball penetrates (delta = r - z > 0), and no force across a
gap. Its ODE, integrated to 1e-12 (``drops.ode_drop``), is the answer a step must converge to.
Worked example, the 0.25 kg ball (damping ratio d / (2 sqrt(k m)) = 1.0, critical) landing at
0.5 m/s: it sinks 0.093 mm, and the force ends 1.05 ms after touch-down, while the ball still
penetrates and rises at 0.066 m/s (there k delta = d z': the damper's pull would exceed the
spring's push, and the clamp max(0, .) lets the ball go). So even the over-damped ball rebounds
(0.1 kg, zeta = 1.58: 0.034 m/s), which a linear spring-damper without the clamp would not.

Each drop starts 0.5 mm above the ground (``drops.GAP0``), so that our step meets the contact
apart, as in a run. The table of every number is printed by
``PYTHONPATH=. python -m pytest tests/test_contact_ode.py -s`` (``docs/results.md``).
"""

from functools import lru_cache

import numpy as np
import pytest

import drops
from bodies import BALL_RADIUS, GRAVITY, at_height, ball, run
from cobra_ref.step import StepSettings

FINEST, MIDDLE, COARSE = 2.5e-5, 2.5e-4, 1e-3  # [s]


@lru_cache(maxsize=None)
def measured(mass: float, v0: float, dt: float, stepper: str = "reference"):
    """(Drop, results) of ``drops.step_drop``, taken once per test session."""
    return drops.step_drop(mass, v0, dt, stepper)


def errors(mass: float, v0: float) -> dict:
    """{dt: |relative error|} of (penetration, rebound) at every dt; a ball that rests without a
    rebound has the error inf."""
    exact = drops.ode_drop(mass, v0)
    out = {}
    for dt in drops.DTS:
        e = drops.relative_error(measured(mass, v0, dt)[0], exact)
        out[dt] = tuple(np.inf if np.isnan(x) else abs(x) for x in (e.penetration, e.rebound))
    return out


def test_the_ode_lets_even_the_over_damped_balls_go():
    """The ODE's own worked numbers: the force ends at k delta = d z' with the ball still rising out
    of the ground, for every damping ratio; the critically damped ball at 0.066 m/s and the
    over-damped one at 0.034 m/s from 0.5 m/s. Its largest penetration lies between the undamped
    spring's v0 sqrt(m / k) scaled down by the damping and the static sag m g / k."""
    for mass, rebound in ((0.25, 0.0661), (0.1, 0.0340)):
        np.testing.assert_allclose(drops.ode_drop(mass, 0.5).rebound, rebound, rtol=2e-3)
    for mass in drops.MASSES:
        drop = drops.ode_drop(mass, 0.5)
        k = ball(mass=mass).contact_stiffness
        assert mass * GRAVITY / k < drop.penetration < 0.5 * np.sqrt(mass / k)
        assert drop.rebound > 0.0


CONVERGENCE_CASES = [(m, v) for m in drops.MASSES for v in drops.SPEEDS]


@pytest.mark.parametrize("mass,v0", CONVERGENCE_CASES)
def test_penetration_and_rebound_converge_to_the_ode_as_dt_falls(mass, v0):
    """The largest penetration and the rebound speed of our step approach the ODE's as dt falls from
    1 ms through 0.25 and 0.1 ms to 0.025 ms: the error at 0.025 ms is below the ones at 0.25 ms and
    at 1 ms, within 10 % at 0.1 ms and 2 % at 0.025 ms for every ball, and within 25 % at 1 ms for
    the 1 kg and 4 kg balls, whose contact lasts about three steps or more there (2.5-2.7 ms and
    5.7-6.1 ms; the lighter balls' lasts 0.6-1.1 ms, one step). A ball that
    comes to rest in its first contact instead of rebounding has an infinite rebound error."""
    err = errors(mass, v0)
    for i, name in enumerate(("penetration", "rebound")):
        by_dt = {dt: e[i] for dt, e in err.items()}
        assert by_dt[FINEST] < by_dt[MIDDLE] and by_dt[FINEST] < by_dt[COARSE], f"{name}: {by_dt}"
        assert by_dt[1e-4] < 0.10, f"{name} at 0.1 ms: {by_dt[1e-4]:.1%}"
        assert by_dt[FINEST] < 0.02, f"{name} at 0.025 ms: {by_dt[FINEST]:.1%}"
        if mass >= 1.0:
            assert by_dt[COARSE] < 0.25, f"{name} at 1 ms: {by_dt[COARSE]:.1%}"


@pytest.mark.parametrize("mass,v0", [(mass, v) for mass in (0.1, 0.25) for v in drops.SPEEDS])
def test_critically_and_over_damped_balls_rebound_as_the_ode_says(mass, v0):
    """At 0.025 ms the over-damped (0.1 kg) and the critically damped (0.25 kg) balls leave the
    ground rising, at the ODE's speed within 2 %: the clamp's end of the force, k delta = d z', is
    met by the step too. For the over-damped ball that end is ill-conditioned (k delta and d z'
    nearly cancel there), so it needs the step's window centred on its start (second order)."""
    drop, exact = measured(mass, v0, FINEST)[0], drops.ode_drop(mass, v0)
    assert drop.rebound > 0.0
    np.testing.assert_allclose(drop.rebound, exact.rebound, rtol=0.02)


def test_no_step_carries_a_normal_impulse_across_a_gap():
    """On every drop at every dt, a contact whose gap at the step's end, g + dt w, stays positive
    carries no normal impulse (below 1e-12 N s): no force across a gap, at touch-down and at lift-off."""
    for mass in drops.MASSES:
        for v0 in drops.SPEEDS:
            for dt in drops.DTS:
                for res in measured(mass, v0, dt)[1]:
                    if res.contacts.m:
                        apart = res.contacts.g + dt * res.w[0::3] > 0.0
                        assert np.all(res.p[0::3][apart] < 1e-12), (mass, v0, dt, res.contacts.g, res.p)


@pytest.mark.parametrize("mass", drops.MASSES)
def test_a_resting_ball_sags_by_its_weight_over_the_stiffness(mass):
    """Set down on the ground at rest, a ball settles at the sag m g / k (1 um for 0.1 kg, 39 um
    for 4 kg) within 1 %, at dt = 1 ms after 0.1 s: at rest w = 0 and the row's law is x = k |g| dt."""
    model = ball(mass=mass)
    q, qd = at_height(model, BALL_RADIUS)
    q, qd, _ = run(model, q, qd, 100, StepSettings(dt=COARSE), stepper="reference")
    np.testing.assert_allclose(BALL_RADIUS - q[2], mass * GRAVITY / model.contact_stiffness, rtol=0.01)


def test_the_fast_stepper_drops_the_ball_as_the_reference_does():
    """The 1 kg ball at 0.5 m/s, dt = 0.1 ms: the fast stepper's drop is the reference stepper's to 1e-6."""
    fast, reference = measured(1.0, 0.5, 1e-4, "fast")[0], measured(1.0, 0.5, 1e-4)[0]
    np.testing.assert_allclose(fast, reference, rtol=1e-6)
