"""The position servo over one step (compliance.servo_rows, assumption A7): stable, and second order.

The step applies tau = kp (q_ref - q) + kd (qd_ref - qd) to a joint as
f = -kp (e + theta dt w) - kd (theta_d w + (1 - theta_d) qd - qd_ref), e = q - q_ref and
(q_ref, qd_ref) at the step's start, w the rate after it, theta = 0 up to dt = kd / kp = 10 ms and
theta_d = max(1/2, 1 - I / (kd dt)) (``servo_theta``). Worked examples: the step's map is stable
for every joint inertia at every allowed dt and never flips the error's sign; and one joint
tracking a sine converges to the exact solution of the servo's ODE at second order in dt (the
fast stepper takes the reference stepper's steps on COBRA, tests/test_simulate.py).
"""

import dataclasses

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from cobra_ref.compliance import servo_rows, servo_theta
from cobra_ref.robots import chain
from cobra_ref.simulate import simulate
from cobra_ref.step import StepSettings
from cobra_ref.infra.validation import DT_MAX, DT_MIN

KP, KD = 500.0, 5.0  # the servo's gains (A7)


@dataclasses.dataclass
class _Gains:
    servo_kp: float = KP
    servo_kd: float = KD


def servo_map(inertia: float, dt: float) -> np.ndarray:
    """The 2 x 2 matrix A with (e+, dt w+) = A (e, dt w) of one servoed joint of inertia I, its
    reference at rest at 0 and no torque limit.

    The row's optimality condition w+ + R x + b = 0 with w+ = w + x / I (G = 1 / I), then
    e+ = e + dt w+; (R, b) from ``servo_rows``, linear in (e, w).
    """
    A = np.zeros((2, 2))
    for j, (e, u) in enumerate([(1.0, 0.0), (0.0, 1.0)]):
        w = u / dt
        R, b = servo_rows(_Gains(), np.array([e]), np.array([w]), 0.0, 0.0, np.array([1.0 / inertia]), dt)
        x = -(w + b[0]) / (1.0 / inertia + R[0])
        w_next = w + x / inertia
        A[:, j] = e + dt * w_next, dt * w_next
    return A


@pytest.mark.parametrize("dt", [DT_MIN, 2.5e-4, 5e-4, 1e-3, 2e-3, DT_MAX])
def test_a_servo_step_is_stable_for_every_inertia_and_never_flips_the_error(dt):
    """kp = 500 N m/rad, kd = 5 N m s/rad. For joint inertias from 1e-5 to 100 kg m^2 (COBRA's
    joints see 1.5e-3 to 6.5e-3) the map has its eigenvalues inside the unit circle (the
    condition kp dt^2 (1 - 2 theta) < 4 I + 2 (2 theta_d - 1) kd dt of compliance.py), and no
    real eigenvalue is negative: no mode of the step changes the error's sign every step. The
    trapezoidal damper alone (theta_d = 1/2 for every joint) would flip it on a light joint:
    its factor 1 - kd dt / (2 I) is -0.5 at I = kd dt / 3."""
    for inertia in np.logspace(-5, 2, 29):
        eig = np.linalg.eigvals(servo_map(inertia, dt))
        assert np.abs(eig).max() < 1.0, f"I {inertia:.2e} kg m^2, dt {dt * 1e3:g} ms: eigenvalues {eig}"
        real = eig[np.abs(eig.imag) <= 1e-12 * np.abs(eig).max()].real
        assert real.min(initial=0.0) >= -1e-12, f"I {inertia:.2e}, dt {dt * 1e3:g} ms: eigenvalues {eig}"
    light = KD * dt / 3
    theta, theta_d = servo_theta(np.array([1.0 / light]), KP, KD, dt)
    assert theta == 0.0 and theta_d[0] == pytest.approx(1.0 - light / (KD * dt))
    assert 1.0 - KD * dt / (2 * light) == pytest.approx(-0.5)


def test_the_servo_weighs_its_damper_half_and_half_on_a_resolved_joint():
    """theta_d = 1/2 (the trapezoidal rule) once I >= kd dt / 2, and theta = 0 (the spring at the
    step's start) up to dt = kd / kp = 10 ms; above it the spring moves towards the step's end as
    the contact's does, theta = 1 - kd / (kp dt)."""
    theta, theta_d = servo_theta(1.0 / np.array([1e-3, 2.5e-3, 5e-3]), KP, KD, 1e-3)
    np.testing.assert_allclose(theta_d, [0.8, 0.5, 0.5])
    assert theta == 0.0
    assert servo_theta(np.array([1.0]), KP, KD, 20e-3)[0] == pytest.approx(0.5)


def _one_joint(mass: float = 0.2):
    """chain(1) lifted 1 m off the ground: one link yawing (Rz) about a vertical axis, so gravity
    exerts no torque on its joint; I = m (3 r^2 + L^2) / 12 + m (L / 2)^2 about the joint; a
    torque limit (100 N m) the servo never reaches."""
    model = chain(1, link_mass=mass)
    model = dataclasses.replace(model, tree_pos=(np.array([0.0, 0.0, 1.0]),), tau_limit=(100.0,))
    length, radius = 0.3, 0.03
    return model, mass * (3 * radius**2 + length**2) / 12 + mass * (length / 2) ** 2


def test_one_servoed_joint_tracks_a_sine_at_second_order_in_dt(amplitude=0.5, f=1.0, T=1.0):
    """I q'' = kp (r - q) + kd (r' - q') with r = 0.5 sin(2 pi t), from rest, against the ODE's
    solution (rtol 1e-12). The joint's angle at T = 1 s: the error falls by a factor of about four
    per halving of dt (at least 3.5), and is below 1e-6 rad at 1 ms, where the servo's lag behind
    the sine is at most 2.4e-4 rad."""
    model, inertia = _one_joint()
    w = 2 * np.pi * f

    def reference(t):
        return (np.array([amplitude * np.sin(w * t)]), np.array([amplitude * w * np.cos(w * t)]),
                np.array([-amplitude * w * w * np.sin(w * t)]))

    def rhs(t, y):
        r, rd, _ = reference(t)
        return [y[1], (KP * (r[0] - y[0]) + KD * (rd[0] - y[1])) / inertia]

    exact = solve_ivp(rhs, (0.0, T), [0.0, 0.0], method="DOP853", rtol=1e-12, atol=1e-14).y[0, -1]
    errors = []
    for dt in (2e-3, 1e-3, 5e-4):
        traj = simulate(model, reference, T, StepSettings(dt=dt), np.zeros(1), np.zeros(1), stepper="reference")
        errors.append(abs(traj.q[-1, 0] - exact))
    print(f"\n|q(1 s) - exact| at dt = 2 / 1 / 0.5 ms: {errors}")
    assert errors[0] / errors[1] >= 3.5 and errors[1] / errors[2] >= 3.5, errors
    assert errors[1] < 1e-6, errors
