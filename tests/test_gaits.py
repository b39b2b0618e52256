"""The gait library (cobra_ref/gaits.py, assumption A10): shapes by hand, limits, smoothness, periodicity."""

import numpy as np
import pytest

from cobra_ref.gaits import GAITS, YAW, GaitError, RollingGait, SidewindingGait, gait, ramped_phase
from cobra_ref.params import CobraParameters

T_RUN, DT = 10.0, 1e-3  # the paper's run time (assumption A11) and our step
NAMES = ["C", "S", "J", "J-mirror", "sidewinding"]


def _sample(g, t):
    q, qd, qdd = zip(*(g(tk) for tk in t))
    return np.array(q), np.array(qd), np.array(qdd)


@pytest.mark.parametrize("name", NAMES)
def test_every_gait_stays_within_the_joint_limits_for_the_whole_run(name):
    q, _, _ = _sample(gait(name), np.arange(0.0, T_RUN, DT))
    assert np.abs(q).max() <= CobraParameters().q_max
    # and within its own amplitude: A for rolling, max(A_y, A_p) for sidewinding
    g = gait(name)
    A = g.amplitude if isinstance(g, RollingGait) else max(g.amplitude_yaw, g.amplitude_pitch)
    assert np.abs(q).max() <= A + 1e-12


@pytest.mark.parametrize("name", NAMES)
def test_every_gait_starts_at_rest_and_its_derivatives_are_consistent(name):
    """qd(0) = qdd(0) = 0 (the phase rate ramps in from zero), and qd, qdd are the time
    derivatives of q and qd: central differences agree to O(h^2)."""
    g = gait(name)
    _, qd0, qdd0 = g(0.0)
    np.testing.assert_allclose(qd0, 0.0, atol=1e-15)
    np.testing.assert_allclose(qdd0, 0.0, atol=1e-15)
    h = 1e-5
    for t in [0.3, 1.7, 2.0 + 1e-3, 6.1]:  # inside the ramp, across its end, steady
        q_p, qd_p, _ = g(t + h)
        q_m, qd_m, _ = g(t - h)
        _, qd, qdd = g(t)
        np.testing.assert_allclose((q_p - q_m) / (2 * h), qd, atol=1e-8)
        np.testing.assert_allclose((qd_p - qd_m) / (2 * h), qdd, atol=1e-5)


@pytest.mark.parametrize("name", NAMES)
def test_every_gait_is_smooth_with_accelerations_bounded_by_A_omega_squared(name):
    """Steady state: |qdd| <= A omega^2. During the ramp phi'' adds at most A omega 1.5 / T_ramp."""
    g = gait(name)
    omega = 2 * np.pi * g.frequency
    A = g.amplitude if isinstance(g, RollingGait) else max(g.amplitude_yaw, g.amplitude_pitch)
    _, qd, qdd = _sample(g, np.arange(0.0, T_RUN, DT))
    assert np.abs(qd).max() <= A * omega + 1e-12
    assert np.abs(qdd).max() <= A * omega**2 + A * omega * 1.5 * g.frequency + 1e-9


@pytest.mark.parametrize("name", NAMES)
def test_every_gait_is_periodic_after_the_ramp(name):
    g = gait(name)
    period = 1.0 / g.frequency
    for t in np.linspace(period, 3 * period, 17):  # the ramp lasts one period by default
        for a, b in zip(g(t), g(t + period)):
            np.testing.assert_allclose(a, b, atol=1e-12)


def test_the_mirrored_J_is_the_J_reflected_in_the_robots_vertical_plane():
    """A reflection y -> -y negates every yaw angle and keeps every pitch angle."""
    J, Jm = gait("J"), gait("J-mirror")
    M = np.where(YAW, -1.0, 1.0)
    for t in np.linspace(0.0, 5.0, 23):
        for a, b in zip(J(t), Jm(t)):
            np.testing.assert_allclose(b, M * a, atol=1e-15)


def test_rolling_shapes_by_hand_at_phase_zero():
    """At phi = 0 all bending is in the yaw joints: theta_yaw = kappa, theta_pitch = 0."""
    A = 0.5
    q_C = RollingGait(shape="C")(0.0)[0]
    np.testing.assert_allclose(q_C, np.where(YAW, A, 0.0))
    q_S = RollingGait(shape="S")(0.0)[0]
    np.testing.assert_allclose(q_S[[0, 2, 4, 6, 8, 10]], A * np.cos(np.pi * np.array([0, 2, 4, 6, 8, 10]) / 10))
    assert q_S[0] == pytest.approx(A) and q_S[10] == pytest.approx(-A)  # S: opposite bends at the two ends
    q_J = RollingGait(shape="J")(0.0)[0]
    np.testing.assert_allclose(q_J, [A, 0, A, 0, A, 0, 0, 0, 0, 0, 0])  # the hook: joints with s_i <= 0.5


def test_sidewinding_by_hand_after_the_ramp():
    """theta_i = A sin(phi - Omega i (+ delta for pitch)), phi = omega (t - T_ramp / 2) after the ramp
    (the smoothstep ramp integrates to omega T / 2 over T)."""
    g = SidewindingGait()
    t = 3.3
    omega = 2 * np.pi * g.frequency
    phi = omega * (t - 1.0 / g.frequency / 2)
    assert ramped_phase(t, omega, 1.0 / g.frequency)[0] == pytest.approx(phi)
    i = np.arange(11)
    expected = 0.6 * np.sin(phi - 0.57 * i + np.where(YAW, 0.0, np.pi / 4))
    np.testing.assert_allclose(g(t)[0], expected, atol=1e-12)


@pytest.mark.parametrize("make, message", [
    (lambda: RollingGait(amplitude=-0.1), r"amplitude = -0.1 rad is out of range \(allowed: \(0, pi/2\] rad\)"),
    (lambda: RollingGait(amplitude=2.0), r"amplitude = 2 rad is out of range \(allowed: \(0, pi/2\] rad\)"),
    (lambda: RollingGait(frequency=float("nan")), "frequency = nan is not finite"),
    (lambda: RollingGait(frequency=-0.5), r"frequency = -0.5 Hz is out of range \(allowed: \(0, 10\] Hz\)"),
    (lambda: RollingGait(shape="U"), "shape = 'U' is unknown"),
    (lambda: SidewindingGait(amplitude_pitch=float("nan")), "amplitude_pitch = nan is not finite"),
    (lambda: gait("slithering"), "name = 'slithering' is unknown"),
])
def test_bad_gait_parameters_raise_naming_the_parameter(make, message):
    with pytest.raises(GaitError, match=message):
        make()


def test_every_named_gait_is_listed():
    assert set(NAMES) | {"rolling"} == set(GAITS)
