"""The compliant contact's spring-damper over one step: where the spring and the damper act (compliance.py).

The step applies f = -k (g + theta dt w) - d (theta_d w + (1 - theta_d) w_0) to a penetrating
contact's gap g, w its rate after the step and w_0 before it, with theta = max(0, 1 - d / (k dt))
(``contact_theta``) and theta_d = 1 / (1 - exp(-h)) - 1 / h, h = d dt / m_c (``contact_theta_d``).
Worked examples: the step is stable and never overshoots, for every contact mass and time step; it
adds no numerical damping while dt <= d / k; its damper decays a contact's rate by exp(-h) per
step, as the damper does, and tends to the trapezoid as dt -> 0; and a ball's rebound on a lightly
damped ground then matches the exact solution of the contact law's ODE.
"""

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bodies import BALL_MASS, BALL_RADIUS, GRAVITY, at_height, ball, run
from cobra_ref.compliance import CONTACT_LAWS, contact_theta, contact_theta_d
from cobra_ref.step import StepSettings
from cobra_ref.infra.validation import DT_MAX, DT_MIN


def step_map(model, mass: float, dt: float) -> np.ndarray:
    """The 2 x 2 matrix A with (g+, w+) = A (g, w) of one engaged contact of mass ``mass`` without gravity.

    The contact row's optimality condition w+ + R x + b = 0 with w+ = w + x / mass (G = 1 / mass),
    then g+ = g + dt w+; (R, b) from the compliant law's ``normal_rows`` of a contact that penetrates
    through the step's window (g <= 0, its rate before the step w), which is linear in (g, w) (b = 0
    at g = w = 0): the columns are probed at g = -1 (and negated) and w = 1 (at g = 0).
    """
    A = np.zeros((2, 2))
    for j, (g, w, sign) in enumerate([(-1.0, 0.0, -1.0), (0.0, 1.0, 1.0)]):
        R, b = np.broadcast_arrays(*CONTACT_LAWS["compliant"].normal_rows(model, np.array([g]), np.array([1.0 / mass]),
                                                                          dt, np.array([w])))
        x = -(w + b[0]) / (1.0 / mass + R[0])
        w_next = w + x / mass
        A[:, j] = sign * (g + dt * w_next), sign * w_next
    return A


@pytest.mark.parametrize("dt", [DT_MIN, 2.5e-4, 5e-4, 1e-3, 1.5e-3, DT_MAX])
def test_a_contact_step_is_stable_for_every_mass_and_a_light_contact_never_overshoots(dt):
    """The paper's k = 1e6 N/m, d = 1e3 N s/m. For contact masses from 0.01 g to 100 kg the step's
    map has its eigenvalues inside the unit circle (stable at every allowed dt, the module
    docstring's condition k dt^2 (1 - 2 theta) < 4 m + 2 d dt). A light contact (1e-9 kg) maps its
    gap to g (1 - k dt / (d + theta k dt)): 1 - k dt / d >= 0 below dt = d / k = 1 ms and exactly 0
    above, never negative (an explicit spring, theta = 0, gives 1 - 2 = -1 at 2 ms: a gap that
    flips sign every step and never settles).
    """
    model = ball()
    k, d = model.contact_stiffness, model.contact_damping
    for mass in np.logspace(-5, 2, 29):
        radius = np.abs(np.linalg.eigvals(step_map(model, mass, dt))).max()
        assert radius < 1.0, f"mass {mass:.2e} kg, dt {dt * 1e3:g} ms: spectral radius {radius:.6f}"
    factor = step_map(model, 1e-9, dt)[0, 0]
    expected = max(0.0, 1.0 - k * dt / d)
    np.testing.assert_allclose(factor, expected, atol=1e-6)
    assert factor >= -1e-9


def test_the_contact_spring_adds_no_damping_while_dt_is_at_most_d_over_k():
    """A heavy contact (1 kg) penetrating by 10 um, rising at w_0 = 1 mm/s before the step: its row's
    impulse as a function of the rate after the step w, x(w) = -(w + b) / R, is the law by hand,
    x = -k (g + theta dt w) dt - d dt (theta_d w + (1 - theta_d) w_0). The damping on w,
    1 / (R dt) = theta_d d + theta k dt, is theta_d d up to dt = d / k (theta = 0): the rest of d
    acts on w_0, no numerical damping added; above it the spring adds k dt - d
    (theta = 1 - d / (k dt)). The backward-Euler spring (theta = 1) would double d at 1 ms."""
    model = ball()
    k, d = model.contact_stiffness, model.contact_damping
    g, w_0 = -1e-5, 1e-3
    for dt in (DT_MIN, 5e-4, 1e-3, 1.5e-3, 2e-3, DT_MAX):
        R, b = np.broadcast_arrays(*CONTACT_LAWS["compliant"].normal_rows(model, np.array([g]), np.array([1.0]), dt,
                                                                          np.array([w_0])))
        theta, theta_d = max(0.0, 1.0 - d / (k * dt)), contact_theta_d(np.array([1.0]), d, dt)[0]
        np.testing.assert_allclose(1.0 / (R[0] * dt), theta_d * d + theta * k * dt, rtol=1e-12)
        np.testing.assert_allclose(1.0 / (R[0] * dt), theta_d * d + max(0.0, k * dt - d), rtol=1e-12)
        for w in (-0.01, 0.0, 0.02):
            by_hand = -k * (g + theta * dt * w) * dt - d * dt * (theta_d * w + (1.0 - theta_d) * w_0)
            np.testing.assert_allclose(-(w + b[0]) / R[0], by_hand, rtol=1e-9)
        np.testing.assert_allclose(contact_theta(k, d, dt), theta, rtol=0, atol=1e-15)


def test_the_damper_step_decays_a_contacts_rate_as_the_damper_does():
    """A contact of mass m_c = 1 / G under the damper alone, x = -d dt (theta_d w + (1 - theta_d) w_0):
    its rate after the step is w = w_0 (1 - (1 - theta_d) h) / (1 + theta_d h), h = d dt / m_c, and
    theta_d makes that exp(-h) w_0, the damper's own decay, at every h (from 1e-9 through the
    series' switch at 1e-2 to 1e4; to 1e-11 where exp(-h) is below that formula's rounding). The
    weight is 1/2 + h / 12 + O(h^3) (the trapezoid as dt -> 0), at least the light contact's bound
    1 - 1 / h (0.9 at h = 10: within 5e-5 of it), and for the paper's d at 1 ms the 1 kg ball's
    h = 1 gives e^-1 / (1 - e^-1) = 0.58198."""
    d, dt = 1e3, 1e-3
    h = np.concatenate([np.logspace(-9, 4, 131), [1e-2 * (1 - 1e-12), 1e-2]])
    theta_d = contact_theta_d(h / (d * dt), d, dt)  # G = h / (d dt)
    decay = (1 - (1 - theta_d) * h) / (1 + theta_d * h)
    # the rounding of 1 - (1 - theta_d) h: about 1e-16 h, absolute
    np.testing.assert_allclose(decay, np.exp(-h), rtol=1e-9, atol=1e-11)
    small = h < 0.1
    np.testing.assert_allclose(theta_d[small], 0.5 + h[small] / 12, rtol=0, atol=1e-5)
    assert np.all(theta_d >= np.maximum(0.5, 1 - 1 / h))
    assert contact_theta_d(np.array([10.0 / (d * dt)]), d, dt)[0] - 0.9 < 5e-5
    np.testing.assert_allclose(contact_theta_d(np.array([1.0]), d, dt), np.exp(-1) / (1 - np.exp(-1)), rtol=1e-14)


def exact_rebound(k: float, d: float, v0: float = 1.0) -> float:
    """The speed at which a ball that lands at v0 leaves the ground under f = max(0, -k g - d g') (ODE, to 1e-10)."""
    def rhs(t, y):
        g, v = y
        force = max(0.0, -k * g - d * v) if g < 0 else 0.0
        return [v, force / BALL_MASS - GRAVITY]

    def leaves(t, y):
        return y[0] if t > 1e-3 else -1.0
    leaves.terminal, leaves.direction = True, 1
    sol = solve_ivp(rhs, (0.0, 1.0), [0.0, -v0], events=leaves, rtol=1e-10, atol=1e-12, max_step=1e-4)
    return float(sol.y_events[0][0][1])


def test_a_ball_rebounds_from_a_lightly_damped_ground_at_the_speed_of_the_exact_solution(k=1e4, zeta=0.1):
    """A 1 kg ball lands at 1 m/s on k = 1e4 N/m with damping ratio 0.1 (d = 20 N s/m; the contact
    lasts 34 ms). The exact law leaves it at 0.706 m/s; dt = 1 ms (d / (k dt) = 2: theta = 0) gives it
    within 2 % (-0.9 %). The backward-Euler spring adds k dt = 10 N s/m of damping and gives
    0.594 m/s (-16 %)."""
    d = 2 * zeta * np.sqrt(k * BALL_MASS)
    model = ball(contact_stiffness=k, contact_damping=d)
    q0, qd0 = at_height(model, BALL_RADIUS, v=(0.0, 0.0, -1.0))
    _, _, results = run(model, q0, qd0, 200, StepSettings(dt=1e-3))
    height = np.array([res.q[2] for res in results]) - BALL_RADIUS
    leaves = np.flatnonzero((height[1:] >= 0) & (height[:-1] < 0))[0] + 1
    np.testing.assert_allclose(results[leaves].qd[2], exact_rebound(k, d), rtol=0.02)
