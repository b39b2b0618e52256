"""Joint references q_ref(t), qd_ref(t), qdd_ref(t) for the 11 joints.

A reference is any object with ``__call__(t) -> (q, qd, qdd)`` (three (11,) arrays): a gait of
:mod:`cobra_ref.gaits` (``builtin_reference(name)``: rolling = C, S, J, J-mirror, sidewinding),
or a reference read from a file (``cobra-ref simulate --reference FILE``).

Reference files: ``.npz`` with arrays ``t`` (N,) and ``q`` (N, 11), or ``.csv`` with a header
row ``t,J0,...,J10``; times strictly increasing, N >= 4, finite values; interpolated with a
C2 cubic spline, held constant after the last sample.
"""

from __future__ import annotations

import os

import numpy as np
from scipy.interpolate import CubicSpline

from .gaits import N_JOINTS, GaitError, gait


class ReferenceError(ValueError):
    """A reference that cannot be used (the message names the problem)."""


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
    """Read a reference file (.npz or .csv, see the module docstring) with clear errors.

    Helper: joint references for the stepper.
    """
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


def builtin_reference(name: str):
    """A built-in reference (a gait of :mod:`cobra_ref.gaits` with its defaults) by name, with a
    clear error for an unknown one.

    Helper: joint references for the stepper.
    """
    try:
        return gait(name)
    except GaitError as exc:
        raise ReferenceError(str(exc)) from None
