"""The params JSON of an optimization: the optimum, every rollout, every setting; its replay.

The output of ``cobra-ref optimize`` and the input of ``cobra-ref simulate --params`` and of the
figures.
"""

from __future__ import annotations

import dataclasses
import json
import os
import sys
from dataclasses import asdict
from typing import NamedTuple

import numpy as np

from ..infra.output import atomic_write
from ..infra.validation import value_text
from ..provenance import code_version
from ..gaits import gait
from ..params import CobraParameters
from ..robots import cobra_model
from ..step import SimulationError, StepSettings
from ..trajectory import Trajectory
from .cost import BOX_PATH_DT, cost_without_impact, shooting_cost
from .problem import DECISION, FORMAT, ShootingError, ShootingProblem, Weights, check_goal, rollout, start_state

CHECK_DT = 5e-4  # [s] the high-fidelity check's step, the converged setting (docs/results.md, "Does a result
# hold when dt halves?")
# the params JSON's "step_settings": ``substeps`` is the touch-down substeps n the run took (A33), also where
# ``touchdown_substeps`` is None, the law's default
STEP_SETTINGS_KEYS = ("dt", "contact", "servo", "margin", "touchdown_substeps", "substeps")
TRANSFER_KEYS = ("plan_dt", "check_dt", "plan_distance_to_goal", "check_distance_to_goal",
                 "plan_impact_impulse_per_s", "check_impact_impulse_per_s")

def problem_to_dict(problem: ShootingProblem) -> dict:
    """The problem as JSON-ready settings (every input of a rollout): the ``settings`` part of the
    params JSON."""
    s = problem.settings
    return {"gait": problem.gait, "goal": list(problem.goal), "goal_world": [float(v) for v in problem.goal_world],
            "duration": problem.duration, "dt": problem.dt,
            "step_settings": {k: getattr(s, k) for k in STEP_SETTINGS_KEYS},
            "decision": {"names": list(problem.names), "lower": list(problem.lower), "upper": list(problem.upper),
                         "x0": list(problem.x0)},
            "fixed": dict(problem.fixed), "weights": asdict(problem.weights),
            "box_pose0": list(problem.box_pose0), "middle_pose0": list(problem.middle_pose0),
            "box_direction": None if problem.box_direction is None else list(problem.box_direction),
            "cobra_parameters": {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(problem.cobra).items()},
            "servo": s.servo, "contact": s.contact}


def problem_from_dict(d: dict) -> ShootingProblem:
    """The problem back from ``problem_to_dict``'s output; ShootingError if malformed.

    Every setting is checked by its rule (:mod:`cobra_ref.infra.validation`) and the message names
    it ("malformed settings in params JSON: settings.<field>: ..."): a missing key, a string where a
    number belongs, a non-finite number, dt and duration (a time grid of at most ``MAX_STEPS``),
    the goal (``check_goal``: not at the box's start, reachable), the decision (names, bounds
    lower < upper, x0 within them), the weights (finite, >= 0), the CobraParameters (each field's
    rule), servo and contact law (``StepSettings``), the gait and its parameters at x0.
    """
    from ..infra.validation import ValidationError

    parts: dict = {}
    for where, read in _SETTINGS_READERS:
        try:
            parts.update(read(d, parts))
        except KeyError as exc:
            message = f"missing key {exc}"
        except (ShootingError, ValidationError) as exc:
            message = str(exc)
        except (TypeError, ValueError, AttributeError) as exc:
            message = f"{type(exc).__name__}: {exc}"
        else:
            continue
        raise ShootingError(f"malformed settings in params JSON: {where}: {message}") from None
    return parts["problem"]


def _read_object(d, parts) -> dict:
    if not isinstance(d, dict):
        raise TypeError(f"expected an object, got {type(d).__name__}")
    return {}


def _read_decision(d, parts) -> dict:
    dec = d["decision"]
    names = tuple(map(str, dec["names"]))
    lower, upper, x0 = (_floats(dec[k], len(names), f"decision.{k}") for k in ("lower", "upper", "x0"))
    for n, lo, hi, x in zip(names, lower, upper, x0):
        if not lo < hi:
            raise ValueError(f"bounds of {n} must have lower < upper, got [{lo}, {hi}]")
        if not lo <= x <= hi:
            raise ValueError(f"x0 {n} = {x} is outside its bounds [{lo}, {hi}]")
    return {"names": names, "lower": lower, "upper": upper, "x0": x0}


def _read_time(d, parts) -> dict:
    from ..infra.validation import RULES, time_grid

    dt, duration = float(RULES["dt"].check(d["dt"], "dt")), d["duration"]
    time_grid(duration, dt, exact=False)
    return {"dt": dt, "duration": float(duration)}


def _read_goal(d, parts) -> dict:
    return {"goal": check_goal(_floats(d["goal"], 2, "goal"), parts["duration"])}


def _read_fixed(d, parts) -> dict:
    from ..infra.validation import is_number

    fixed = d["fixed"]
    if not isinstance(fixed, dict) or not all(is_number(v) and np.isfinite(v) for v in fixed.values()):
        raise ValueError(f"expected {{name: finite number}}, got {value_text(fixed)}")
    return {"fixed": tuple(sorted((str(k), float(v)) for k, v in fixed.items()))}


def _read_weights(d, parts) -> dict:
    from ..infra.validation import RULES

    weights = d["weights"]
    if not isinstance(weights, dict):
        raise ValueError(f"expected {{term: weight}}, got {value_text(weights)}")
    for k, v in weights.items():
        RULES["weight"].check(v, f"weights.{k}")
    return {"weights": Weights(**weights)}


def _read_poses(d, parts) -> dict:
    from ..infra.validation import check_pose

    direction = None if d["box_direction"] is None else _floats(d["box_direction"], 2, "box_direction")
    return {"box_pose0": check_pose("box_pose0", d["box_pose0"]),
            "middle_pose0": _floats(d["middle_pose0"], 3, "middle_pose0"), "box_direction": direction}


def _read_cobra(d, parts) -> dict:
    cobra = d["cobra_parameters"]
    if not isinstance(cobra, dict):
        raise ValueError(f"expected {{parameter: value}}, got {value_text(cobra)}")
    return {"cobra": CobraParameters(**{str(k): tuple(v) if isinstance(v, list) else v for k, v in cobra.items()})}


def _read_step_settings(d, parts) -> dict:
    servo, contact = str(d.get("servo", "position")), str(d.get("contact", "compliant"))
    recorded = d.get("step_settings") or {}  # a file that predates it: the law's default substeps
    settings = StepSettings(dt=parts["dt"], contact=contact, servo=servo,
                            touchdown_substeps=recorded.get("touchdown_substeps"))
    if recorded.get("substeps", settings.substeps) != settings.substeps:  # the law's default moved: the run's n
        settings = dataclasses.replace(settings, touchdown_substeps=recorded["substeps"])
    return {"settings": settings}


def _read_problem(d, parts) -> dict:
    fields = {f.name for f in dataclasses.fields(ShootingProblem)} - {"gait"}
    problem = ShootingProblem(gait=str(d["gait"]), **{k: v for k, v in parts.items() if k in fields})
    if problem.gait not in DECISION:
        raise ValueError(f"unknown gait {problem.gait!r}; gaits: {', '.join(DECISION)}")
    return {"problem": problem}


def _read_gait(d, parts) -> dict:
    problem = parts["problem"]
    problem.reference(problem.x0)
    return {}


# (where, reader) in order: each reader returns its parts of the problem (``problem_from_dict``)
_SETTINGS_READERS = (("settings", _read_object), ("settings.decision", _read_decision),
                     ("settings.dt/duration", _read_time), ("settings.goal", _read_goal),
                     ("settings.fixed", _read_fixed), ("settings.weights", _read_weights),
                     ("settings.box_pose0/middle_pose0/box_direction", _read_poses),
                     ("settings.cobra_parameters", _read_cobra),
                     ("settings.servo/contact/step_settings", _read_step_settings),
                     ("settings", _read_problem), ("settings (the gait at x0)", _read_gait))


def _floats(values, n: int | None = None, field: str = "values") -> tuple:
    """The finite numbers in ``values`` as floats (``n`` of them, if given); a ValueError naming
    ``field`` for a string, a non-finite number or a wrong count."""
    from ..infra.validation import is_number

    if isinstance(values, (str, bytes, dict)) or not hasattr(values, "__iter__"):
        raise ValueError(f"{field}: expected {n or 'some'} numbers, got {value_text(values)}")
    values = list(values)
    if (n is not None and len(values) != n) or not all(is_number(v) and np.isfinite(v) for v in values):
        raise ValueError(f"{field}: expected {n or 'some'} finite numbers, got {value_text(values)}")
    return tuple(float(v) for v in values)


def transfer(problem: ShootingProblem, x, plan_entry: dict | None = None, check_dt: float = CHECK_DT) -> dict:
    """The optimum x in the plan (the rollout at the planner's dt) and in the high-fidelity check
    (the same parameters and start replayed at ``check_dt``): box distance to the goal [m] and
    impact impulse per second [N s/s] in each (``TRANSFER_KEYS``), and the check's error if its
    simulation failed (its numbers are then None).

    The transfer record of a params JSON ("transfer"). ``plan_entry``: the optimum's history entry
    (its numbers are used; None = roll the plan out again). The check starts from the same box
    pose and robot middle as the plan (``start_state`` with the check's dt).
    """
    def numbers(traj) -> tuple:
        d = float(np.linalg.norm(traj.box_pose[-1, :2] - problem.goal_world))
        return d, float(np.sum(traj.steps["impact_impulse"])) / problem.duration

    if plan_entry is None:
        plan = numbers(rollout(problem, x))
    else:
        plan = (plan_entry["box_distance_to_goal"], plan_entry["contact"]["impact_impulse"] / problem.duration)
    record = {"plan_dt": problem.dt, "check_dt": float(check_dt), "plan_distance_to_goal": plan[0],
              "check_distance_to_goal": None, "plan_impact_impulse_per_s": plan[1],
              "check_impact_impulse_per_s": None, "check_error": None}
    try:
        settings = dataclasses.replace(problem.settings, dt=float(check_dt))
        check = numbers(rollout(dataclasses.replace(problem, settings=settings), x))
        record.update(check_distance_to_goal=check[0], check_impact_impulse_per_s=check[1])
    except SimulationError as exc:
        record["check_error"] = str(exc)
    return record


def result_to_dict(result: ShootingResult) -> dict:
    """The params JSON: ``params`` (the optimum), ``history``, and every setting to re-run it;
    ``"checkpoint": true`` when it holds the rollouts so far of a search still running.
    """
    best = result.best
    path = best.get("box_path")
    return {"format": FORMAT, "gait": result.problem.gait, "params": result.params,
            "cost": best["cost"], "box_distance_to_goal": best["box_distance_to_goal"],
            "terms": best["terms"], "box_final": best.get("box_final"),
            "box_path": None if path is None else {"dt": BOX_PATH_DT, "xy": np.asarray(path, dtype=float).tolist()},
            "contact": best.get("contact"),
            "interrupted": result.interrupted, "message": result.message,
            **({"checkpoint": True} if result.checkpoint else {}),
            "settings": problem_to_dict(result.problem),
            "optimizer": {"method": result.method, "seed": result.seed, "maxiter": result.maxiter,
                          "iterations": result.iterations, "rollouts": len(result.history), **result.options},
            "code": code_version(planning=True), "wall_time": result.wall_time,
            "impacts": impact_comparison(result),
            **({"transfer": result.transfer} if result.transfer is not None else {}),
            "history": [{k: v for k, v in e.items() if k != "box_path"} for e in result.history]}


def impact_comparison(result) -> dict | None:
    """The optimum beside the rollout of least J - w_I I (the companion search's, ``search.optimize``):
    for each, the rollout's index, parameters, J - w_I I, box distance to the goal [m] and impact
    impulse per second [N s/s]; ``lower`` is true when the optimum's impact impulse is below the
    other's, ``same`` when both are one rollout: the "with and without the impact term" record of
    the params JSON. None without the companion search.
    """
    if result.without_impact is None:
        return None

    def row(e: dict) -> dict:
        impulse = None if e.get("contact") is None else e["contact"]["impact_impulse"] / result.problem.duration
        return {"rollout": e["rollout"], "params": e["params"], "cost_without_impact": cost_without_impact(result.problem, e),
                "box_distance_to_goal": e["box_distance_to_goal"], "impact_impulse_per_s": impulse}

    a, b = row(result.best), row(result.without_impact)
    return {"optimum": a, "without_impact_term": b, "same": a["rollout"] == b["rollout"],
            "lower": (a["impact_impulse_per_s"] is not None and b["impact_impulse_per_s"] is not None
                      and a["impact_impulse_per_s"] < b["impact_impulse_per_s"])}


def write_result(result: ShootingResult, path: str) -> dict:
    """Write the params JSON atomically (temporary file + rename); return what was written.
    """
    record = result_to_dict(result)

    def write(tmp: str) -> None:
        with open(tmp, "w") as f:
            json.dump(record, f, indent=1, allow_nan=False)
            f.write("\n")

    atomic_write(path, write, "params JSON")
    return record


def load_result(path: str) -> dict:
    """Read a params JSON with clear errors (missing, not JSON, not ours, malformed settings,
    parameters the gait refuses or outside the optimization's bounds).
    """
    from ..infra.validation import is_number

    if not os.path.isfile(path):
        raise ShootingError(f"params file not found: {path}")
    try:
        with open(path) as f:
            record = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ShootingError(f"{path}: not a readable JSON file ({exc})") from None
    except RecursionError:  # json's decoder recurses once per level of nesting
        raise ShootingError(f"{path}: not a params file of cobra-ref optimize: nested deeper than "
                            f"{sys.getrecursionlimit()} levels") from None
    if not isinstance(record, dict) or record.get("format") != FORMAT:
        raise ShootingError(f"{path}: not a params file of cobra-ref optimize (expected format {FORMAT!r})")
    for key in ("params", "settings", "cost"):
        if key not in record:
            raise ShootingError(f"{path}: malformed params file, missing {key!r}")
    try:
        problem = problem_from_dict(record["settings"])
    except ShootingError as exc:
        raise ShootingError(f"{path}: {exc}") from None
    params = record["params"]
    if not isinstance(params, dict) or not all(is_number(v) and np.isfinite(v) for v in params.values()):
        raise ShootingError(f"{path}: malformed 'params': expected {{name: finite number}}, "
                            f"got {value_text(params)}")
    if not (is_number(record["cost"]) and np.isfinite(record["cost"])):
        raise ShootingError(f"{path}: malformed 'cost': expected a finite number, got {value_text(record['cost'])}")
    try:
        record["params"] = {str(k): float(v) for k, v in params.items()}
        gait(problem.gait, **record["params"])
    except (AttributeError, TypeError, ValueError) as exc:
        raise ShootingError(f"{path}: malformed 'params': {exc}") from None
    for n, lo, hi in zip(problem.names, problem.lower, problem.upper):
        if n not in record["params"]:
            raise ShootingError(f"{path}: malformed 'params': missing the decision parameter {n!r}")
        v = record["params"][n]
        if not lo <= v <= hi:
            raise ShootingError(f"{path}: params {n} = {v:g} is outside the optimization's bounds [{lo:g}, {hi:g}] "
                                "(settings.decision): not an optimum of this problem")
    if "transfer" in record:
        t = record["transfer"]
        if not isinstance(t, dict) or any(k not in t for k in TRANSFER_KEYS) or not all(
                t[k] is None or (is_number(t[k]) and np.isfinite(t[k])) for k in TRANSFER_KEYS):
            raise ShootingError(f"{path}: malformed 'transfer': expected {{{', '.join(TRANSFER_KEYS)}}} "
                                f"as finite numbers (or null where the check failed), got {value_text(t)}")
    if record.get("box_path") is not None:
        try:
            xy = np.asarray(record["box_path"]["xy"], dtype=float)
        except (TypeError, KeyError, IndexError, ValueError):
            xy = np.zeros((0, 0))
        if xy.ndim != 2 or xy.shape[1:] != (2,) or len(xy) < 2 or not np.all(np.isfinite(xy)):
            raise ShootingError(f"{path}: malformed 'box_path': expected {{'dt': seconds, 'xy': [[x, y], ...]}} "
                                "with at least two finite points")
        record["box_path"] = {"dt": record["box_path"].get("dt"), "xy": xy}
    record["problem"] = problem
    return record


def decision_vector(problem: ShootingProblem, params: dict) -> tuple:
    """x for the full gait parameters ``params`` (the decision parameters picked out).
    """
    return tuple(float(params[n]) for n in problem.names)


def replay(path: str, progress=None) -> tuple[Trajectory, dict]:
    """Re-run the optimum of a params JSON; return the trajectory and its cost entry.

    The exact replay (the simulator is deterministic: the cost equals the recorded one).
    """
    record = load_result(path)
    problem = record["problem"]
    x = decision_vector(problem, record["params"])
    traj = rollout(problem, x, progress)
    return traj, shooting_cost(problem, traj)


def summary_lines(result: ShootingResult) -> list[str]:
    """The final summary of an optimization, a few lines of text.
    """
    p, b, x0 = result.problem, result.best, result.history[0]
    c = b.get("contact") or {}
    lines = [f"{'INTERRUPTED: ' if result.interrupted else ''}{result.message}",
             f"{p.gait}: {len(result.history)} rollouts in {result.wall_time:.0f} s, {result.iterations} iterations",
             "optimum: " + ", ".join(f"{n} = {b['params'][n]:.4f}" for n in p.names),
             f"cost {x0['cost']:.5g} (initial guess) -> {b['cost']:.5g}; terms "
             + ", ".join(f"{k} {v:.4g}" for k, v in (b["terms"] or {}).items())]
    if b["box_distance_to_goal"] is not None and x0["box_distance_to_goal"] is not None:
        lines.append(f"box to goal {float(np.hypot(*p.goal)):.4f} m at start, {x0['box_distance_to_goal']:.4f} m "
                     f"with the initial guess, {b['box_distance_to_goal']:.4f} m at the optimum")
    if c:
        lines.append(f"contact conditions over the rollout: max complementarity {c['max_complementarity']:.2e} "
                     f"N s m/s, max cone residual {c['max_cone_residual']:.2e}, {c['steps_not_converged']} steps "
                     f"with the friction fixed point not converged; torque over tau_max in {c['steps_over_tau_max']} steps "
                     f"(max excess {c['max_tau_excess']:.2f} N m), max |q| - q_max {c['max_q_excess']:.3f} rad")
    impacts = impact_comparison(result)
    if impacts and impacts["optimum"]["impact_impulse_per_s"] is not None and \
            impacts["without_impact_term"]["impact_impulse_per_s"] is not None:
        o, u = impacts["optimum"], impacts["without_impact_term"]
        lines.append(f"impact impulse {o['impact_impulse_per_s']:.4g} N s/s at the optimum; without the impact term the best "
                     f"rollout is " + ("the same one" if impacts["same"] else
                                       f"rollout {u['rollout']}, {u['impact_impulse_per_s']:.4g} N s/s"))
    return lines


class ParamsRun(NamedTuple):
    """What ``cobra-ref simulate --params FILE`` needs to replay an optimum exactly."""

    gait: str
    reference: object  # the optimal gait: gait(gait, **params)
    settings: object  # StepSettings of the optimization
    duration: float  # the optimization's horizon, or the override
    q0: np.ndarray  # the common initial state of the optimization
    qd0: np.ndarray
    model: object  # cobra_model with the recorded CobraParameters
    problem: ShootingProblem
    recorded_cost: float
    same_code: bool = True  # the physics modules' SHA-256 equals the one the optimum was found with


def params_reference(path: str, duration: float | None = None, step: dict | None = None) -> ParamsRun:
    """Read a params JSON and return everything to replay its optimum with ``simulate``.

    For ``cobra-ref simulate --params``. ``duration`` None = the optimization's horizon (then
    ``params_summary`` checks that the replayed cost equals the recorded one); ``step``: the
    ``StepSettings`` fields (dt, contact, servo) that replace the optimization's, with the start
    settled under them, as the transfer check does. The horizon is a whole number of steps of the
    replay's dt when either differs from the file's (``validation.step_count``). Raises
    ``ShootingError`` for a missing or malformed file, a bad ``duration`` or step setting, or a
    recorded start the model refuses.
    """
    from ..infra.validation import ValidationError, step_count
    from ..model import ModelError

    record = load_result(path)
    problem: ShootingProblem = record["problem"]
    try:
        replayed = dataclasses.replace(problem, settings=dataclasses.replace(problem.settings, **(step or {})))
        horizon = problem.duration if duration is None else float(duration)
        # a new grid (another horizon or dt) is a whole number of steps; the file's own was checked on reading
        step_count(horizon, replayed.dt, exact=duration is not None or replayed.dt != problem.dt,
                   duration_field="--duration", dt_field="--dt" if "dt" in (step or {}) else "dt")
        x = decision_vector(problem, record["params"])
        model = cobra_model(problem.cobra)
        q0, qd0 = start_state(replayed, x, model)
    except (ValidationError, ModelError) as exc:
        raise ShootingError(f"{path}: {exc}") from None
    return ParamsRun(problem.gait, problem.reference(x), replayed.settings, horizon, q0, qd0, model, problem,
                     float(record["cost"]), record.get("code", {}).get("physics_sha256") == code_version(planning=True)["physics_sha256"])
