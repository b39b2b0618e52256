"""The checks of a saved run before it is shown: every array the viewer and the renderer read.

``scene.load_run`` calls :func:`check_run` on what it read (``cobra-ref view``, ``cobra-ref
render``): the times finite and strictly increasing, one state (q, box pose) per time, each box
pose a position and a unit quaternion (``validation.check_pose``, the rule of the params JSON),
and a contact log whose arrays have one row per contact, each row's step a step of the run and its
kind one of the three contact kinds. A refusal is a ``RunError`` whose one-line message names the
file, the array, the offending value and what is allowed.
"""

from __future__ import annotations

import numpy as np

from ..infra.validation import ValidationError, check_pose, number_text
from ..trajectory import CONTACT_KEYS

N_POSE = 25  # qpos of COBRA and the box
KIND_NAMES = ("robot-ground", "robot-box", "box-ground")  # contact_kind 0, 1, 2
# the contact log's arrays with three numbers per row (a point, a direction, a force)
VECTOR_KEYS = ("contact_point", "contact_normal", "contact_force")


class RunError(ValueError):
    """A file that is not a readable cobra-ref run (the message says why)."""


def check_run(traj, path: str) -> None:
    """A ``RunError`` naming ``path``, the array and the value unless ``traj`` is a run that can be
    shown (module docstring)."""
    t = _numbers(path, "t", traj.t)
    if t.ndim != 1 or len(t) == 0:
        raise RunError(f"{path}: t has shape {t.shape}, expected (n,) with at least one time: the run holds no state")
    _check_times(path, t)
    n = len(t)
    for name, width in (("q", N_POSE), ("box_pose", 7)):
        values = _numbers(path, name, getattr(traj, name))
        if values.shape != (n, width):
            raise RunError(f"{path}: {name} has shape {values.shape}, expected ({n}, {width}): one row per time")
        rows = np.flatnonzero(~np.all(np.isfinite(values), axis=1))
        if len(rows):
            raise RunError(f"{path}: {name}[{rows[0]}] holds non-finite values (allowed: finite numbers)")
    norms = np.linalg.norm(np.asarray(traj.box_pose)[:, 3:], axis=1)
    rows = np.flatnonzero(np.abs(norms - 1.0) > 1e-6)
    if len(rows):
        try:
            check_pose(f"box_pose[{rows[0]}]", list(traj.box_pose[rows[0]]))
        except ValidationError as exc:
            raise RunError(f"{path}: {exc}") from None
    _check_contacts(path, traj.contacts, n)


def _numbers(path: str, name: str, values) -> np.ndarray:
    """``values`` as an array of real numbers (ints, floats, bools), or a RunError naming ``name``."""
    values = np.asarray(values)
    if not (np.issubdtype(values.dtype, np.number) or values.dtype == bool) or np.iscomplexobj(values):
        raise RunError(f"{path}: {name} holds {values.dtype} values (allowed: real numbers)")
    return values


def _check_times(path: str, t: np.ndarray) -> None:
    """The times: finite and strictly increasing."""
    bad = np.flatnonzero(~np.isfinite(t))
    if len(bad):
        raise RunError(f"{path}: t[{bad[0]}] = {number_text(float(t[bad[0]]))} s (allowed: finite times)")
    back = np.flatnonzero(np.diff(t) <= 0)
    if len(back):
        k = back[0]
        raise RunError(f"{path}: t[{k + 1}] = {number_text(float(t[k + 1]))} s does not follow t[{k}] = "
                       f"{number_text(float(t[k]))} s (allowed: strictly increasing times)")


def _check_contacts(path: str, contacts: dict, n: int) -> None:
    """The contact log: one row per contact in every array, steps of the run, known kinds."""
    present = [k for k in CONTACT_KEYS if k in contacts]
    lengths = {k: len(np.atleast_1d(contacts[k])) for k in present}
    if len(set(lengths.values())) > 1:
        listed = ", ".join(f"{k} {m}" for k, m in lengths.items())
        raise RunError(f"{path}: the contact log's arrays have different lengths ({listed}; allowed: one row per "
                       "contact in each)")
    for key in ("contact_body", "contact_onset_speed", "contact_gap", "contact_gap_end"):
        if key in contacts:
            _numbers(path, key, contacts[key])
    for key in VECTOR_KEYS:
        if key in contacts:
            values = _numbers(path, key, contacts[key])
            if values.ndim != 2 or values.shape[1] != 3 or not np.all(np.isfinite(values)):
                raise RunError(f"{path}: {key} has shape {values.shape} or non-finite values (allowed: (m, 3) "
                               "finite numbers, one row per contact)")
    for key, high, allowed in (("contact_step", max(n - 2, 0), f"a step of the run, 0 to {max(n - 2, 0)}"),
                               ("contact_kind", len(KIND_NAMES) - 1,
                                "0, 1, 2 (" + ", ".join(KIND_NAMES) + ")")):
        if key in contacts:
            values = _numbers(path, key, contacts[key])
            bad = np.flatnonzero(~np.isfinite(values) | (values != np.round(values)) | (values < 0) | (values > high))
            if values.ndim != 1 or len(bad):
                where = f"{key}[{bad[0]}] = {number_text(float(values[bad[0]]))}" if len(bad) else \
                    f"{key} has shape {values.shape}"
                raise RunError(f"{path}: {where} (allowed: {allowed})")
