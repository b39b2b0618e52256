"""MuJoCo rollouts of the exported model: does MuJoCo push the box the same way we do?

Implements: the rollout cross-check with MuJoCo ("a gait rollout in MuJoCo moves
the box the same way within a stated tolerance band"), on the MJCF of :func:`cobra_ref.mjcf.to_mjcf`.
[MJ] = MuJoCo documentation, "Computation" (soft constraints, eq. aref) and "XML Reference"
(actuator/position, equality/joint), as shipped with mujoco 4.0 in ``mujoco/doc``.

MuJoCo's qpos / qvel layout is cobra_ref's (free joint 7 + 11 hinges + box free joint 7; nv = 23),
so ``q0`` from :func:`cobra_ref.simulate.initial_state` goes in unchanged; ``rollout`` checks the
joint addresses of the compiled model against ``model.q_idx`` / ``model.v_idx`` before it starts.

Two ways to drive the 11 joints (``mode``):

* ``"kinematic"`` (default), the analogue of our ``StepSettings(servo="prescribed")``, which is
  what ``cobra-ref simulate`` and the figure runs use. The position actuators are removed and
  every hinge gets a one-joint equality constraint theta_i = a0_i (``<equality><joint>`` without
  joint2, [MJ] XML equality/joint), whose target a0_i is moved every step. MuJoCo solves these
  rows together with the contacts in one constraint problem, so the servo torque is a
  constraint force, the base and the box feel its reaction, and nothing is limited by the
  9.2 N m stall torque (as in our prescribed servo, which only reports the excess). The rows are
  as hard as MuJoCo allows: solref = (2 dt, 1), the smallest time constant its ``refsafe`` rule
  keeps, and impedance d = 0.9999 = mjMAXIMP. Measured: |theta - theta_ref| <= 1.3e-5 rad on
  each of the five gaits over 2 s.

  Rejected alternatives: (a) overwriting the hinge qpos / qvel with the reference before each
  ``mj_step`` and integrating the rest. The step's dynamics then see free, unactuated joints:
  the overwritten joint velocity is injected without any reaction on the base. Measured on
  C rolling over 2 s: the base moves 1 cm and the box not at all, where the equality servo
  rolls the robot into the box and pushes it 11 cm. (b) Very stiff position actuators: the
  stiffness kp is integrated explicitly by ``implicitfast`` (only the damping kv is implicit),
  so kp is capped by the stability limit dt < 2 / omega, and a 9.2 N m force range would not be
  the prescribed servo anyway.

* ``"position"``, the analogue of our ``StepSettings(servo="pd")``: the exported position
  actuators, force = clip(kp (ctrl - theta) - kv theta_dot, +-tau_max) ([MJ] actuator/position:
  gainprm = kp, biasprm = (0, -kp, -kv)). With ctrl = theta_ref + (kv / kp) theta_dot_ref this is
  kp (theta_ref - theta) + kv (theta_dot_ref - theta_dot), our PD law with the velocity target,
  with one actuator per joint. Gains default to ``to_mjcf``'s (kp = 100 N m / rad, kv = 2 N m s / rad,
  = StepSettings.kp / kd, assumption A7); with them the C roll lags the reference by up to 0.05 rad.

The comparison (``compare``) states its tolerance band and why; ``cross_check`` runs the gaits.
mujoco is an optional dependency (the ``test`` extra): without it, ``rollout`` and
``cross_check`` raise ``MujocoUnavailable`` saying so, and ``mujoco_available()`` is False.
"""

from __future__ import annotations

import inspect
import time
import xml.etree.ElementTree as ET
from typing import NamedTuple

import numpy as np

from ..mjcf import to_mjcf
from ..model import Model

MODES = ("kinematic", "position")
# compare(): the tolerance band, stated before any run (see compare's docstring)
MAX_ANGLE_DEG = 45.0
MAX_RATIO = 3.0
MIN_DISPLACEMENT = 0.005  # [m], 5 % of the box's edge


class MujocoUnavailable(ImportError):
    """mujoco is not installed (it is an optional extra)."""


class MujocoRolloutError(RuntimeError):
    """A MuJoCo rollout that cannot go on (diverged, or the model does not match)."""


class MujocoRollout(NamedTuple):
    """What a MuJoCo rollout returns (states at the N + 1 times t_k = k dt, stats over the N steps)."""

    t: np.ndarray  # (N+1,) [s]
    qpos: np.ndarray  # (N+1, nq), cobra_ref's q layout
    box_pose: np.ndarray  # (N+1, 7) box x y z qw qx qy qz
    box_displacement: np.ndarray  # (2,) horizontal, box_pose[-1, :2] - box_pose[0, :2] [m]
    max_penetration: float  # max over steps of -min(mjContact.dist), >= 0 [m]
    mean_contacts: float  # mean number of MuJoCo contacts per step
    max_tracking_error: float  # max |theta - theta_ref(t_k)| over joints and times [rad]
    max_joint_torque: float  # max |servo torque| (kinematic: equality force, position: actuator_force) [N m]
    n_warnings: int  # MuJoCo warnings raised during the run (all kinds)
    wall_time: float  # seconds spent in the stepping loop
    mode: str


def mujoco_available() -> bool:
    """True when ``import mujoco`` works.

    Helper: lets callers skip the cross-check instead of catching ``MujocoUnavailable``.
    """
    try:
        _import_mujoco()
    except MujocoUnavailable:
        return False
    return True


def _import_mujoco():
    try:
        import mujoco
    except ImportError as exc:
        raise MujocoUnavailable("the MuJoCo cross-check needs the optional dependency mujoco: "
                                "pip install mujoco (or pip install 'cobra-ref[test]')") from exc
    return mujoco


def servo_mjcf(model: Model, dt: float, mode: str = "kinematic", kp: float | None = None,
               kv: float | None = None) -> str:
    """MJCF of ``model`` with the joint servo of ``mode`` (module docstring).

    Helper: "position" is ``to_mjcf(model, dt, kp, kv)`` unchanged; "kinematic" removes its
    actuators and adds one equality/joint row per hinge, ``servo_<joint>``, solref = (2 dt, 1),
    solimp = (0.9999, 0.9999, 0.001, 0.5, 2), i.e. a constant impedance d = d_width = 0.9999.
    """
    if mode not in MODES:
        raise ValueError(f"mode must be one of {', '.join(MODES)}, got {mode!r}")
    kp, kv = _gains(kp, kv)
    root = ET.fromstring(to_mjcf(model, timestep=dt, kp=kp, kv=kv))
    if mode == "kinematic":
        root.remove(root.find("actuator"))
        equality = ET.SubElement(root, "equality")
        for i in _hinges(model):
            name = model.joint_names[i]
            ET.SubElement(equality, "joint", name=f"servo_{name}", joint1=name, polycoef="0 0 0 0 0",
                          solref=f"{2 * dt!r} 1", solimp="0.9999 0.9999 0.001 0.5 2")
    return ET.tostring(root, encoding="unicode")


def _gains(kp, kv):
    """kp, kv, or to_mjcf's defaults for the ones not given."""
    defaults = inspect.signature(to_mjcf).parameters
    return (defaults["kp"].default if kp is None else float(kp),
            defaults["kv"].default if kv is None else float(kv))


def _hinges(model: Model) -> list[int]:
    return [i for i, jt in enumerate(model.joint_type) if jt != "free"]


def _check_layout(model: Model, m) -> None:
    """MuJoCo's qpos / qvel addresses must be cobra_ref's, joint by joint."""
    if (m.nq, m.nv, m.njnt) != (model.nq, model.nv, len(model.joint_type)):
        raise MujocoRolloutError(f"MuJoCo model has nq, nv, njnt = {m.nq}, {m.nv}, {m.njnt}; "
                                 f"cobra_ref has {model.nq}, {model.nv}, {len(model.joint_type)}")
    for i, name in enumerate(model.joint_names):
        if (m.joint(i).name, m.jnt_qposadr[i], m.jnt_dofadr[i]) != (name, model.q_idx[i].start, model.v_idx[i].start):
            raise MujocoRolloutError(f"joint {i} ({name}) has a different qpos/qvel address in MuJoCo")


def rollout(model: Model, reference, q0, duration: float, dt: float = 1e-3, mode: str = "kinematic",
            kp: float | None = None, kv: float | None = None, qd0=None) -> MujocoRollout:
    """Roll the exported model out in MuJoCo for ``duration`` seconds with the joints driven by
    ``reference(t) -> (q_ref, qd_ref, qdd_ref)`` (11 joints) from the state (``q0``, ``qd0`` = 0).

    Implements: the MuJoCo rollout; the servos of the module docstring.

    Notes
    -----
    Per step k (t = k dt), before ``mj_step``::

        kinematic:  a0_i = theta_ref + 2 tau_c theta_dot_ref,  tau_c = 2 dt     # equality target
                    -> aref_i = -b (theta_dot - theta_dot_ref) - k (theta - theta_ref)
        position:   ctrl_i = theta_ref + (kv / kp) theta_dot_ref
                    -> force_i = kp (theta_ref - theta) + kv (theta_dot_ref - theta_dot)

    The kinematic target follows from [MJ] eq. (aref), aref = -b (J v) - k r with r = theta - a0,
    and from solref = (tau_c, 1) with constant impedance d: b = 2 / (d tau_c), k = 1 / (d tau_c^2),
    so b / k = 2 tau_c. Without the shift the row would damp theta_dot towards 0 and lag the
    reference by 2 tau_c theta_dot_ref (6 mrad at 1.6 rad/s, measured); with it, 1e-5 rad.
    """
    mujoco = _import_mujoco()
    if not (np.isfinite(duration) and duration > 0 and np.isfinite(dt) and dt > 0):
        raise ValueError(f"duration and dt must be positive and finite, got {duration}, {dt}")
    kp, kv = _gains(kp, kv)
    m = mujoco.MjModel.from_xml_string(servo_mjcf(model, dt, mode, kp, kv))
    d = mujoco.MjData(m)
    _check_layout(model, m)
    d.qpos[:] = model.check_q(np.asarray(q0, dtype=float))
    d.qvel[:] = 0.0 if qd0 is None else model.check_qd(np.asarray(qd0, dtype=float))
    hinge_q = [model.q_idx[i].start for i in _hinges(model)]
    box = model.q_idx[model.boxes[0].body]
    n = int(round(duration / dt))
    qpos = np.zeros((n + 1, m.nq))
    qpos[0] = d.qpos
    stats = _Stats(mujoco)
    start = time.perf_counter()
    for k in range(n):
        q_ref, qd_ref, _ = reference(k * dt)
        if mode == "kinematic":
            # equality/joint with no joint2: theta = qpos0 + a0 (qpos0 = 0 for a hinge), a0 = polycoef[0]
            m.eq_data[:, 0] = q_ref + 2 * (2 * dt) * qd_ref
        else:
            d.ctrl[:] = q_ref + (kv / kp) * qd_ref
        mujoco.mj_step(m, d)
        stats.add(m, d, mode)
        if not np.all(np.isfinite(d.qpos)) or d.warning[mujoco.mjtWarning.mjWARN_BADQACC].number:
            raise MujocoRolloutError(f"MuJoCo diverged at step {k}, t = {k * dt:.4f} s (mode {mode!r})")
        qpos[k + 1] = d.qpos
    wall = time.perf_counter() - start
    t = np.arange(n + 1) * dt
    q_ref_all = np.array([reference(tk)[0] for tk in t])
    return MujocoRollout(
        t=t, qpos=qpos, box_pose=qpos[:, box].copy(), box_displacement=qpos[-1, box][:2] - qpos[0, box][:2],
        max_penetration=stats.max_penetration, mean_contacts=stats.contacts / max(n, 1),
        max_tracking_error=float(np.abs(qpos[:, hinge_q] - q_ref_all).max()),
        max_joint_torque=stats.max_torque, n_warnings=int(sum(w.number for w in d.warning)),
        wall_time=wall, mode=mode)


class _Stats:
    """Running contact and servo statistics of a rollout."""

    def __init__(self, mujoco):
        self.equality = mujoco.mjtConstraint.mjCNSTR_EQUALITY
        self.max_penetration, self.contacts, self.max_torque = 0.0, 0, 0.0

    def add(self, m, d, mode: str) -> None:
        # mjContact.dist < 0 is a penetration; the contacts are those of the step's start state
        if d.ncon:
            self.max_penetration = max(self.max_penetration, -float(d.contact.dist[:d.ncon].min()))
        self.contacts += d.ncon
        if mode == "kinematic":  # the servo torque is the equality row's force (J = e_i for a joint row)
            rows = d.efc_type[:d.nefc] == self.equality
            torque = d.efc_force[:d.nefc][rows]
        else:
            torque = d.actuator_force
        self.max_torque = max(self.max_torque, float(np.abs(torque).max(initial=0.0)))


def compare(ours_displacement, mujoco_displacement, max_angle_deg: float = MAX_ANGLE_DEG,
            max_ratio: float = MAX_RATIO, min_displacement: float = MIN_DISPLACEMENT) -> dict:
    """Do two horizontal box displacements agree within the stated band?

    Implements: the tolerance band of the MuJoCo cross-check (compare bands, not equality).

    Returns ``angle_deg`` (between the two directions; nan if either is zero), ``ratio``
    (|mujoco| / |ours|), ``ours_norm`` and ``mujoco_norm`` [m], ``holds`` and ``reason``, and the
    ``band`` used. The band holds when both move the box at least ``min_displacement`` and
    angle <= ``max_angle_deg`` and 1 / ``max_ratio`` <= ratio <= ``max_ratio``, or when neither
    does (both agree the gait does not push the box); one moving it and the other not fails.

    Notes
    -----
    Why this band (stated before any run, not fitted to one). Everything except the contact law
    is shared: the same bodies, inertias, kinematics and Jacobians (``test_mujoco_oracle``: equal
    to 1e-9), the same gait, the same initial state, and a kinematic servo that tracks to 1e-5 rad.
    What differs is contact: ours is hard, velocity-level least action with Coulomb friction on a
    4-facet pyramid; MuJoCo's is soft (solref 4 ms, solimp 0.9-0.95: sub-mm penetration) and its
    friction is regularized, so a contact below the friction limit still creeps.

    * Direction, 45 deg: which way the box goes is set by geometry that both share (which side
      of the robot the box is on, which way the gait rolls or travels). More than 45 deg (nearer
      perpendicular than parallel) means the box was pushed by another part of the body or in
      another phase: a qualitative disagreement.
    * Magnitude, factor 3: the distance is the time integral of the box's slip, the quantity
      most sensitive to the contact law (when each robot-box contact starts and ends, its
      stick/slip split, and the cube sliding on mu = 1 at its tipping limit, where the split of
      its load between corners is undetermined: README "Pushing the box"). Each push also moves
      the box relative to the next one, so the differences compound over a run. A factor of 3
      still separates "pushes it about as far" from "barely nudges it" or "flings it".
    * Floor, 5 mm (5 % of the box edge): below it a direction is settling and creep, not a push.
    """
    d_o, d_m = np.asarray(ours_displacement, dtype=float)[:2], np.asarray(mujoco_displacement, dtype=float)[:2]
    n_o, n_m = float(np.linalg.norm(d_o)), float(np.linalg.norm(d_m))
    # cos(angle) = d_o . d_m / (|d_o| |d_m|)
    angle = float(np.degrees(np.arccos(np.clip(d_o @ d_m / (n_o * n_m), -1, 1)))) if n_o * n_m > 0 else float("nan")
    ratio = n_m / n_o if n_o > 0 else float("inf")
    if n_o < min_displacement and n_m < min_displacement:
        holds, reason = True, f"neither moves the box {min_displacement * 1000:g} mm"
    elif n_o < min_displacement or n_m < min_displacement:
        holds, reason = False, f"only {'MuJoCo' if n_m >= min_displacement else 'ours'} moves the box"
    else:
        holds = angle <= max_angle_deg and 1 / max_ratio <= ratio <= max_ratio
        reason = (f"angle {angle:.1f} deg (band <= {max_angle_deg:g}), "
                  f"ratio {ratio:.2f} (band [1/{max_ratio:g}, {max_ratio:g}])")
    return {"angle_deg": angle, "ratio": ratio, "ours_norm": n_o, "mujoco_norm": n_m, "holds": bool(holds),
            "reason": reason, "band": {"max_angle_deg": max_angle_deg, "max_ratio": max_ratio,
                                       "min_displacement": min_displacement}}


def cross_check(gait_names, duration: float, dt: float = 1e-3, ours: dict | None = None,
                box_directions: dict | None = None, mode: str = "kinematic", model: Model | None = None,
                kp: float | None = None, kv: float | None = None, params: dict | None = None) -> list[dict]:
    """For each gait: its MuJoCo rollout from our initial state, and ``compare`` against our box
    displacement ``ours[gait] = (dx, dy)`` when the caller supplies it.

    Implements: the gait-by-gait MuJoCo cross-check.

    The reference is ``gaits.gait(name, **params[name])`` (the defaults without ``params``); the initial state is
    ``simulate.initial_state(model, reference, box_direction=...)`` with ``box_directions[name]``
    if given, else, for sidewinding, ``reproduce.travel_direction(RunSpec("sidewinding",
    duration, dt))`` (a box-free run of our simulator, as the figure runs place it), else the
    concave side. Pass the direction our run used (its ``meta["box_direction"]``) to skip that
    run. Each row: gait, mode, duration, dt, box_direction, mujoco_displacement, ours_displacement
    (or None), the MuJoCo contact / servo stats, wall_time, and the ``compare`` keys when ``ours``
    has the gait.
    """
    from ..gaits import gait
    from ..robots import cobra_model
    from ..start import initial_state

    _import_mujoco()
    model = cobra_model() if model is None else model
    ours, box_directions = ours or {}, box_directions or {}
    rows = []
    for name in gait_names:
        reference = gait(name, **(params or {}).get(name, {}))
        direction = box_directions.get(name)
        if direction is None and name == "sidewinding":
            from .runs import RunSpec, travel_direction

            direction = travel_direction(RunSpec("sidewinding", duration, dt))
        q0, qd0 = initial_state(model, reference, box_direction=direction)
        res = rollout(model, reference, q0, duration, dt, mode, kp, kv, qd0)
        row = {"gait": name, "mode": mode, "duration": duration, "dt": dt,
               "box_direction": None if direction is None else [float(x) for x in np.asarray(direction)[:2]],
               "mujoco_displacement": [float(x) for x in res.box_displacement],
               "ours_displacement": None if name not in ours else [float(x) for x in np.asarray(ours[name])[:2]],
               "max_penetration": res.max_penetration, "mean_contacts": res.mean_contacts,
               "max_tracking_error": res.max_tracking_error, "max_joint_torque": res.max_joint_torque,
               "n_warnings": res.n_warnings, "wall_time": res.wall_time}
        if name in ours:
            row.update(compare(ours[name], res.box_displacement))
        rows.append(row)
    return rows
