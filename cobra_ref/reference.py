"""Joint references q_ref(t), qd_ref(t), qdd_ref(t) for the 11 joints.

A reference is any object with ``__call__(t) -> (q, qd, qdd)`` (three (11,) arrays). Two kinds
live here: the built-in lateral-rolling sinusoid used until the gait library (issue 4) lands,
and references read from a file (``cobra-ref simulate --reference FILE``).

Built-in "rolling" (notes B9, fixed-shape lateral rolling in a C shape)::

    theta_i = A cos(phi(t))   for yaw joints (i even)
    theta_i = A sin(phi(t))   for pitch joints (i odd),
    phi' = omega r(t),  omega = 2 pi f,  r(t) = smoothstep(t / T_ramp) = 3 s^2 - 2 s^3

The *rolling rate* is ramped, not the amplitude: the robot starts at rest in its fixed C shape
lying flat (phi = 0: all bending in the yaw joints) and speeds up over T_ramp, so qd and qdd
start at zero and the start is not impulsive. (Ramping the amplitude instead stands the
growing arc up on its middle within the first half cycle, and it falls over with an impact.)
Defaults A = 0.5 rad, f = 0.5 Hz, T_ramp = 1 / f (one cycle).

Reference files: ``.npz`` with arrays ``t`` (N,) and ``q`` (N, 11), or ``.csv`` with a header
row ``t,J0,...,J10``; times strictly increasing, N >= 4, finite values; interpolated with a
C2 cubic spline, held constant after the last sample.
"""

from __future__ import annotations

import os
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

N_JOINTS = 11


class ReferenceError(ValueError):
    """A reference that cannot be used (the message names the problem)."""


def smoothstep(t: float, T: float):
    """r, r', r'' of r(t) = 3 s^2 - 2 s^3, s = t / T clipped to [0, 1]."""
    if T <= 0:
        return 1.0, 0.0, 0.0
    s = min(max(t / T, 0.0), 1.0)
    if s >= 1.0:
        return 1.0, 0.0, 0.0
    return 3 * s**2 - 2 * s**3, (6 * s - 6 * s**2) / T, (6 - 12 * s) / T**2


def ramped_phase(t: float, omega: float, T: float):
    """phi, phi', phi'' with phi' = omega r(t): the integral of the smoothstep ramp.

    For t < T: phi = omega T (s^3 - s^4 / 2), s = t / T; afterwards phi grows at omega.
    """
    r, rd, _ = smoothstep(t, T)
    if T <= 0:
        return omega * t, omega, 0.0
    s = min(max(t / T, 0.0), 1.0)
    phi = omega * T * (s**3 - s**4 / 2) + omega * max(t - T, 0.0)
    return phi, omega * r, omega * rd


@dataclass(frozen=True)
class RollingReference:
    """Built-in C-shaped lateral rolling sinusoid (see the module docstring)."""

    amplitude: float = 0.5
    frequency: float = 0.5
    ramp_time: float | None = None

    def __post_init__(self):
        for name in ("amplitude", "frequency"):
            v = getattr(self, name)
            if not (np.isfinite(v) and v > 0):
                raise ReferenceError(f"{name} must be positive and finite, got {v}")

    def __call__(self, t: float):
        T = 1.0 / self.frequency if self.ramp_time is None else self.ramp_time
        phi, phid, phidd = ramped_phase(t, 2 * np.pi * self.frequency, T)
        yaw = np.arange(N_JOINTS) % 2 == 0
        # theta = A cos(phi) (yaw), A sin(phi) (pitch); chain rule for the derivatives
        q = self.amplitude * np.where(yaw, np.cos(phi), np.sin(phi))
        dq = self.amplitude * np.where(yaw, -np.sin(phi), np.cos(phi))  # d theta / d phi
        return q, dq * phid, -q * phid**2 + dq * phidd


class SplineReference:
    """A reference sampled in a file, interpolated by a C2 cubic spline."""

    def __init__(self, t, q, source: str = "reference"):
        t = np.asarray(t, dtype=float)
        q = np.asarray(q, dtype=float)
        if t.ndim != 1 or len(t) < 4:
            raise ReferenceError(f"{source}: 't' must be 1-D with at least 4 samples, got shape {t.shape}")
        if q.shape != (len(t), N_JOINTS):
            raise ReferenceError(f"{source}: 'q' must have shape ({len(t)}, {N_JOINTS}), got {q.shape}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(q))):
            raise ReferenceError(f"{source}: non-finite values in t or q")
        if np.any(np.diff(t) <= 0):
            raise ReferenceError(f"{source}: times must be strictly increasing")
        self.t_end = t[-1]
        self._spline = CubicSpline(t, q, axis=0, bc_type="natural")

    def __call__(self, t: float):
        tt = min(t, self.t_end)
        q = self._spline(tt)
        if t > self.t_end:
            return q, np.zeros(N_JOINTS), np.zeros(N_JOINTS)
        return q, self._spline(tt, 1), self._spline(tt, 2)


def load_reference(path: str) -> SplineReference:
    """Read a reference file (.npz or .csv, see the module docstring) with clear errors."""
    if not os.path.isfile(path):
        raise ReferenceError(f"reference file not found: {path}")
    try:
        if path.endswith(".npz"):
            with np.load(path) as data:
                if "t" not in data or "q" not in data:
                    raise ReferenceError(f"{path}: NPZ needs arrays 't' and 'q', found {sorted(data.files)}")
                return SplineReference(data["t"], data["q"], path)
        if path.endswith(".csv"):
            with open(path) as f:
                header = f.readline().strip().split(",")
            expected = ["t"] + [f"J{i}" for i in range(N_JOINTS)]
            if [h.strip() for h in header] != expected:
                raise ReferenceError(f"{path}: CSV header must be {','.join(expected)}")
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
            return SplineReference(data[:, 0], data[:, 1:], path)
    except ReferenceError:
        raise
    except Exception as exc:  # unreadable numbers, bad zip, wrong column count ...
        raise ReferenceError(f"{path}: malformed reference file ({exc})") from exc
    raise ReferenceError(f"{path}: unknown reference format; use .npz (t, q) or .csv (t,J0..J10)")


BUILTIN = {"rolling": RollingReference}


def builtin_reference(name: str):
    """A built-in reference by name, with a clear error for an unknown one."""
    if name not in BUILTIN:
        raise ReferenceError(f"unknown reference {name!r}; built-in references: {', '.join(BUILTIN)}")
    return BUILTIN[name]()
