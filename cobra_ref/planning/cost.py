"""The cost of one rollout of the shooting problem, and its contact and limit report.

Implements: the cost J(p) of the single-shooting problem (``planning.problem`` states it) and
the per-rollout record that the search keeps for every candidate.
"""

from __future__ import annotations

import numpy as np

from ..robots import cobra_model
from ..step import SimulationError
from ..trajectory import Trajectory
from .problem import FAILED_COST, ShootingProblem, rollout, rollouts

BOX_PATH_DT = 0.01  # [s] spacing of the box path kept with each rollout (the optimum's is drawn)


def robot_weight(model) -> float:
    """m_robot g [N]: the robot's weight (every body that is not a box) under the model's gravity.

    The scale of the impact term (``impact_term``); 12 bodies (head, 10 links, tail) x 0.5 kg x 9.81
    m/s^2 = 58.86 N for COBRA.
    """
    boxes = {b.body for b in model.boxes}
    mass = sum(m for i, m in enumerate(model.mass) if i not in boxes)
    return float(mass * np.linalg.norm(model.gravity))


def impact_term(traj: Trajectory, weight: float, duration: float) -> float:
    """I = (total impact impulse of the rollout) / (m_robot g T), dimensionless.

    Implements: [COBRA] sec. "Results", "contact forces f_ext stand orthogonal to gap functions and
    their derivative" (no contact force where a gap closes with speed) as a penalty: the impulse of
    every impact (assumption A26: a contact that starts carrying load while approaching faster
    than 1 cm/s; m v_a per impact, ``steps["impact_impulse"]``) summed over the rollout, per
    second, as a fraction of the robot's weight ``weight`` = m_robot g. Zero for a rollout without
    impacts.
    """
    return float(np.sum(traj.steps["impact_impulse"])) / (weight * duration)


def effort_term(traj: Trajectory, tau_max: float, duration: float) -> float:
    """E = integral ||tau||^2 dt / (n tau_max^2 T), dimensionless: the joints' mean squared torque
    over tau_max^2 (n joints, T = ``duration``)."""
    return traj.dt * float(np.sum(traj.tau**2)) / (traj.tau.shape[1] * tau_max**2 * duration)


def excess_term(traj: Trajectory, key: str, limit: float, duration: float) -> float:
    """P = integral max(0, excess) dt / (limit T), dimensionless: ``steps[key]`` (a limit's excess per
    step, max_i |.| - limit) where it is positive, over the limit and T = ``duration``."""
    return traj.dt * float(np.sum(np.maximum(traj.steps[key], 0.0))) / (limit * duration)


def shooting_cost(problem: ShootingProblem, traj: Trajectory) -> dict:
    """The cost J of a rollout and its terms (module docstring).

    Implements: the shooting cost (assumption A17), [COBRA] eq. (6) constraints (2), (3) as exact
    penalties, and its non-impulsive condition as the impact term (assumption A28)::

        J = w_e E + w_g (d_T / d_0)^2 + w_I I + w_tau P_tau + w_q P_q
    """
    cp, w, T = problem.cobra, problem.weights, problem.duration
    effort = effort_term(traj, cp.tau_max, T)
    # d_T = |p_box(T) - p_goal|, d_0 = |goal|
    d_T = float(np.linalg.norm(traj.box_pose[-1, :2] - problem.goal_world))
    goal = (d_T / float(np.hypot(*problem.goal))) ** 2
    p_tau, p_q = excess_term(traj, "tau_excess", cp.tau_max, T), excess_term(traj, "q_excess", cp.q_max, T)
    # I = sum of the impacts' impulses / (m_robot g T)
    impact = impact_term(traj, robot_weight(cobra_model(cp)), T)
    cost = w.effort * effort + w.goal * goal + w.impact * impact + w.tau * p_tau + w.q * p_q
    return {"cost": cost, "box_distance_to_goal": d_T,
            "terms": {"effort": effort, "goal": goal, "impact": impact, "tau_limit": p_tau, "q_limit": p_q}}


def contact_report(traj: Trajectory, tau_max: float) -> dict:
    """How well every step's contact impulses met the QP's conditions, and the limits' record.

    Implements: the KKT conditions of eq. (6) per step (``least_action.kkt_residuals``):
    complementarity max_i |p_N,i g_N,i| [N s m/s], the friction outside Coulomb's circle and
    the steps whose friction fixed point did not converge, maxima over the rollout; the impacts
    (approach speed at contact onset, the paper's non-impulsive condition); and the torque and
    joint-limit excess (``tau_excess``, ``q_excess``).
    """
    s = traj.steps
    n = max(len(traj.tau), 1)
    return {"max_complementarity": float(np.max(s["complementarity"], initial=0.0)),
            "max_cone_residual": float(np.max(s["cone_residual"], initial=0.0)),
            "max_penetration": float(np.max(s["max_penetration"], initial=0.0)),
            "steps_not_converged": int(np.sum(s["fp_converged"] == 0)),
            "impact_impulse": float(np.sum(s["impact_impulse"])),
            "impacts": int(np.sum(s["impact_count"])),
            "max_tau_excess": float(np.max(s["tau_excess"], initial=-np.inf)),
            "steps_over_tau_max": int(np.sum(s["tau_excess"] > 0)),
            "fraction_over_tau_max": float(np.sum(s["tau_excess"] > 0)) / n,
            "rms_tau_over_tau_max": float(np.sqrt(np.mean(traj.tau**2))) / tau_max if len(traj.tau) else 0.0,
            "max_q_excess": float(np.max(s["q_excess"], initial=-np.inf))}


def evaluate(problem: ShootingProblem, x) -> dict:
    """One rollout's history entry: params, cost, box_distance_to_goal, the cost terms, the final
    box position, the contact and limit report, and the error if the simulation failed; and
    ``box_path``, the box's (x, y) every ``BOX_PATH_DT`` and at the end ((n, 2) array), which the
    params JSON keeps for the optimum only (``results.result_to_dict``). What the executor runs (a
    module-level function: picklable for a process pool).
    """
    try:
        traj, error = rollout(problem, x), ""
    except SimulationError as exc:
        traj, error = exc.trajectory, str(exc)
    return _entry(problem, x, traj, error)


def evaluate_batch(problem: ShootingProblem, xs) -> list:
    """``evaluate`` of each candidate in xs, their rollouts advanced together (``problem.rollouts``):
    the same entries, bit for bit. What the executor runs (picklable)."""
    return [_entry(problem, x, traj, error) for x, (traj, error) in zip(xs, rollouts(problem, xs))]


def _entry(problem: ShootingProblem, x, traj, error: str) -> dict:
    """The history entry (``evaluate``) of candidate x from its rollout ``traj`` (None: none) and
    the rollout's error ("" if none)."""
    entry = {"params": {n: float(v) for n, v in zip(problem.names, x)}, "error": error or None}
    if traj is None or entry["error"]:
        entry.update(cost=FAILED_COST, box_distance_to_goal=None, terms=None)
    else:
        entry.update(shooting_cost(problem, traj))
    if traj is not None:
        entry["box_final"] = [float(v) for v in traj.box_pose[-1, :2]]
        every = max(1, int(round(BOX_PATH_DT / problem.dt)))
        rows = np.unique(np.append(np.arange(0, len(traj.box_pose), every), len(traj.box_pose) - 1))
        entry["box_path"] = traj.box_pose[rows, :2].copy()
        entry["contact"] = contact_report(traj, problem.cobra.tau_max)
    return entry


def cost_without_impact(problem: ShootingProblem, entry: dict) -> float:
    """J - w_I I of a history entry (a failed rollout keeps its J): the cost the companion search
    of ``search.optimize`` minimizes."""
    terms = entry.get("terms")
    return entry["cost"] if terms is None else entry["cost"] - problem.weights.impact * terms["impact"]
