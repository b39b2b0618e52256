"""simulate(): roll a stepper forward from a start at rest, and record every step and contact.

Implements: the paper's "time-stepping methodology ... over Delta t" ([COBRA] sec. "Motion
Optimization") with a stepper named in :mod:`cobra_ref.steppers`: the reference step
:func:`cobra_ref.step.step` (``stepper="reference"``) or its faster twin
:class:`cobra_ref.fast.stepper.FastStepper` (``stepper="fast"``, the default; the two take the
same steps, tests run them side by side), from the settle of the start to the last step. What is
recorded: :mod:`cobra_ref.trajectory`. A run that leaves physics says so (A32): when prescribed
joint motion needs torques beyond tau_max, or a contact's normal force exceeds
``contact_force_bound(model)``, the run issues one ``LeftPhysicsWarning`` naming each, its worst
value and its share of the steps; the trajectory's summary records both.
"""

from __future__ import annotations

import math
import time
import warnings
from dataclasses import asdict

import numpy as np

from .contact import KINDS, find_contacts
from .infra import arguments
from .infra.executors import one_blas_thread
from .model import Model
from .qp import ContactSolveError
from .start import check_run_arguments, initial_state
from .step import IMPACT_SPEED, SimulationError, StepSettings, joint_coordinates
from .steppers import make_stepper
from .trajectory import CONTACT_KEYS, STEP_KEYS, Trajectory

MAX_START_PENETRATION = 0.005  # [m] a start deeper in the ground or the box is refused
CONTACT_FORCE_WEIGHTS = 30.0  # the bound on a contact's normal force, in weights of every body (A32)


class LeftPhysicsWarning(UserWarning):
    """A run whose joint torques or contact forces went beyond what the robot and its contacts can
    carry (``simulate``'s module docstring, A32)."""


def contact_force_bound(model: Model) -> float:
    """The largest normal force [N] a contact carries within physics: ``CONTACT_FORCE_WEIGHTS``
    times the weight of every body of the model (A32; COBRA's 12 links and the 0.5 kg box: 1913 N)."""
    return CONTACT_FORCE_WEIGHTS * float(sum(model.mass)) * float(np.linalg.norm(model.gravity))


def left_physics(traj: Trajectory) -> str:
    """The sentence that says where ``traj`` left physics (``Trajectory.beyond_limits``); empty when
    it did not."""
    limits = traj.beyond_limits()
    tau, force = limits["tau_beyond_limit"], limits["contact_force_beyond_bound"]
    parts = []
    if tau["share_of_steps"]:
        parts.append(f"joint torques beyond tau_max = {tau['limit_N_m']:g} N m on {100 * tau['share_of_steps']:.3g} % "
                     f"of the steps (worst {tau['worst_N_m']:.4g} N m)")
    if force["share_of_steps"]:
        parts.append(f"a contact's normal force beyond the bound {force['bound_N']:.4g} N (A32) on "
                     f"{100 * force['share_of_steps']:.3g} % of the steps (worst {force['worst_N']:.4g} N)")
    return ("the run left physics: " + "; ".join(parts)) if parts else ""


def simulate(model: Model, reference, duration: float, settings: StepSettings = StepSettings(), q0=None,
             qd0=None, progress=None, stepper: str = "fast") -> Trajectory:
    """Simulate ``duration`` seconds from (q0, qd0); return a Trajectory.

    Implements: the time stepping of [COBRA] (module docstring). ``stepper``: the name of the
    stepper (``steppers.STEPPERS``); a new one is made for the run, and, without q0, for the start
    ``start.initial_state(model, reference, settings, stepper=stepper)`` (the default box
    placement; for another, pass that function's (q0, qd0) with its ``BoxPlacement``). The time
    grid is checked before anything is allocated (``validation.step_count``; ``settings.dt`` was checked by
    ``StepSettings``): ``settings.dt`` within the stable range,
    ``round(duration / dt)`` steps, at least one and at most ``validation.MAX_STEPS`` (the
    command line also asks for a whole number of steps). A bad argument (a model that is not a
    ``Model``, a reference that is not callable, settings that are not a ``StepSettings``, a bad
    duration, stepper or progress) raises ``infra.arguments.ArgumentError`` (a ValueError) or
    ``ArgumentTypeError`` (a TypeError) naming it. Raises ``SimulationError`` for a start in deep
    penetration or a failure mid-run; a failure mid-run,
    of any exception type, names the step and time, and its ``trajectory`` attribute keeps
    everything computed before it (the original exception is its ``__cause__``). Ctrl-C
    (``KeyboardInterrupt``) is re-raised as it is, with the same ``trajectory`` attribute.
    """
    check_run_arguments(model, reference, settings, stepper, progress)
    n_steps = arguments.duration_steps(duration, settings.dt)  # settings.dt: checked by StepSettings
    if q0 is None:
        q0, qd0 = initial_state(model, reference, settings, stepper=stepper)
    run = Run(model, settings, q0, qd0, stepper, n_steps)
    run.advance(reference, n_steps, progress)
    traj = run.finish()
    message = left_physics(traj)
    if message:
        warnings.warn(message, LeftPhysicsWarning, stacklevel=2)
    return traj


class Run:
    """A simulation that goes on where it stopped: one stepper (its warm start and memory kept
    from step to step) and one log of at most ``capacity`` steps.

    ``simulate`` is one ``advance`` of a new Run; a planner that decides the reference as the run
    goes advances it piece by piece, with the same steps, bit for bit, as one ``advance`` over
    the whole. ``t0`` and ``memory`` (a stepper's ``memory``) start a run in the middle of another
    one: a planner's rollout from the state its plant reached.
    """

    def __init__(self, model: Model, settings: StepSettings, q0, qd0, stepper: str = "fast", capacity: int = 1,
                 t0: float = 0.0, memory: dict | None = None):
        self.stepping = make_stepper(stepper, model, settings)  # checks the three (infra.arguments)
        self.stepping.memory = memory
        self.model, self.settings, self.t0 = model, settings, float(t0)
        self.q, self.qd = model.check_q(q0).copy(), model.check_qd(np.zeros(model.nv) if qd0 is None else qd0).copy()
        check_start(model, self.q)
        self.log = RunLog(model, capacity, settings.dt)
        self.log.add_state(self.t0, self.q, self.qd)
        self.k, self.wall_time, self._started = 0, 0.0, None

    @property
    def t(self) -> float:
        """The time [s] the run has reached."""
        return self.t0 + self.k * self.settings.dt

    def advance(self, reference, n_steps: int, progress=None) -> None:
        """``n_steps`` more steps following ``reference``. A failure raises ``SimulationError`` (a
        ``KeyboardInterrupt`` as it is) naming the step and time, with everything computed so far
        as its ``trajectory`` (``simulate``)."""
        if self.k + n_steps > len(self.log.tau):
            raise SimulationError(f"the run holds {len(self.log.tau)} steps; {self.k} taken, {n_steps} more asked")
        dt, log = self.settings.dt, self.log
        # the step's matrices are small: one BLAS thread is fastest (executors.one_blas_thread)
        with one_blas_thread():
            self._started = time.perf_counter()
            try:
                for i in range(n_steps):
                    k = self.k
                    t = self.t0 + k * dt
                    try:
                        res = self.stepping.step(self.q, self.qd, t, reference)
                        if not math.isfinite(res.q.sum() + res.qd.sum()):  # a NaN or inf anywhere makes the sum non-finite
                            raise _NonFinite()
                        self.q, self.qd = res.q, res.qd
                        log.add_step(k, res)
                        log.add_state(t + dt, self.q, self.qd)
                        self.k = k + 1
                        if progress is not None and ((i + 1) % 250 == 0 or i + 1 == n_steps):
                            progress(i + 1, n_steps)
                    except _NonFinite:
                        error, message = step_failure(k, t)
                        raise SimulationError(message, self.finish(error)) from None
                    except KeyboardInterrupt as exc:
                        exc.trajectory = self.finish(f"step {k} (t = {t:.4f} s): interrupted")
                        raise
                    except Exception as exc:  # any failure of the step: keep what was computed, name step and time
                        error, message = step_failure(k, t, exc)
                        raise SimulationError(message, self.finish(error)) from exc
            finally:
                self.wall_time += time.perf_counter() - self._started
                self._started = None

    def finish(self, error: str = "") -> Trajectory:
        """The trajectory so far (``error``: why it ends early, empty for a run that did not fail)."""
        running = time.perf_counter() - self._started if self._started is not None else 0.0
        return self.log.finish(self.wall_time + running, error, meta(self.model, self.settings, self.stepping))


# the failures a step is known to raise (named by their message alone); any other is named with its type
EXPECTED = (ContactSolveError, np.linalg.LinAlgError, SimulationError, ValueError, FloatingPointError)


class _NonFinite(Exception):
    """A step that left NaN or inf in the state."""


def step_failure(k: int, t: float, exc: BaseException | None = None) -> tuple[str, str]:
    """(the trajectory's ``error``, the ``SimulationError``'s message) of a run whose step k at
    time t raised ``exc``, or, with none, left a non-finite state: how every run names its failure."""
    where = f"step {k} (t = {t:.4f} s)"
    if exc is None:
        return f"{where}: non-finite state", f"non-finite state at step {k}, t = {t:.4f} s"
    what = str(exc) if isinstance(exc, EXPECTED) else f"{type(exc).__name__}: {exc}"
    return f"{where}: {what}", f"step failed at step {k}, t = {t:.4f} s: {what}"


def meta(model: Model, settings: StepSettings, stepper) -> dict:
    """What a run was made with (settings, friction, model, stepper), its limits (the largest
    tau_max, the contact force bound) and the seconds spent per phase of the stepper
    (``stepper.timing``), stored in the trajectory's ``meta``."""
    tau_max = max((float(x) for x in model.tau_limit if math.isfinite(x)), default=None)
    return {"settings": asdict(settings), "model": model.name, "nq": model.nq, "nv": model.nv,
            "mu": model.mu, "mu_robot_box": model.mu_rb, "mu_box_ground": model.mu_bg,
            "limits": {"tau_max_N_m": tau_max, "contact_force_bound_N": contact_force_bound(model)},
            "stepper": stepper.name, "phase_seconds": dict(stepper.timing)}


def check_start(model: Model, q) -> None:
    """Refuse a start deeper than MAX_START_PENETRATION in the ground or the box, naming the body.

    ``simulate`` checks its start with it; the command line checks a placement before
    it settles.
    """
    contacts = find_contacts(model, q, 0.0)
    if contacts.m and contacts.g.min() < -MAX_START_PENETRATION:
        k = int(np.argmin(contacts.g))
        raise SimulationError(
            f"initial state in deep penetration: {KINDS[contacts.kind[k]]} contact on body "
            f"'{model.body_names[contacts.body_A[k]]}' is {-contacts.g[k] * 1000:.1f} mm deep "
            f"(allowed {MAX_START_PENETRATION * 1000:.1f} mm)")


class RunLog:
    """Preallocated per-step arrays and a growing contact log."""

    def __init__(self, model: Model, n_steps: int, dt: float):
        self.model, self.dt, self.n = model, dt, 0
        self.joints = joint_coordinates(model)
        self.t = np.zeros(n_steps + 1)
        self.q = np.zeros((n_steps + 1, model.nq))
        self.qd = np.zeros((n_steps + 1, model.nv))
        self.tau = np.zeros((n_steps, len(self.joints.v)))
        self.q_ref = np.zeros((n_steps, len(self.joints.q)))  # each step's joint reference
        self.steps = {k: np.zeros(n_steps) for k in STEP_KEYS}
        self.contact_rows = {k: [] for k in CONTACT_KEYS}
        self.box = model.q_idx[model.boxes[0].body] if model.boxes else None
        self.loaded = set()  # the contact keys that carried load in the last step

    def add_state(self, t, q, qd):
        i = self.n
        self.t[i], self.q[i], self.qd[i] = t, q, qd

    def add_step(self, k, res):
        s, info, cs = self.steps, res.info, res.contacts
        s["fp_converged"][k], s["fp_iter"][k] = info.converged, info.iterations
        s["qp_iter"][k], s["qp_solves"][k] = info.qp_iterations, info.qp_solves
        for key in ("coulomb_residual", "complementarity", "cone_residual"):
            s[key][k] = res.residuals[key]
        s["max_penetration"][k] = max(0.0, -float(cs.g.min())) if cs.m else 0.0
        s["n_contacts"][k] = cs.m
        s["substeps"][k] = res.substeps
        p_N = res.p[0::3]
        s["max_normal_force"][k] = float(p_N.max()) / self.dt if cs.m else 0.0
        self.q_ref[k] = res.q_ref  # the joints' limits and tracking error follow at ``finish``
        for key in ("kinetic", "potential", "elastic", "work_actuators", "work_contacts"):
            s[key][k] = getattr(res, key)
        self.tau[k] = res.tau
        # the contact log, and the impacts: contacts that start carrying load while approaching
        active = (p_N > 0.0).nonzero()[0]
        keys = cs.keys()
        active_keys = [keys[i] for i in active.tolist()]
        onset = np.array([key not in self.loaded for key in active_keys], dtype=bool)
        speed = np.where(onset, res.approach[active], 0.0)
        impact = speed > IMPACT_SPEED
        if impact.any():  # (the arrays start at zero)
            s["impact_count"][k] = int(impact.sum())
            s["impact_impulse"][k] = float(np.sum(speed[impact] / res.G_NN[active][impact]))
            s["impact_energy"][k] = float(np.sum(0.5 * speed[impact] ** 2 / res.G_NN[active][impact]))
        self.loaded = set(active_keys)
        if len(active):
            rows = self.contact_rows
            frame = cs.frame[active]
            rows["contact_step"].append(np.full(len(active), k))
            rows["contact_kind"].append(cs.kind[active])
            rows["contact_body"].append(cs.body_A[active])
            rows["contact_point"].append(0.5 * (cs.point_A[active] + cs.point_B[active]))
            rows["contact_normal"].append(frame[:, :, 0])
            p3 = res.p.reshape(-1, 3)[active]
            rows["contact_force"].append((frame @ p3[:, :, None])[:, :, 0] / self.dt)
            rows["contact_onset_speed"].append(speed)
            g = cs.g[active]
            rows["contact_gap"].append(g)
            rows["contact_gap_end"].append(g + self.dt * res.w[0::3][active])
        self.n = k + 1

    def _joint_excess(self, n: int) -> None:
        """Each of the first n steps' torque, angle and rate beyond the joints' limits (-inf without
        joints) and its largest tracking error, from the state after it and its reference."""
        s, joints = self.steps, self.joints
        if not len(joints.v):
            for key in ("tau_excess", "q_excess", "qd_excess"):
                s[key][:n] = -np.inf
            return
        q_joint = self.q[1:n + 1, joints.q]
        s["tau_excess"][:n] = (np.abs(self.tau[:n]) - joints.tau_max).max(axis=1)
        s["q_excess"][:n] = (np.abs(q_joint) - joints.q_max).max(axis=1)
        s["qd_excess"][:n] = (np.abs(self.qd[1:n + 1, joints.v]) - joints.qd_max).max(axis=1)
        s["tracking_error"][:n] = np.abs(q_joint - self.q_ref[:n]).max(axis=1)

    def finish(self, wall_time: float, error: str = "", meta: dict | None = None) -> Trajectory:
        n = self.n
        self._joint_excess(n)
        shapes = {"contact_point": (0, 3), "contact_normal": (0, 3), "contact_force": (0, 3)}
        contacts = {k: (np.concatenate(v) if v else np.zeros(shapes.get(k, (0,)))) for k, v in self.contact_rows.items()}
        box_pose = self.q[:n + 1, self.box] if self.box is not None else np.zeros((n + 1, 7))
        return Trajectory(self.dt, self.t[:n + 1].copy(), self.q[:n + 1].copy(), self.qd[:n + 1].copy(),
                          self.tau[:n].copy(), box_pose.copy(), {k: v[:n].copy() for k, v in self.steps.items()},
                          contacts, wall_time, error, meta or {})
