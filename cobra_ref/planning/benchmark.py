"""The push benchmark: sixteen goals around the box and two waypoint paths, each pushed by the planner.

The goals (``GOALS``) are fixed before any run and chosen independently of where the gaits push:
eight directions, every 45 deg from the robot's initial heading (0 deg = +x, 90 deg = its left),
at 0.25 m and at 0.5 m from the box's start; and two paths through a waypoint. Each task is one
``receding.push`` from the same start with the same options; a row per task records the final
error [m], the simulated time [s], the impact impulse per second [N s/s], the rollouts and the
wall time [s], and for a path the closest pass of each waypoint [m]. The criteria the rows are
judged by (``summary``): the box's centre within ``REACHED`` of the goal, the median final error,
each waypoint passed within ``PASSED``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .plan_file import push_record
from .receding import PushOptions, push

REACHED = 0.02  # [m] a goal counts as reached within this
PASSED = 0.03  # [m] a waypoint counts as passed within this


def _direction(degrees: float, distance: float) -> tuple:
    """(dx, dy) [m] at ``distance`` in the direction ``degrees`` from +x."""
    a = math.radians(degrees)
    return (distance * math.cos(a), distance * math.sin(a))


# (name, goal, waypoints): eight directions at two distances, then two paths
GOALS = tuple((f"{d:03d}deg-{r:.2f}m", _direction(d, r), ()) for r in (0.25, 0.5) for d in range(0, 360, 45)) + (
    ("path-left", (0.3, 0.2), ((0.2, 0.0),)),
    ("path-right", (0.3, -0.25), ((0.15, -0.1),)),
)


def run_benchmark(base: PushOptions, executor=None, tasks=GOALS, progress=None, keep=None, plant=None,
                  keep_plan=None) -> list:
    """One row per task (module docstring), in order; ``keep(rows)`` is called after each task (to
    write what is done), ``keep_plan(name, record)`` with its plan JSON's record (``push_record``:
    it replays to the task's run, and holds every re-plan's candidates and costs),
    ``progress(line)`` gets the planner's lines and one per task; ``plant``: as ``receding.push``'s."""
    rows = []
    for name, goal, via in tasks:
        result = push(replace(base, goal=tuple(goal), via=tuple(via)), executor, progress, plant)
        record = push_record(result, replace(base, goal=tuple(goal), via=tuple(via)))
        if keep_plan is not None:
            keep_plan(name, record)
        box = result.trajectory.box_pose[:, :2]
        start = box[0]
        passes = [float(np.min(np.linalg.norm(box - (start + np.asarray(w)), axis=1))) for w in via]
        every = max(1, int(round(0.05 / base.plant_settings.dt)))  # the box path every 50 ms of the plant
        rows.append({"task": name, "goal": list(goal), "via": [list(w) for w in via],
                     "final_error": record["final_distance"], "reached": record["final_distance"] <= REACHED,
                     "waypoint_passes": passes, "simulated_time": record["simulated_time"],
                     "impact_impulse_per_second": record["impact_impulse_per_second"],
                     "rollouts": record["rollouts"], "wall_time": record["wall_time"], "reason": record["reason"],
                     "box_path": (box[::every] - start).round(5).tolist()})
        if progress is not None:
            progress(f"{name}: {100 * record['final_distance']:.2f} cm from the goal after "
                     f"{record['simulated_time']:g} s ({record['reason']}), {record['rollouts']} rollouts, "
                     f"{record['wall_time']:.0f} s")
        if keep is not None:
            keep(rows)
    return rows


def select(names) -> tuple:
    """The tasks of ``GOALS`` named in ``names``, in the benchmark's order (all for none); ValueError
    naming an unknown one and the names there are."""
    known = [name for name, _, _ in GOALS]
    unknown = [n for n in names or () if n not in known]
    if unknown:
        raise ValueError(f"no benchmark task {unknown[0]!r} (the tasks: {', '.join(known)})")
    return tuple(t for t in GOALS if not names or t[0] in names)


def summary(rows: list) -> dict:
    """How the rows meet the criteria: goals reached within ``REACHED``, the median final error,
    waypoints passed within ``PASSED``, the median wall time per task."""
    errors = [r["final_error"] for r in rows]
    passes = [p for r in rows for p in r["waypoint_passes"]]
    return {"tasks": len(rows), "reached": int(sum(r["reached"] for r in rows)),
            "median_final_error": float(np.median(errors)) if errors else None,
            "waypoints_passed": int(sum(p <= PASSED for p in passes)), "waypoints": len(passes),
            "median_wall_time": float(np.median([r["wall_time"] for r in rows])) if rows else None}
