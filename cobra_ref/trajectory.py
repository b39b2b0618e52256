"""The record of a simulation: states, torques, per-step solver and energy records, the contact log.

What ``simulate`` returns and ``cobra-ref simulate`` writes (NPZ, every array named; numpy users
open it with ``np.load``). Arrays of length N + 1 hold states (one per time t_k), arrays of length N
hold steps (from t_k to t_k+1):

* ``t``, ``q``, ``qd``, ``box_pose`` (x y z qw qx qy qz); ``tau`` (N, n_joints) joint torques;
* per step (``STEP_KEYS``): the friction fixed point (``fp_converged`` 1/0, ``fp_iter`` iterates,
  ``qp_iter`` OSQP iterations, ``qp_solves`` OSQP solves, ``coulomb_residual``), the contact
  conditions (``complementarity``, ``cone_residual`` against Coulomb's circle,
  ``max_penetration`` [m], ``n_contacts``, ``max_normal_force`` = the largest normal force of a
  contact [N], 0 without load), the limits (``tau_excess`` = max |tau| - tau_max,
  ``q_excess``, ``qd_excess`` = max |qd| - qd_max, <= 0 within them; ``tracking_error`` =
  max |q - q_ref| at the step's end [rad]), the energy ledger (``kinetic``, ``potential``,
  ``elastic`` at the step's start, ``work_actuators``, ``work_contacts`` over the step [J]) and
  the impacts (``impact_count``, ``impact_impulse`` [N s], ``impact_energy`` [J], see
  :func:`cobra_ref.reproduce.analysis.impacts`) and ``substeps``, the steps of dt / n the step was
  taken in around a touch-down (A33, :mod:`cobra_ref.touchdown`; 1 for a whole step);
* the contact log (``CONTACT_KEYS``), one row per contact that carries a normal impulse in a
  step: ``contact_step``, ``contact_kind`` (0 robot-ground, 1 robot-box, 2 box-ground),
  ``contact_body`` (body A: the robot link, or the box for box-ground), ``contact_point``
  (world, the midpoint of the witness points), ``contact_normal`` (world, from B to A),
  ``contact_force`` (world, the force ON body A BY body B: frame @ p / dt; the box feels minus
  the robot-box rows), ``contact_onset_speed`` (the approach speed [m/s] of a contact in
  its first loaded step, 0 afterwards), ``contact_gap`` (the gap g at the step's start [m]) and
  ``contact_gap_end`` (g + dt g', the gap the step's velocity leads to at its end [m], in a
  sub-stepped step the smallest a substep ended at: a compliant contact carries a normal force
  only where it is negative).
"""

from __future__ import annotations

import contextlib
import json
import zipfile
import zlib
from dataclasses import dataclass, field

import numpy as np

from .infra import arguments
from .infra.output import write_binary

STEP_KEYS = ("fp_converged", "fp_iter", "qp_iter", "qp_solves", "coulomb_residual", "complementarity",
             "cone_residual", "max_penetration", "n_contacts", "max_normal_force", "tau_excess", "q_excess",
             "qd_excess", "tracking_error", "kinetic", "potential", "elastic", "work_actuators", "work_contacts",
             "impact_count", "impact_impulse", "impact_energy", "substeps")
CONTACT_KEYS = ("contact_step", "contact_kind", "contact_body", "contact_point", "contact_normal", "contact_force",
                "contact_onset_speed", "contact_gap", "contact_gap_end")


@dataclass
class Trajectory:
    """Everything a simulation computed (complete, or up to a failure: see ``error``)."""

    dt: float
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    tau: np.ndarray
    box_pose: np.ndarray
    steps: dict
    contacts: dict
    wall_time: float = 0.0
    error: str = ""
    meta: dict = field(default_factory=dict)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0

    def summary(self) -> dict:
        """The one-line JSON summary of ``cobra-ref simulate``.

        The box's displacement, the worst contact conditions, the friction fixed point's
        convergence, the largest torque, the share of steps taken in touch-down substeps (A33),
        speed.
        """
        s = self.steps
        d = self.box_pose[-1, :2] - self.box_pose[0, :2] if len(self.box_pose) else np.zeros(2)
        n = max(len(self.tau), 1)
        return {
            "box_displacement": [round(float(x), 6) for x in d],
            "max_penetration": float(np.max(s["max_penetration"], initial=0.0)),
            "max_cone_residual": float(np.max(s["cone_residual"], initial=0.0)),
            "max_coulomb_residual": float(np.max(s["coulomb_residual"], initial=0.0)),
            "fixed_point_converged": float(np.sum(s["fp_converged"])) / n,
            "max_abs_tau": float(np.max(np.abs(self.tau), initial=0.0)),
            "impacts_per_second": float(np.sum(s["impact_count"])) / max(self.duration, 1e-300),
            "substepped": float(np.sum(s["substeps"] > 1)) / n,
            "real_time_factor": round(self.duration / self.wall_time, 4) if self.wall_time > 0 else None,
            "steps": int(len(self.tau)),
            "error": self.error or None,
            **self.beyond_limits(),
        }

    def contact_normal_force(self) -> np.ndarray:
        """(rows,) the normal force [N] of each row of the contact log, ``contact_force`` .
        ``contact_normal`` (on body A, along the normal from B to A)."""
        c = self.contacts
        return np.einsum("ij,ij->i", np.reshape(c["contact_force"], (-1, 3)), np.reshape(c["contact_normal"], (-1, 3)))

    def beyond_limits(self) -> dict:
        """Where the run left physics, as the share of steps and the worst value (A32).

        ``tau_beyond_limit``: the steps whose joint torques exceed tau_max (``tau_excess`` > 0) and
        the largest |tau| [N m]; with the position servo the share is 0 by construction (its
        impulses are bounded rows, |tau| <= tau_max). ``contact_force_beyond_bound``: the steps in
        which a contact's normal force exceeds the bound ``meta["limits"]["contact_force_bound_N"]``
        and the largest normal force [N]; the share is None for a record without the bound.
        """
        s, n = self.steps, max(len(self.tau), 1)
        limits = self.meta.get("limits", {})
        position = self.meta.get("settings", {}).get("servo") == "position"
        tau = {"share_of_steps": 0.0 if position else float(np.sum(s["tau_excess"] > 0.0)) / n,
               "worst_N_m": float(np.max(np.abs(self.tau), initial=0.0)), "limit_N_m": limits.get("tau_max_N_m")}
        if position:
            tau["note"] = "the position servo bounds |tau| by tau_max"
        bound = limits.get("contact_force_bound_N")
        force = s["max_normal_force"]
        return {"tau_beyond_limit": tau,
                "contact_force_beyond_bound": {
                    "share_of_steps": None if bound is None else float(np.sum(force > bound)) / n,
                    "worst_N": float(np.max(force, initial=0.0)), "bound_N": bound}}

    def truncated(self, duration: float) -> "Trajectory":
        """The first ``duration`` seconds: the states up to step n = round(duration / dt), the
        steps before it and the contact rows of those steps; the whole trajectory if it is shorter.

        An ensemble's members judged over one common window. ``wall_time`` is scaled by the share of
        steps kept; ``error`` is kept only when the failure lies within the window.
        """
        if not (np.isfinite(duration) and duration > 0):
            raise ValueError(f"duration must be positive and finite, got {duration}")
        n = int(round(duration / self.dt))
        if n >= len(self.tau):
            return self
        keep = self.contacts["contact_step"] < n
        share = n / max(len(self.tau), 1)
        return Trajectory(self.dt, self.t[:n + 1], self.q[:n + 1], self.qd[:n + 1], self.tau[:n],
                          self.box_pose[:n + 1], {k: v[:n] for k, v in self.steps.items()},
                          {k: v[keep] for k, v in self.contacts.items()}, self.wall_time * share, "",
                          dict(self.meta, truncated_to=float(n * self.dt)))

    @classmethod
    def from_npz(cls, path: str) -> "Trajectory":
        """Read back what ``to_npz`` wrote.

        The cache of the figure runs, and users' own analysis. A record written before one of
        ``ADDED_KEYS`` existed reads it as zeros. A ``path`` that is not a file name raises an
        ``infra.arguments.ArgumentTypeError``; a file that cannot be opened an ``OSError``; one
        that is not an NPZ, is damaged or lacks an array of a run an ``ArgumentError`` naming the
        file (``_open_npz``).
        """
        with _open_npz(arguments.path("path", path)) as z:
            n, m = len(z["tau"]), len(z["contact_step"])
            return cls(float(z["dt"]), z["t"], z["q"], z["qd"], z["tau"], z["box_pose"],
                       {k: _read(z, k, n) for k in STEP_KEYS}, {k: _read(z, k, m) for k in CONTACT_KEYS},
                       float(z["wall_time"]), str(z["error"]), json.loads(str(z["meta"])))

    def to_npz(self, path: str) -> None:
        """Write every array to an NPZ under exactly the name ``path`` (nothing appended: ``run``
        stays ``run``), atomically: a temporary file renamed onto the target, never half-written
        (:mod:`cobra_ref.infra.output`; ``OutputError`` for a directory, a device or a missing directory).

        ``cobra-ref simulate --out`` and the figure runs' cache.
        """
        arrays = dict(t=self.t, q=self.q, qd=self.qd, tau=self.tau, box_pose=self.box_pose, dt=np.array(self.dt),
                      wall_time=np.array(self.wall_time),
                      meta=np.array(json.dumps(self.meta)), error=np.array(self.error), **self.steps, **self.contacts)
        write_binary(path, lambda f: np.savez_compressed(f, **arrays), "NPZ")


ADDED_KEYS = ("max_normal_force", "contact_gap", "contact_gap_end", "substeps")  # keys a record may predate
RUN_KEYS = ("t", "q", "qd", "tau", "box_pose", "dt", "wall_time", "meta", "error")  # besides the step and contact keys


NOT_A_RUN = "allowed: an NPZ written by Trajectory.to_npz or cobra-ref simulate"


@contextlib.contextmanager
def _open_npz(path: str):
    """``np.load(path)`` of a run's NPZ, checked, for a ``with`` block: an ``ArgumentError`` naming
    ``path`` for a file that is not a zip archive, lacks an array that ``from_npz`` reads, or is
    damaged (an array that cannot be read in the block); an ``OSError`` (a missing file, a
    directory) as ``open`` raises it."""
    with open(path, "rb"):  # a missing file, a directory: the OSError of open
        pass
    if not zipfile.is_zipfile(path):  # an NPZ is a zip archive (a truncated one has lost its directory)
        raise arguments.ArgumentError(f"path = {path!r} is not an NPZ (zip) archive ({NOT_A_RUN})")
    with np.load(path, allow_pickle=False) as z:
        needed = RUN_KEYS + tuple(k for k in STEP_KEYS + CONTACT_KEYS if k not in ADDED_KEYS)
        missing = [k for k in needed if k not in z.files]
        if missing:
            raise arguments.ArgumentError(f"path = {path!r} is not a run's NPZ: it lacks {len(missing)} of its "
                                          f"arrays ({', '.join(missing[:5])}{', ...' if len(missing) > 5 else ''}; "
                                          f"{NOT_A_RUN})")
        try:
            yield z
        except (zipfile.BadZipFile, zlib.error, EOFError, TypeError, ValueError) as exc:  # a damaged array
            raise arguments.ArgumentError(f"path = {path!r}: a damaged run NPZ ({type(exc).__name__}: {exc}; "
                                          f"{NOT_A_RUN})") from None


def _read(z, key: str, n: int) -> np.ndarray:
    """``z[key]``, or n zeros for one of ``ADDED_KEYS`` that an older record lacks."""
    if key not in z.files and key in ADDED_KEYS:
        return np.zeros(n)
    return z[key]
