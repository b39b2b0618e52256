"""The gait library: joint references q_ref(t), qd_ref(t), qdd_ref(t) for COBRA's 11 joints.

Implements: the fixed-shape lateral rolling (C, S, J and the mirrored J) and the sidewinding of
[COBRA] sec. "Results", written for COBRA's joints (assumption A3; joints i = 0..10 from the head,
yaw Y = {0, 2, ..., 10}, pitch P = {1, 3, ..., 9}, s_i = i / 10, omega = 2 pi f)::

    rolling:      theta_i = kappa_i cos(phi(t))             i in Y
                  theta_i = kappa_i sin(phi(t))             i in P
    sidewinding:  theta_i = A_y sin(phi(t) - Omega i)       i in Y
                  theta_i = A_p sin(phi(t) - Omega i + delta)   i in P

    phi(t) = phi_0 + integral_0^t omega r(s) ds,   r = smoothstep(t / T_ramp) = 3 s^2 - 2 s^3

The *phase rate* is ramped in over T_ramp (default one period, 1 / f): the robot starts at
rest (qd = qdd = 0 at t = 0) in the gait's shape at phi_0, and is at the steady gait from
T_ramp on. (Ramping the amplitude instead stands a growing rolling arc up on its middle within
half a cycle, and it falls over with an impact.)

Bend profiles kappa_i of the rolling shapes (defaults: assumption A10):

    C          kappa_i = A                                 constant curvature, an arc
    S          kappa_i = A cos(pi s_i)                     curvature changes sign at the middle (J5)
    J          kappa_i = A for s_i <= s_J, else 0          a hook at the head, straight tail (s_J = 0.5)
    J-mirror   the J reflected in the robot's vertical plane (y -> -y): yaw joints negated,
               pitch joints unchanged (a reflection maps a rotation about y to itself)

Every joint stays within |theta_i| <= A (rolling) or max(A_y, A_p) (sidewinding), which must be
<= q_max = pi / 2 (assumption A4); a value out of range raises ``GaitError`` (an
``infra.arguments.ArgumentError``), one that is not a number an ``ArgumentTypeError``, each
naming the parameter, the value and the allowed range.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .infra import arguments
from .infra.rule import Rule

N_JOINTS = 11
Q_MAX = np.pi / 2  # joint range, assumption A4 (CobraParameters.q_max)
YAW = np.arange(N_JOINTS) % 2 == 0  # even joints yaw, odd joints pitch
S = np.arange(N_JOINTS) / (N_JOINTS - 1)  # s_i = i / 10
SHAPES = ("C", "S", "J", "J-mirror")


class GaitError(arguments.ArgumentError):
    """A gait parameter that cannot be used (the message names it)."""


def smoothstep(t: float, T: float):
    """r, r', r'' of r(t) = 3 s^2 - 2 s^3, s = t / T clipped to [0, 1].

    The ramp-in of every gait (module docstring).
    """
    if T <= 0:
        return 1.0, 0.0, 0.0
    s = min(max(t / T, 0.0), 1.0)
    if s >= 1.0:
        return 1.0, 0.0, 0.0
    return 3 * s**2 - 2 * s**3, (6 * s - 6 * s**2) / T, (6 - 12 * s) / T**2


def ramped_phase(t: float, omega: float, T: float):
    """phi - phi_0, phi', phi'' with phi' = omega r(t): the integral of the smoothstep ramp.

    For t < T, phi = omega T (s^3 - s^4 / 2), s = t / T; afterwards phi grows at omega.
    """
    r, rd, _ = smoothstep(t, T)
    if T <= 0:
        return omega * t, omega, 0.0
    s = min(max(t / T, 0.0), 1.0)
    phi = omega * T * (s**3 - s**4 / 2) + omega * max(t - T, 0.0)
    return phi, omega * r, omega * rd


def _check(name: str, value, unit: str, low: float = 0.0, high: float = np.inf, strict: bool = True) -> None:
    """A ``GaitError`` unless ``value`` is a finite number in (low, high] (``strict``) or [low, high];
    an ``ArgumentTypeError`` for a value that is not a number (a string, a bool, None)."""
    arguments.number(name, value, Rule(name, unit, low, high, low_open=strict), GaitError)


@dataclass(frozen=True)
class _Periodic:
    """Frequency, phase offset and ramp shared by every gait (see the module docstring)."""

    frequency: float = 0.5  # f [Hz] (assumption A10)
    phase: float = 0.0  # phi_0 [rad]
    ramp_time: float | None = None  # T_ramp [s]; None = one period

    def _phase(self, t: float):
        T = 1.0 / self.frequency if self.ramp_time is None else self.ramp_time
        phi, phid, phidd = ramped_phase(t, 2 * np.pi * self.frequency, T)
        return self.phase + phi, phid, phidd

    def _check_periodic(self) -> None:
        _check("frequency", self.frequency, "Hz", high=10.0)
        _check("phase", self.phase, "rad", low=-np.inf)
        if self.ramp_time is not None:
            _check("ramp_time", self.ramp_time, "s", strict=False)


@dataclass(frozen=True)
class RollingGait(_Periodic):
    """Fixed-shape lateral rolling in the planar bend profile ``shape`` (C, S, J, J-mirror).

    Implements: [COBRA] C-, S- and J-shaped lateral rolling (assumption A10).
    """

    shape: str = "C"
    amplitude: float = 0.5  # A [rad] (assumption A10)
    s_J: float = 0.5  # J only: the hook spans s_i <= s_J (assumption A10)

    def __post_init__(self):
        arguments.choice("shape", self.shape, SHAPES, GaitError)
        _check("amplitude", self.amplitude, "rad", high=Q_MAX)
        _check("s_J", self.s_J, "-", strict=False, high=1.0)
        self._check_periodic()
        object.__setattr__(self, "_kappa", self.kappa())  # the profile is fixed: computed once, not per call

    def kappa(self) -> np.ndarray:
        """The bend profile kappa_i [rad] of the 11 joints (module docstring)."""
        A = self.amplitude
        if self.shape == "C":
            return np.full(N_JOINTS, A)
        if self.shape == "S":
            return A * np.cos(np.pi * S)
        hook = np.where(S <= self.s_J + 1e-12, A, 0.0)
        return hook if self.shape == "J" else np.where(YAW, -hook, hook)

    def __call__(self, t: float):
        phi, phid, phidd = self._phase(t)
        q, dq = rolling_shape(self._kappa, phi)
        # chain rule: qd = dq phi', qdd = d2q phi'^2 + dq phi'', and d2q = -q for sines and cosines
        return q, dq * phid, -q * phid**2 + dq * phidd


def rolling_shape(kappa: np.ndarray, phi: float):
    """(theta, d theta / d phi) of lateral rolling with the bend profile kappa at the phase phi:
    theta_i = kappa_i cos(phi) on the yaw joints, kappa_i sin(phi) on the pitch joints."""
    q = kappa * np.where(YAW, np.cos(phi), np.sin(phi))
    dq = kappa * np.where(YAW, -np.sin(phi), np.cos(phi))
    return q, dq


@dataclass(frozen=True)
class SidewindingGait(_Periodic):
    """Sidewinding: the compound serpenoid with COBRA's parity (defaults: assumption A10).

    Implements: [COBRA] sidewinding (assumption A10).
    """

    amplitude_yaw: float = 0.6  # A_y [rad]
    amplitude_pitch: float = 0.6  # A_p [rad]
    spatial_frequency: float = 0.57  # Omega [rad per joint], about one wavelength on the body
    delta: float = np.pi / 4  # pitch-yaw phase offset [rad]

    def __post_init__(self):
        _check("amplitude_yaw", self.amplitude_yaw, "rad", high=Q_MAX)
        _check("amplitude_pitch", self.amplitude_pitch, "rad", high=Q_MAX)
        _check("spatial_frequency", self.spatial_frequency, "rad", low=-np.inf)
        _check("delta", self.delta, "rad", low=-np.inf)
        self._check_periodic()

    def __call__(self, t: float):
        phi, phid, phidd = self._phase(t)
        q, dq = self.shape(phi)
        return q, dq * phid, -q * phid**2 + dq * phidd

    def shape(self, phi: float):
        """(theta, d theta / d phi) at the phase phi: A_i sin(phi - Omega i + delta_i), delta_i = 0 on
        the yaw joints and delta on the pitch joints."""
        arg = phi - self.spatial_frequency * np.arange(N_JOINTS) + np.where(YAW, 0.0, self.delta)
        A = np.where(YAW, self.amplitude_yaw, self.amplitude_pitch)
        return A * np.sin(arg), A * np.cos(arg)


GAITS = {
    "rolling": (RollingGait, {"shape": "C"}),  # the built-in reference's first name
    "C": (RollingGait, {"shape": "C"}),
    "S": (RollingGait, {"shape": "S"}),
    "J": (RollingGait, {"shape": "J"}),
    "J-mirror": (RollingGait, {"shape": "J-mirror"}),
    "sidewinding": (SidewindingGait, {}),
}


def gait(name: str, **params):
    """The gait ``name`` with its default parameters, or with ``params`` (the dataclass fields:
    amplitude, frequency, phase, ramp_time, s_J, ... ) replacing them; a clear error for an
    unknown gait or parameter.
    """
    arguments.choice("name", name, tuple(GAITS), GaitError)
    cls, fixed = GAITS[name]
    allowed = [f for f in cls.__dataclass_fields__ if f not in fixed]
    unknown = sorted(set(params) - set(allowed))
    if unknown:
        raise GaitError(f"unknown parameter(s) {', '.join(unknown)} for gait {name!r}; use {', '.join(allowed)}")
    return cls(**fixed, **params)


def gait_params(g) -> dict:
    """The free parameters of a gait object as a JSON-ready dict (the inverse of ``gait``); an
    ``infra.arguments.ArgumentTypeError`` for anything that is not a gait of ``GAITS``.
    """
    arguments.instance("g", g, (RollingGait, SidewindingGait), "gait('C')")
    return {f: getattr(g, f) for f in g.__dataclass_fields__ if f != "shape"}
