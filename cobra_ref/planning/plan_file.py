"""The plan JSON of a push: what ``push`` chose and did, written (``push_record``) and read back
(``load_push``) so that ``receding.replay`` executes it again, bit for bit.

The record holds the options (the task, the planner's settings and weights, the model), the plan
(its start shape and one primitive per period), one record per period (the candidates and their
costs, the chosen one, the box's distance) and the outcome (final distance, simulated time, impact
impulse per second, rollouts, wall time).
"""

from __future__ import annotations

from dataclasses import asdict

import numpy as np

from ..params import CobraParameters
from ..provenance import code_version
from ..step import StepSettings
from .primitives import Primitive
from .receding import PushOptions, PushResult

FORMAT = "cobra-ref push v1"


def push_record(result: PushResult, options: PushOptions) -> dict:
    """The plan JSON: the options, the plan, one record per period and the outcome (``load_push`` reads it)."""
    traj, o = result.trajectory, options
    final = float(np.linalg.norm(traj.box_pose[-1, :2] - np.asarray(result.goal_world)))
    return {"format": FORMAT, "code": code_version(planning=True),
            "options": {"goal": list(o.goal), "via": [list(v) for v in o.via], "period": o.period,
                        "horizon": o.horizon, "budget": o.budget, "tolerance": o.tolerance,
                        "via_tolerance": o.via_tolerance, "samples": o.samples, "seed": o.seed,
                        "start": o.start.to_dict(), "settings": asdict(o.settings), "plant_dt": o.plant_dt, "plant": o.plant,
                        "cobra": asdict(o.cobra),
                        "weights": {"effort": o.w_effort, "impact": o.w_impact, "tau": o.w_tau,
                                    "approach": o.w_approach, "face": o.w_face, "lateral": o.w_lateral}},
            "plan": result.plan.to_dict(), "cycles": result.cycles, "goal_world": list(result.goal_world),
            "reached": result.reached, "reason": result.reason, "outlook": result.outlook, "final_distance": final,
            "simulated_time": traj.duration,
            "impact_impulse_per_second": float(np.sum(traj.steps["impact_impulse"])) / max(traj.duration, 1e-12),
            "rollouts": int(sum(c["rollouts"] for c in result.cycles)), "wall_time": round(result.wall_time, 1)}


def load_push(record: dict) -> tuple[dict, PushOptions]:
    """(plan, options) of a plan JSON's record (``push_record``), for ``replay``; ValueError if malformed."""
    if not isinstance(record, dict) or record.get("format") != FORMAT:
        raise ValueError(f"not a push plan (expected format {FORMAT!r})")
    o = record["options"]
    cobra = CobraParameters(**{k: tuple(v) if isinstance(v, list) else v for k, v in o["cobra"].items()})
    options = PushOptions(goal=tuple(o["goal"]), via=tuple(tuple(v) for v in o["via"]), period=o["period"],
                          horizon=o["horizon"], budget=o["budget"], tolerance=o["tolerance"],
                          via_tolerance=o["via_tolerance"], samples=o["samples"], seed=o["seed"],
                          start=Primitive(**o["start"]), settings=StepSettings(**o["settings"]), cobra=cobra,
                          w_effort=o["weights"]["effort"], w_impact=o["weights"]["impact"], w_tau=o["weights"]["tau"],
                          w_approach=o["weights"]["approach"], w_face=o["weights"].get("face", 0.0),
                          w_lateral=o["weights"].get("lateral", 1.0),
                          plant_dt=o.get("plant_dt"),
                          plant=o.get("plant", "cobra_ref"))
    return record["plan"], options
