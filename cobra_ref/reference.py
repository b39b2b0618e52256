"""Joint references q_ref(t), qd_ref(t), qdd_ref(t) for the 11 joints.

A reference is any object with ``__call__(t) -> (q, qd, qdd)`` (three (11,) arrays): a gait of
:mod:`cobra_ref.gaits` (``builtin_reference(name)``: rolling = C, S, J, J-mirror, sidewinding),
or a reference read from a file (``cobra-ref simulate --reference FILE``).

Reference files: ``.npz`` with arrays ``t`` (N,) and ``q`` (N, 11), or ``.csv`` with a header
row ``t,J0,...,J10``; times strictly increasing from t >= 0, N >= 4, finite values, every joint
angle within the joint limit |q| <= q_max (pi/2, assumption A4); interpolated with a C2 cubic
spline, held constant after the last sample. ``check_reference`` checks a reference over a run:
its angles (between the samples too) within q_max (a refusal naming the joint, the time and the
value), its rates against the speed limit qd_max (a warning: the limit is reported, not
enforced, assumption A6).
"""

from __future__ import annotations

import os

import numpy as np
from scipy.interpolate import CubicSpline

from .gaits import N_JOINTS, Q_MAX, GaitError, gait
from .infra import arguments
from .infra.validation import PARAMETER_RULES

QD_MAX = 3.77  # [rad/s] the joint speed limit (CobraParameters.qd_max, assumption A6)
CHECK_SAMPLES = 5000  # a reference is checked at this many times over a run (and at its own samples)


class ReferenceError(arguments.ArgumentError):
    """A reference that cannot be used (the message names the problem)."""


class SplineReference:
    """A reference sampled in a file, interpolated by a C2 cubic spline."""

    def __init__(self, t, q, source: str = "reference", q_max: float = Q_MAX):
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
        if t[0] < 0:
            raise ReferenceError(f"{source}: times must start at t >= 0 s, got t = {t[0]:g} s")
        _check_angles(source, t, q, q_max)
        self.t_end = t[-1]
        self.t_samples, self.q_samples = t, q
        self._spline = CubicSpline(t, q, axis=0, bc_type="natural")

    def __call__(self, t: float):
        tt = min(t, self.t_end)
        q = self._spline(tt)
        if t > self.t_end:
            return q, np.zeros(N_JOINTS), np.zeros(N_JOINTS)
        return q, self._spline(tt, 1), self._spline(tt, 2)


def load_reference(path: str, q_max: float = Q_MAX) -> SplineReference:
    """Read a reference file (.npz or .csv, see the module docstring) with clear errors; every
    sample's angle within ``q_max`` [rad] (the rule of ``CobraParameters.q_max``). A ``path`` that
    is not a file name or a ``q_max`` that is not a number raises an ``infra.arguments``
    ``ArgumentTypeError``, a ``q_max`` out of its range a ``ReferenceError``.
    """
    path = arguments.path("path", path)
    q_max = arguments.number("q_max", q_max, PARAMETER_RULES["q_max"], ReferenceError)
    if not os.path.isfile(path):
        raise ReferenceError(f"reference file not found: {path}")
    try:
        if path.endswith(".npz"):
            with np.load(path) as data:
                if "t" not in data or "q" not in data:
                    raise ReferenceError(f"{path}: NPZ needs arrays 't' and 'q', found {sorted(data.files)}")
                return SplineReference(data["t"], data["q"], path, q_max)
        if path.endswith(".csv"):
            with open(path) as f:
                header = f.readline().strip().split(",")
            expected = ["t"] + [f"J{i}" for i in range(N_JOINTS)]
            if [h.strip() for h in header] != expected:
                raise ReferenceError(f"{path}: CSV header must be {','.join(expected)}")
            data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
            return SplineReference(data[:, 0], data[:, 1:], path, q_max)
    except ReferenceError:
        raise
    except Exception as exc:  # unreadable numbers, bad zip, wrong column count ...
        raise ReferenceError(f"{path}: malformed reference file ({exc})") from exc
    raise ReferenceError(f"{path}: unknown reference format; use .npz (t, q) or .csv (t,J0..J10)")


def builtin_reference(name: str, params: dict | None = None):
    """A built-in reference (a gait of :mod:`cobra_ref.gaits`) by name, with its defaults or with
    ``params`` = {parameter: value} replacing them; a clear error for an unknown gait, an unknown
    parameter or a value the gait refuses.
    """
    try:
        return gait(name, **(params or {}))
    except GaitError as exc:
        raise ReferenceError(str(exc)) from None
    except (TypeError, ValueError) as exc:
        raise ReferenceError(f"gait {name!r}: {exc}") from None


def check_reference(reference, duration: float, q_max: float = Q_MAX, qd_max: float = QD_MAX,
                    source: str = "reference") -> list[str]:
    """Check a reference over [0, duration]: angles within ``q_max`` [rad] (a ``ReferenceError``
    naming the joint, the time and the value), rates within ``qd_max`` [rad/s] (a list of at most
    one warning naming the joints over the limit: the speed limit is reported, not enforced, A6).

    The input check of ``cobra-ref simulate``. The reference is evaluated at ``CHECK_SAMPLES``
    evenly spaced times and, for a file, at its own samples within the run.
    """
    times = np.linspace(0.0, float(duration), CHECK_SAMPLES)
    samples = getattr(reference, "t_samples", None)
    if samples is not None:
        times = np.union1d(times, samples[samples <= duration])
    if isinstance(reference, SplineReference):  # vectorised: the spline at every time at once
        tt = np.minimum(times, reference.t_end)
        q = reference._spline(tt)
        qd = np.where((times > reference.t_end)[:, None], 0.0, reference._spline(tt, 1))
    else:
        values = [reference(float(t)) for t in times]
        q = np.array([v[0] for v in values], dtype=float)
        qd = np.array([v[1] for v in values], dtype=float)
    if not (np.all(np.isfinite(q)) and np.all(np.isfinite(qd))):
        k = int(np.flatnonzero(~(np.isfinite(q).all(axis=1) & np.isfinite(qd).all(axis=1)))[0])
        raise ReferenceError(f"{source}: the joint reference is not finite at t = {times[k]:.4f} s")
    _check_angles(f"{source} (interpolated)" if samples is not None else source, times, q, q_max)
    over = np.abs(qd) > qd_max
    if not over.any():
        return []
    joints = np.flatnonzero(over.any(axis=0))
    k, j = np.unravel_index(int(np.argmax(np.abs(qd))), qd.shape)
    plural = len(joints) > 1
    return [f"{source}: joint{'s' if plural else ''} {', '.join(f'J{i}' for i in joints)} "
            f"{'move' if plural else 'moves'} faster "
            f"than the servo's speed limit qd_max = {qd_max:g} rad/s (up to {abs(qd[k, j]):.3g} rad/s, J{j} at "
            f"t = {times[k]:.3f} s; over the limit {100 * over.any(axis=1).mean():.0f} % of the run): reported in "
            "the NPZ (qd_excess), not enforced (assumption A6)"]


def _check_angles(source: str, t, q, q_max: float) -> None:
    """A ReferenceError naming the first joint, time and angle beyond |q| <= q_max."""
    q = np.asarray(q, dtype=float)
    bad = np.abs(q) > q_max * (1 + 1e-12)
    if bad.any():
        k, j = (int(v) for v in np.argwhere(bad)[0])
        worst = float(np.abs(q[:, j]).max())
        raise ReferenceError(f"{source}: joint J{j} = {q[k, j]:.4g} rad at t = {t[k]:.4g} s is beyond the joint "
                             f"limit |q| <= q_max = {q_max:.4f} rad (assumption A4; largest |J{j}| = {worst:.4g} "
                             "rad)")
