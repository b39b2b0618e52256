"""MuJoCo compared with cobra_ref like for like: the same model, contact law, servo and start.

Implements: the MuJoCo comparison of ``docs/mujoco.md``. MuJoCo runs the MJCF of
:func:`cobra_ref.mjcf.to_mjcf`, whose contact is our spring-damper with Coulomb's circle (the
mapping of assumption A27) and whose joints are the position servo of A7, from our own settled
start (A25). [MJ] = MuJoCo documentation, "Computation" and "XML Reference" (actuator/position).

MuJoCo's qpos / qvel layout is cobra_ref's (A19: free joint 7 + 11 hinges, the box's free joint
7; nv = 23 with the box), so a start (q0, qd0) goes in unchanged; ``rollout`` checks the joint
addresses of the compiled model against ``model.q_idx`` / ``model.v_idx`` before it starts.

The servo. MuJoCo's position actuator applies clip(kp (ctrl - q) - kv qd, +-tau_max) ([MJ]
actuator/position: gainprm = kp, biasprm = (0, -kp, -kv)); with ctrl = q_ref + (kv / kp) qd_ref
this is kp (q_ref - q) + kv (qd_ref - qd), our servo law (A7, ``servo_control``), with the
reference taken at the step's start as ours is (``compliance.servo_rows``).

Two comparisons, each with its band stated here, before any run:

* ``robot_travel_rows``: the robot alone (no box), each paper gait, ``TRAVEL_DURATION`` = 3 s
  from the same settled start in both simulators. Holds when the travel of the robot's centre
  of mass agrees within ``TRAVEL_BAND`` = 10 %: |d_MuJoCo - d_ours| <= 0.10 |d_ours| (the
  vector difference, so length and direction both count: 10 % allows 5.7 degrees). Why 3 s:
  it is 1.5 periods of the 0.5 Hz gaits (A10), the one-period ramp and half a period at full
  amplitude, and the robot then travels 0.3-0.7 m, so the band (3-7 cm) is far above settling
  and creep (mm); over longer runs the two integrators' differences compound. Our side's runs
  go to any ``concurrent.futures.Executor``.
* ``box_ensemble_rows``: the robot pushing the box, per gait an ensemble of starts (and friction
  scales) supplied by the caller, run in MuJoCo from the same states. The ensembles overlap
  (``ensembles_overlap``) when the lengths of the box displacements and their directions, each
  over the members as [min, max] with every member's end point widened by ``RESOLUTION`` =
  5 mm (5 % of the box's edge: below it a displacement is settling and creep, not a push),
  overlap between the two simulators. Pushing a box is sensitive to where and when each link
  meets it, so single runs may differ more than the simulators do; the ensemble's spread is
  that sensitivity.

mujoco is an optional dependency (the ``test`` extra): without it ``rollout`` and the row
functions raise ``MujocoUnavailable`` saying so, and ``mujoco_available()`` is False.
"""

from __future__ import annotations

import dataclasses
import time
from typing import NamedTuple

import numpy as np

from ..infra.validation import DEFAULT_DT
from ..mjcf import TIMESTEP, to_mjcf
from ..model import Model

TRAVEL_DURATION = 3.0  # [s] the robot-only comparison (module docstring)
TRAVEL_BAND = 0.10  # |d_MuJoCo - d_ours| <= TRAVEL_BAND |d_ours|
RESOLUTION = 0.005  # [m] each box displacement's end point is known to this (5 % of the box's edge)


class MujocoUnavailable(ImportError):
    """mujoco is not installed (it is an optional extra)."""


class MujocoRolloutError(RuntimeError):
    """A MuJoCo rollout that cannot go on (diverged, or the model does not match)."""


class MujocoRollout(NamedTuple):
    """What a MuJoCo rollout returns (states at the N + 1 times t_k = k timestep, stats over the N steps)."""

    t: np.ndarray  # (N+1,) [s]
    qpos: np.ndarray  # (N+1, nq), cobra_ref's q layout
    max_penetration: float  # max over steps of -min(mjContact.dist), >= 0 [m]
    mean_contacts: float  # mean number of MuJoCo contacts per step
    max_tracking_error: float  # max |q - q_ref(t_k)| over joints and times [rad]
    max_joint_torque: float  # max |actuator_force| [N m]
    n_warnings: int  # MuJoCo warnings raised during the run (all kinds)
    wall_time: float  # seconds spent in the stepping loop


def mujoco_available() -> bool:
    """True when ``import mujoco`` works.

    Lets callers skip the comparison instead of catching ``MujocoUnavailable``.
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
        raise MujocoUnavailable("the MuJoCo comparison needs the optional dependency mujoco: "
                                "pip install mujoco (or pip install 'cobra-ref[test]')") from exc
    return mujoco


def servo_control(model: Model, q_ref, qd_ref) -> np.ndarray:
    """ctrl = q_ref + (kv / kp) qd_ref: MuJoCo's position actuators then apply our servo law.

    Implements: the position servo of assumption A7 as MuJoCo's actuator/position
    (module docstring): kp (ctrl - q) - kv qd = kp (q_ref - q) + kv (qd_ref - qd).
    """
    return np.asarray(q_ref, dtype=float) + (model.servo_kd / model.servo_kp) * np.asarray(qd_ref, dtype=float)


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


def rollout(model: Model, reference, q0, duration: float, timestep: float = TIMESTEP, qd0=None) -> MujocoRollout:
    """Roll ``to_mjcf(model, timestep)`` out in MuJoCo for ``duration`` seconds from (``q0``, ``qd0`` = 0),
    the joints driven by ``reference(t) -> (q_ref, qd_ref, qdd_ref)``.

    Implements: the MuJoCo rollout of the module docstring. Per step k, before ``mj_step``,
    ctrl = ``servo_control``(q_ref(t_k), qd_ref(t_k)). Raises ``MujocoRolloutError`` when
    the state becomes non-finite or MuJoCo reports a bad position, velocity or acceleration.
    """
    mujoco = _import_mujoco()
    if not (np.isfinite(duration) and duration > 0):
        raise ValueError(f"duration must be positive and finite, got {duration}")
    m = mujoco.MjModel.from_xml_string(to_mjcf(model, timestep))
    d = mujoco.MjData(m)
    _check_layout(model, m)
    d.qpos[:] = model.check_q(np.asarray(q0, dtype=float))
    d.qvel[:] = 0.0 if qd0 is None else model.check_qd(np.asarray(qd0, dtype=float))
    n = int(round(duration / timestep))
    t = np.arange(n + 1) * timestep
    qpos = np.zeros((n + 1, m.nq))
    qpos[0] = d.qpos
    hinge_q = [model.q_idx[i].start for i in _hinges(model)]
    q_refs, forces = np.zeros((n, len(hinge_q))), np.zeros((n, m.nu))
    penetration, contacts = 0.0, 0
    start = time.perf_counter()
    # the loop does only what needs the live mjData; the statistics come from its records afterwards
    for k in range(n):
        q_ref, qd_ref, _ = reference(t[k])
        d.ctrl[:] = servo_control(model, q_ref, qd_ref)
        mujoco.mj_step(m, d)
        forces[k], q_refs[k] = d.actuator_force, q_ref  # the force over the step from t_k
        qpos[k + 1] = d.qpos
        # mjContact.dist < 0 is a penetration (the contacts of the step's start state)
        if d.ncon:
            contacts += d.ncon
            penetration = max(penetration, -float(d.contact.dist[:d.ncon].min()))
        if (k + 1) % DIVERGENCE_CHECK == 0 or k + 1 == n:
            _check_diverged(mujoco, d, qpos, k, timestep, (k // DIVERGENCE_CHECK) * DIVERGENCE_CHECK)
    return MujocoRollout(t=t, qpos=qpos, max_penetration=penetration, mean_contacts=contacts / max(n, 1),
                         max_tracking_error=float(np.abs(qpos[:-1, hinge_q] - q_refs).max(initial=0.0)),
                         max_joint_torque=float(np.abs(forces).max(initial=0.0)),
                         n_warnings=int(sum(w.number for w in d.warning)), wall_time=time.perf_counter() - start)


DIVERGENCE_CHECK = 100  # [steps] how often a rollout checks its state for NaN or an unstable-simulation warning


def _check_diverged(mujoco, d, qpos, k: int, timestep: float, since: int = 0) -> None:
    """Raise ``MujocoRolloutError`` naming the first step that left a non-finite state in
    ``qpos[since + 1:k + 2]`` (the states after the last check, which found ``qpos[:since + 1]`` finite),
    or, when MuJoCo reported a bad position, velocity or acceleration (it then resets the state and
    goes on), the check's step k by which it happened."""
    bad = np.flatnonzero(~np.isfinite(qpos[since + 1:k + 2]).all(axis=1))
    if len(bad):
        j = since + int(bad[0])
        raise MujocoRolloutError(f"MuJoCo diverged at step {j}, t = {j * timestep:.4f} s (timestep {timestep:g} s)")
    unstable = [name for name in ("BADQPOS", "BADQVEL", "BADQACC") if d.warning[getattr(mujoco.mjtWarning, f"mjWARN_{name}")].number]
    if unstable:
        raise MujocoRolloutError(f"MuJoCo diverged by step {k}, t = {k * timestep:.4f} s (timestep {timestep:g} s): "
                                 f"it reported {', '.join(unstable)} and reset the state")


def robot_com(model: Model, q) -> np.ndarray:
    """(2,) horizontal position of the robot's centre of mass (every body but the box) [m].

    The travel of the robot-only comparison, the mass-weighted mean of the bodies' centres of mass,
    for our trajectories and MuJoCo's alike.
    """
    from ..kinematics import forward_kinematics

    boxes = {box.body for box in model.boxes}
    robot = [i for i in range(model.nb) if i not in boxes]
    kin = forward_kinematics(model, q)
    com = np.array([kin.o[i] + kin.R[i] @ model.com[i] for i in robot])
    return np.average(com, axis=0, weights=[model.mass[i] for i in robot])[:2]


def box_displacement(model: Model, q_start, q_end) -> np.ndarray:
    """(2,) horizontal displacement of the box's centre between two configurations [m].
    """
    iq = model.q_idx[model.boxes[0].body]
    return np.asarray(q_end, dtype=float)[iq][:2] - np.asarray(q_start, dtype=float)[iq][:2]


def compare_travel(ours, mujoco, band: float = TRAVEL_BAND) -> dict:
    """Do two travels of the centre of mass agree within ``band``: |d_MuJoCo - d_ours| <= band |d_ours|?

    Implements: the band of the robot-only comparison (module docstring). Returns ``ours_length``,
    ``mujoco_length`` [m], ``difference`` |d_MuJoCo - d_ours| [m], ``relative`` (difference /
    |d_ours|; inf when ours does not move), ``angle_deg`` between the two (nan if either is zero)
    and ``holds``.
    """
    d_o, d_m = np.asarray(ours, dtype=float)[:2], np.asarray(mujoco, dtype=float)[:2]
    n_o, n_m, diff = float(np.linalg.norm(d_o)), float(np.linalg.norm(d_m)), float(np.linalg.norm(d_m - d_o))
    # cos(angle) = d_o . d_m / (|d_o| |d_m|)
    angle = float(np.degrees(np.arccos(np.clip(d_o @ d_m / (n_o * n_m), -1, 1)))) if n_o * n_m > 0 else float("nan")
    relative = diff / n_o if n_o > 0 else (0.0 if diff == 0 else float("inf"))
    return {"ours_length": n_o, "mujoco_length": n_m, "difference": diff, "relative": relative,
            "angle_deg": angle, "holds": bool(relative <= band)}


def _ours_travel(name: str, gait_params: dict, duration: float, dt: float) -> dict:
    """Our side of one robot-only run (in a worker): the settled start and the state after ``duration``."""
    from ..gaits import gait
    from ..robots import cobra_model
    from ..simulate import simulate
    from ..start import initial_state
    from ..step import StepSettings

    model, reference, settings = cobra_model(with_box=False), gait(name, **gait_params), StepSettings(dt=dt)
    q0, qd0 = initial_state(model, reference, settings)
    traj = simulate(model, reference, duration, settings, q0=q0, qd0=qd0)
    return {"q0": q0, "qd0": qd0, "q_end": traj.q[-1], "wall_time": traj.wall_time}


def robot_travel_rows(gaits, duration: float = TRAVEL_DURATION, executor=None, timestep: float = TIMESTEP,
                      dt: float = DEFAULT_DT, params: dict | None = None) -> list[dict]:
    """For each gait, the robot alone (no box): the travel of its centre of mass over ``duration``
    in our simulator (step ``dt``) and in MuJoCo (``timestep``), from the same settled start.

    Implements: the robot-only comparison of the module docstring (band ``TRAVEL_BAND``).
    ``gaits``: names for ``gaits.gait``, with ``params[name]`` its parameters (default the
    gait's own); our runs go to ``executor`` (any ``concurrent.futures.Executor``; default
    serial), MuJoCo's run here. Each row: kind "travel", gait, duration, dt, timestep, ``ours``
    and ``mujoco`` (dx, dy) [m], the ``compare_travel`` keys, ``band``, and MuJoCo's
    max_penetration, max_tracking_error, max_joint_torque, n_warnings and wall times.
    """
    from ..infra.executors import SerialExecutor
    from ..gaits import gait
    from ..robots import cobra_model

    _import_mujoco()
    model, params, executor = cobra_model(with_box=False), params or {}, executor or SerialExecutor()
    futures = {name: executor.submit(_ours_travel, name, params.get(name, {}), duration, dt) for name in gaits}
    rows = []
    for name, future in futures.items():
        ours = future.result()
        res = rollout(model, gait(name, **params.get(name, {})), ours["q0"], duration, timestep, ours["qd0"])
        d_o = robot_com(model, ours["q_end"]) - robot_com(model, ours["q0"])
        d_m = robot_com(model, res.qpos[-1]) - robot_com(model, res.qpos[0])
        rows.append({"kind": "travel", "gait": name, "duration": duration, "dt": dt, "timestep": timestep,
                     "ours": [float(x) for x in d_o], "mujoco": [float(x) for x in d_m], **compare_travel(d_o, d_m),
                     "band": TRAVEL_BAND, "max_penetration": res.max_penetration,
                     "max_tracking_error": res.max_tracking_error, "max_joint_torque": res.max_joint_torque,
                     "n_warnings": res.n_warnings, "ours_wall_time": ours["wall_time"],
                     "mujoco_wall_time": res.wall_time})
    return rows


def scaled_friction(model: Model, mu_scale: float) -> Model:
    """``model`` with every coefficient of friction (robot-ground, box-ground, robot-box) times ``mu_scale``.
    """
    if mu_scale == 1.0:
        return model
    return dataclasses.replace(model, mu=model.mu * mu_scale, mu_robot_box=model.mu_rb * mu_scale)


def box_ensemble_rows(members: dict, duration: float, timestep: float = TIMESTEP, model: Model | None = None) -> list[dict]:
    """For each gait, its ensemble of box pushes in MuJoCo beside ours, and whether the two overlap.

    Implements: the box-ensemble comparison of the module docstring (rule ``ensembles_overlap``).
    ``members`` = {gait: [member, ...]}, each member a dict with ``reference`` (the joint
    reference), ``q0`` (the start, box included; ``qd0`` optional, default 0), ``mu_scale``
    (friction multiplier, ``scaled_friction``; 1.0 nominal) and ``ours`` (our box displacement
    (dx, dy) [m] after ``duration``). ``model``: the robot with the box (default
    ``cobra_model()``). Each row: kind "box", gait, duration, timestep, n_members, mu_scale,
    ``ours`` and ``mujoco`` (the (dx, dy) of each member) [m], the ``ensembles_overlap`` keys,
    and MuJoCo's max_penetration and n_warnings over the members.
    """
    from ..robots import cobra_model

    _import_mujoco()
    model = cobra_model() if model is None else model
    rows = []
    for name, ensemble in members.items():
        mujoco_d, penetration, warnings = [], 0.0, 0
        for member in ensemble:
            res = rollout(scaled_friction(model, float(member.get("mu_scale", 1.0))), member["reference"],
                          member["q0"], duration, timestep, member.get("qd0"))
            mujoco_d.append([float(x) for x in box_displacement(model, res.qpos[0], res.qpos[-1])])
            penetration, warnings = max(penetration, res.max_penetration), warnings + res.n_warnings
        ours_d = [[float(x) for x in np.asarray(member["ours"], dtype=float)[:2]] for member in ensemble]
        rows.append({"kind": "box", "gait": name, "duration": duration, "timestep": timestep,
                     "n_members": len(ensemble), "mu_scale": [float(m.get("mu_scale", 1.0)) for m in ensemble],
                     "ours": ours_d, "mujoco": mujoco_d, **ensembles_overlap(ours_d, mujoco_d),
                     "max_penetration": penetration, "n_warnings": warnings})
    return rows


def _length_interval(d: np.ndarray, resolution: float) -> tuple[float, float]:
    """[min |d_i| - resolution, max |d_i| + resolution] over the members (lower end at least 0)."""
    length = np.linalg.norm(d, axis=1)
    return max(0.0, float(length.min()) - resolution), float(length.max()) + resolution


def _direction_arc(d: np.ndarray, resolution: float) -> tuple[float, float]:
    """(centre, half-width) [deg] of the arc of directions covered by the members' end points, each
    widened to a disk of radius ``resolution``; a member shorter than that points anywhere (180)."""
    length = np.linalg.norm(d, axis=1)
    if np.any(length <= resolution):
        return 0.0, 180.0
    phi = np.arctan2(d[:, 1], d[:, 0])
    mean = np.arctan2(np.sin(phi).sum(), np.cos(phi).sum())
    # each member's angle from the mean direction, wrapped to (-pi, pi], +- the angle its disk subtends
    rel = np.angle(np.exp(1j * (phi - mean)))
    alpha = np.arcsin(resolution / length)
    lo, hi = float((rel - alpha).min()), float((rel + alpha).max())
    return float(np.degrees(mean + (lo + hi) / 2)), min(180.0, float(np.degrees((hi - lo) / 2)))


def ensembles_overlap(ours, mujoco, resolution: float = RESOLUTION) -> dict:
    """Do two ensembles of box displacements overlap in length and in direction?

    Implements: the rule of the box-ensemble comparison (module docstring), stated before any
    run. Every member's end point is a disk of radius ``resolution``. Length: the intervals
    [min |d_i| - resolution, max |d_i| + resolution] of the two ensembles intersect. Direction:
    the arcs of directions their disks cover intersect (an arc is the whole circle when a
    member moves the box less than ``resolution``: its direction is undetermined); arcs meet
    when the angle between their centres is at most the sum of their half-widths. The
    ensembles overlap when both hold. When no member of either ensemble moves the box by more
    than ``resolution`` there is nothing to compare: ``holds`` is None (not tested), so a push
    too short to see cannot pass the check. Returns ``ours_length`` and ``mujoco_length`` (the
    intervals) [m], ``ours_direction_deg`` and ``mujoco_direction_deg`` (centre, half-width)
    [deg], ``length_overlap``, ``direction_overlap``, ``holds``, ``reason``, ``resolution``.
    """
    d_o, d_m = np.asarray(ours, dtype=float).reshape(-1, 2), np.asarray(mujoco, dtype=float).reshape(-1, 2)
    L_o, L_m = _length_interval(d_o, resolution), _length_interval(d_m, resolution)
    length_overlap = L_o[0] <= L_m[1] and L_m[0] <= L_o[1]
    arc_o, arc_m = _direction_arc(d_o, resolution), _direction_arc(d_m, resolution)
    # the angle between the arcs' centres, wrapped to [0, 180]
    between = abs((arc_m[0] - arc_o[0] + 180.0) % 360.0 - 180.0)
    direction_overlap = between <= arc_o[1] + arc_m[1]
    moved = max(np.linalg.norm(d_o, axis=1).max(), np.linalg.norm(d_m, axis=1).max()) > resolution
    holds = bool(length_overlap and direction_overlap) if moved else None
    reason = "" if moved else "neither simulator moves the box by more than the resolution: not tested; "
    reason += (f"length {1e3 * L_o[0]:.0f}-{1e3 * L_o[1]:.0f} mm vs {1e3 * L_m[0]:.0f}-{1e3 * L_m[1]:.0f} mm "
              f"({'overlap' if length_overlap else 'apart'}); direction {arc_o[0]:.0f} +- {arc_o[1]:.0f} deg vs "
              f"{arc_m[0]:.0f} +- {arc_m[1]:.0f} deg ({'overlap' if direction_overlap else 'apart'})")
    return {"ours_length": list(L_o), "mujoco_length": list(L_m), "ours_direction_deg": list(arc_o),
            "mujoco_direction_deg": list(arc_m), "length_overlap": bool(length_overlap),
            "direction_overlap": bool(direction_overlap), "holds": holds,
            "reason": reason, "resolution": resolution}


def claims(rows: list[dict]) -> list[dict]:
    """Claim entries {"id", "claim", "values", "holds"} from robot-travel and box-ensemble rows.

    The MuJoCo part of the claims report; ids "MJ-travel-<gait>" and "MJ-box-<gait>".
    """
    return [_travel_claim(r) if r["kind"] == "travel" else _box_claim(r) for r in rows]


def _travel_claim(r: dict) -> dict:
    text = (f"MuJoCo (the same contact law, servo and start) moves the robot alone like cobra_ref for {r['gait']}: "
            f"over {r['duration']:g} s its centre of mass travels within {100 * r['band']:g} % "
            f"(|d_MuJoCo - d_ours| <= {r['band']:g} |d_ours|)")
    values = {"ours_travel_m": r["ours"], "mujoco_travel_m": r["mujoco"], "relative_difference": r["relative"],
              "angle_deg": r["angle_deg"], "mujoco_max_penetration_m": r["max_penetration"]}
    return {"id": f"MJ-travel-{r['gait']}", "claim": text, "values": values, "holds": r["holds"]}


def _box_claim(r: dict) -> dict:
    text = (f"MuJoCo's and cobra_ref's ensembles of box pushes overlap for {r['gait']} ({r['n_members']} members, "
            f"{r['duration']:g} s): the lengths and the directions of the box displacements, each member's end "
            f"point widened by {1e3 * r['resolution']:g} mm")
    values = {"ours_length_m": r["ours_length"], "mujoco_length_m": r["mujoco_length"],
              "ours_direction_deg": r["ours_direction_deg"], "mujoco_direction_deg": r["mujoco_direction_deg"],
              "reason": r["reason"]}
    return {"id": f"MJ-box-{r['gait']}", "claim": text, "values": values, "holds": r["holds"]}
