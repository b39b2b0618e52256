"""simulate(): roll the stepper forward, log every step and every contact, write NPZ.

Implements: the paper's "time-stepping methodology ... over Delta t" ([COBRA] sec. III) on top
of :mod:`cobra_ref.stepper`.

Logged per step (arrays of length N+1 for states, N for steps):

* ``t, q, qd, box_pose`` (x y z qw qx qy qz), ``tau`` (N, 11) joint torques over each step;
* solver records: ``osqp_status`` (1 solved, 2 OSQP "solved inaccurate", 3 friction fixed
  point not converged and clipped), ``osqp_iter`` (ADMM iterations), ``osqp_solves`` (OSQP
  solves; the other fixed-point iterates were certified re-solves), ``fp_iter``, ``complementarity``,
  ``cone_residual``, ``stick_residual``, ``max_penetration``, ``cond_G``, ``n_contacts``,
  ``tau_excess`` (max |tau| - tau_max, <= 0 means within limits), ``q_excess`` (same for |q|);
* energy: ``kinetic``, ``potential`` (at each step start), ``work_actuators`` (dt tau . u_mid
  over the joints) and ``work_contacts`` (p . J_c u_mid, <= 0 = dissipated by friction and
  contact), both at the step's midpoint velocity u_mid = (u + u+) / 2, for which
  Delta KE = u_mid . M (u+ - u) holds exactly at fixed M;
* a flat contact log with one row per active contact per step (p_N > 0): ``contact_step``,
  ``contact_kind`` (0 robot-ground, 1 robot-box, 2 box-ground), ``contact_body`` (body A:
  the robot link, or the box for box-ground), ``contact_point`` (world, the midpoint of the
  two witness points), ``contact_normal`` (world, from B to A), ``contact_force`` (world,
  the force ON body A BY body B, = frame @ p / dt; the box feels minus this from the robot).
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import asdict, dataclass, field

import numpy as np

from .output import atomic_write
from .fast.contacts import KINDS, find_contacts
from .fast.contact_qp import ContactSolveError
from .kinematics import forward_kinematics
from .model import Model
from .quaternion import quat_exp, quat_mul
from .gaits import N_JOINTS
from .robots import neutral_q
from .fast.stepper import SimulationError, StepSettings, Stepper

# per-step solver status: 1 solved, 2 OSQP "solved inaccurate", 3 friction fixed point not converged
STATUS_CODES = {"solved": 1, "solved inaccurate": 2, "not converged": 3}
STEP_KEYS = ("osqp_status", "osqp_iter", "osqp_solves", "fp_iter", "complementarity", "cone_residual", "stick_residual",
             "max_penetration", "cond_G", "n_contacts", "tau_excess", "q_excess", "kinetic", "potential",
             "work_actuators", "work_contacts")
CONTACT_KEYS = ("contact_step", "contact_kind", "contact_body", "contact_point", "contact_normal", "contact_force")


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
        """The one-line JSON summary of ``cobra-ref simulate``."""
        d = self.box_pose[-1, :2] - self.box_pose[0, :2] if len(self.box_pose) else np.zeros(2)
        return {
            "box_displacement": [round(float(x), 6) for x in d],
            "max_penetration": float(np.max(self.steps["max_penetration"], initial=0.0)),
            "max_cone_residual": float(np.max(self.steps["cone_residual"], initial=0.0)),
            "real_time_factor": round(self.duration / self.wall_time, 4) if self.wall_time > 0 else None,
            "steps": int(len(self.tau)),
            "error": self.error or None,
        }

    @classmethod
    def from_npz(cls, path: str) -> "Trajectory":
        """Read back what ``to_npz`` wrote (a step record that an older file lacks reads as NaN)."""
        with np.load(path, allow_pickle=False) as z:
            n = len(z["tau"])
            return cls(float(z["dt"]), z["t"], z["q"], z["qd"], z["tau"], z["box_pose"],
                       {k: z[k] if k in z else np.full(n, np.nan) for k in STEP_KEYS}, {k: z[k] for k in CONTACT_KEYS},
                       float(z["wall_time"]), str(z["error"]), json.loads(str(z["meta"])))

    def to_npz(self, path: str) -> None:
        """Write every array to an NPZ atomically (temporary file + rename: never half-written)."""
        directory = os.path.dirname(os.path.abspath(path)) or "."
        if not os.path.isdir(directory):
            raise OSError(f"output directory does not exist: {directory}")
        arrays = dict(t=self.t, q=self.q, qd=self.qd, tau=self.tau, box_pose=self.box_pose, dt=np.array(self.dt),
                      wall_time=np.array(self.wall_time),
                      meta=np.array(json.dumps(self.meta)), error=np.array(self.error), **self.steps, **self.contacts)
        atomic_write(path, lambda tmp: np.savez_compressed(tmp, **arrays))


def initial_state(model: Model, reference, box_offset=None, box_gap: float = 0.05, clearance: float = 1e-3,
                  box_direction=None):
    """Robot at rest in the reference's t = 0 shape, head at the origin facing +x, lowest sphere
    ``clearance`` above the ground; the box resting flat on the ground beside the middle of the
    snake (assumption C9).

    Box placement: the middle of the snake is the midpoint of the two middle bodies' centres of
    mass (L5 and L6 for COBRA), and the concave side is the horizontal direction d from there
    to the robot's centre of mass. The box's centre goes to middle + (r + a/2 + box_gap) d,
    turned so that one face looks back at the robot: ``box_gap`` (default 0.05 m, C9) is then
    the clearance between that face and the middle link's cylinder. ``box_offset`` = (dx, dy)
    instead puts the box centre at middle + (dx, dy), axis-aligned; ``box_direction`` = (dx, dy)
    replaces the concave side d by that horizontal direction (sidewinding pushes with its
    leading side: ``reproduce`` passes the direction the gait travels).

    The robot's base is first turned so that its start shape lies on its flattest side
    (``_rest_on_flattest_side``; no turn for the planar rolling shapes).

    Helper: the simulation loop.
    """
    q = neutral_q(model)
    act_q = [model.q_idx[i].start for i, jt in enumerate(model.joint_type) if jt != "free"]
    q[act_q] = reference(0.0)[0]
    q[3:7] = _rest_on_flattest_side(model, q)
    kin = forward_kinematics(model, q)
    sph = model.spheres
    bottoms = [kin.p[b][2] + (kin.R[b] @ c)[2] - r for b, c, r in zip(sph.body, sph.center, sph.radius)]
    q[2] = clearance - min(bottoms)
    if model.boxes:
        box = model.boxes[0]
        robot = [i for i in range(model.nb) if i != box.body]
        com = np.array([kin.p[i] + kin.R[i] @ model.com[i] for i in robot])
        mid_bodies = robot[len(robot) // 2 - 1:len(robot) // 2 + 1]
        middle = com[mid_bodies].mean(axis=0)
        iq = model.q_idx[box.body]
        if box_offset is not None:
            centre, yaw = middle[:2] + np.asarray(box_offset, dtype=float), 0.0
        else:
            d = (np.average(com, axis=0, weights=[model.mass[i] for i in robot]) - middle)[:2]
            if box_direction is not None:
                d = np.asarray(box_direction, dtype=float)[:2]
                if not (np.all(np.isfinite(d)) and np.linalg.norm(d) > 0):
                    raise ValueError(f"box_direction must be a finite non-zero (dx, dy), got {box_direction}")
            elif np.linalg.norm(d) < 1e-3:  # a straight or symmetric S shape: use the body's left side
                d = kin.R[mid_bodies[0]][:2, 1]
            d = d / np.linalg.norm(d)
            r = max(sph.radius[np.isin(sph.body, mid_bodies)])
            centre, yaw = middle[:2] + (r + box.half[0] + box_gap) * d, np.arctan2(d[1], d[0])
        q[iq.start:iq.start + 3] = [centre[0], centre[1], box.half[2]]
        q[iq.start + 3:iq.start + 7] = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    return q, np.zeros(model.nv)


def _rest_on_flattest_side(model: Model, q) -> np.ndarray:
    """Base quaternion that turns the robot's best-fit plane horizontal (a 3-D start shape, such as
    sidewinding's, then lies on its flattest side instead of standing on its tips and falling).

    Helper: the plane through the robot bodies' centres of mass with the least variance across
    it (its normal n is the last right singular vector of the centred points); the base turns by
    the smallest rotation taking n (chosen with n_z >= 0) to z. A planar shape (every rolling
    gait at t = 0) has n = z already, so it is left as it is.
    """
    kin = forward_kinematics(model, q)
    robot = [i for i in range(model.nb) if not any(b.body == i for b in model.boxes)]
    com = np.array([kin.p[i] + kin.R[i] @ model.com[i] for i in robot])
    n = np.linalg.svd(com - com.mean(axis=0))[2][-1]
    n = n if n[2] >= 0 else -n
    axis = np.cross(n, [0.0, 0.0, 1.0])
    if np.linalg.norm(axis) < 1e-9:
        return q[3:7].copy()
    angle = np.arctan2(np.linalg.norm(axis), n[2])
    turn = quat_exp(angle * axis / np.linalg.norm(axis))
    return quat_mul(turn, q[3:7])


def simulate(model: Model, reference, duration: float, settings: StepSettings = StepSettings(), q0=None,
             qd0=None, progress=None, box_offset=None, box_direction=None) -> Trajectory:
    """Simulate ``duration`` seconds; return a Trajectory (see the module docstring for fields).

    Raises ``SimulationError`` for a bad duration, an initial state in deep penetration, or a
    contact solver failure mid-run; the failure names the step and time, and its
    ``trajectory`` attribute keeps everything computed before it.

    Helper: the simulation loop.
    """
    if not (np.isfinite(duration) and duration > 0):
        raise SimulationError(f"duration must be positive and finite, got {duration}")
    if q0 is None:
        q0, qd0 = initial_state(model, reference, box_offset, box_direction=box_direction)
    q, qd = model.check_q(q0).copy(), model.check_qd(np.zeros(model.nv) if qd0 is None else qd0).copy()
    stepper = Stepper(model, settings)
    _check_start(stepper, q, qd)
    n_steps = int(round(duration / settings.dt))
    log = _Log(model, n_steps, settings.dt, n_joints=len(stepper.act))
    log.add_state(0.0, q, qd)
    start = time.perf_counter()
    for k in range(n_steps):
        t = k * settings.dt
        try:
            res = stepper.step(q, qd, t, reference)
        except (ContactSolveError, np.linalg.LinAlgError, SimulationError) as exc:
            traj = log.finish(time.perf_counter() - start, f"step {k} (t = {t:.4f} s): {exc}", meta(stepper))
            what = "contact solve failed" if isinstance(exc, ContactSolveError) else "step failed"
            raise SimulationError(f"{what} at step {k}, t = {t:.4f} s: {exc}", traj) from exc
        q, qd = res.q, res.qd
        if not math.isfinite(q.sum() + qd.sum()):  # a NaN or inf anywhere makes the sum non-finite
            traj = log.finish(time.perf_counter() - start, f"step {k} (t = {t:.4f} s): non-finite state",
                              meta(stepper))
            raise SimulationError(f"non-finite state at step {k}, t = {t:.4f} s", traj)
        log.add_step(k, res, stepper)
        log.add_state(t + settings.dt, q, qd)
        if progress is not None and ((k + 1) % 250 == 0 or k + 1 == n_steps):
            progress(k + 1, n_steps)
    return log.finish(time.perf_counter() - start, "", meta(stepper))


def meta(stepper: Stepper) -> dict:
    """What a run was made with (settings, friction, model), and the seconds spent per phase.

    Helper: the simulation loop.
    """
    model = stepper.model
    return {"settings": asdict(stepper.s), "model": model.name, "nq": model.nq, "nv": model.nv,
            "mu": model.mu, "mu_robot_box": model.mu_rb,
            "phase_seconds": dict(stepper.timing)}


def _check_start(stepper: Stepper, q, qd) -> None:
    terms = stepper.chain.terms(q, qd)
    contacts = find_contacts(stepper.model, terms, 0.0)
    if contacts.m and contacts.g.min() < -stepper.s.max_start_penetration:
        k = int(np.argmin(contacts.g))
        raise SimulationError(
            f"initial state in deep penetration: {KINDS[contacts.kind[k]]} contact on body "
            f"'{stepper.model.body_names[contacts.body_A[k]]}' is {-contacts.g[k] * 1000:.1f} mm deep "
            f"(allowed {stepper.s.max_start_penetration * 1000:.1f} mm)")


class _Log:
    """Preallocated per-step arrays and a growing contact log."""

    def __init__(self, model: Model, n_steps: int, dt: float, n_joints: int = N_JOINTS):
        self.model, self.dt, self.n = model, dt, 0
        self.t = np.zeros(n_steps + 1)
        self.q = np.zeros((n_steps + 1, model.nq))
        self.qd = np.zeros((n_steps + 1, model.nv))
        self.tau = np.zeros((n_steps, n_joints))
        self.steps = {k: np.zeros(n_steps) for k in STEP_KEYS}
        self.contact_rows = {k: [] for k in CONTACT_KEYS}
        self.box = model.q_idx[model.boxes[0].body] if model.boxes else None

    def add_state(self, t, q, qd):
        i = self.n
        self.t[i], self.q[i], self.qd[i] = t, q, qd

    def add_step(self, k, res, stepper):
        s, info, cs = self.steps, res.qp, res.contacts
        s["osqp_status"][k] = STATUS_CODES[info.status.split(" (")[0] if "(" not in info.status else "not converged"]
        s["osqp_iter"][k], s["fp_iter"][k] = info.iterations, info.fp_iterations
        s["osqp_solves"][k] = info.osqp_solves
        s["complementarity"][k], s["cone_residual"][k] = info.complementarity, info.cone_residual
        s["stick_residual"][k], s["cond_G"][k] = info.stick_slip_residual, info.cond_G
        s["max_penetration"][k] = max(0.0, -float(cs.g.min())) if cs.m else 0.0
        s["n_contacts"][k] = cs.m
        if len(stepper.act):
            s["tau_excess"][k] = float((np.abs(res.tau) - stepper.tau_max).max())
            s["q_excess"][k] = float((np.abs(res.q[stepper.act_q]) - stepper.q_max).max())
        else:
            s["tau_excess"][k] = s["q_excess"][k] = -np.inf
        s["kinetic"][k], s["potential"][k] = res.kinetic, res.potential
        s["work_actuators"][k], s["work_contacts"][k] = res.work_actuators, res.work_contacts
        self.tau[k] = res.tau
        active = np.flatnonzero(res.p[0::3] > 1e-12)
        if len(active):
            rows = self.contact_rows
            rows["contact_step"].append(np.full(len(active), k))
            rows["contact_kind"].append(cs.kind[active])
            rows["contact_body"].append(cs.body_A[active])
            rows["contact_point"].append(0.5 * (cs.point_A[active] + cs.point_B[active]))
            rows["contact_normal"].append(cs.frame[active, :, 0])
            p3 = res.p.reshape(-1, 3)[active]
            rows["contact_force"].append((cs.frame[active] @ p3[:, :, None])[:, :, 0] / self.dt)
        self.n = k + 1

    def finish(self, wall_time: float, error: str = "", meta: dict | None = None) -> "Trajectory":
        n = self.n
        shapes = {"contact_point": (0, 3), "contact_normal": (0, 3), "contact_force": (0, 3)}
        contacts = {k: (np.concatenate(v) if v else np.zeros(shapes.get(k, (0,)))) for k, v in self.contact_rows.items()}
        box_pose = self.q[:n + 1, self.box] if self.box is not None else np.zeros((n + 1, 7))
        return Trajectory(self.dt, self.t[:n + 1].copy(), self.q[:n + 1].copy(), self.qd[:n + 1].copy(),
                          self.tau[:n].copy(), box_pose.copy(), {k: v[:n].copy() for k, v in self.steps.items()},
                          contacts, wall_time, error, meta or {})
