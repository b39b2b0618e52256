"""The single-shooting optimizations as pictures: cost histories and the box's path to each goal.

The figures of the single-shooting optimizations (assumption A17). ``make`` draws, for a set of
optimized runs (one params JSON of ``cobra-ref optimize`` each, with the box path its optimum
recorded):

* left: the cost of every rollout in evaluation order (dots) and the best so far (line), per run;
  each gait in its colour, line style and marker (``common.gait_line``, ``gait_marker``: J-mirror's
  costs are J's when it is J's mirror image, so its dashed line and crosses lie on J's, as the
  title then says);
* right: top view of the box's path over the horizon under the optimum (line), relative to its
  start (cross), to where it ended (dot), with the goal (star) and the initial guess's final box
  position (ring) for comparison; rollouts whose simulation failed are counted on the left.

It is used twice: ``fig_optimization`` (one optimum per gait) and ``fig_directions`` (the box
pushed ahead, to the left and to the right by choosing the gait, the mirrored J included).
"""

from __future__ import annotations

import numpy as np

from . import common


def mirrored_pair(runs: list[dict]) -> bool:
    """Whether ``runs`` hold J and J-mirror with the same cost history (the mirror of one
    optimization: their lines coincide)."""
    costs = {run["gait"]: [h["cost"] for h in run["record"]["history"]] for run in runs}
    return "J" in costs and costs["J"] == costs.get("J-mirror")


def make(runs: list[dict], out_dir: str, stem: str, title: str) -> list[str]:
    """Write ``stem.png`` / ``.pdf``; ``runs``: dicts with ``label``, ``gait``, ``record`` (the
    params JSON as read by ``shooting.load_result``) and ``box_xy`` ((n, 2) box path of the optimum's rollout).
    """
    fig = common.new_figure(common.TWO_COLUMN, 3.0)
    ax_cost, ax_path = fig.subplots(1, 2)
    if not runs:
        common.empty_panel(ax_cost, "no optimization results")
        common.empty_panel(ax_path, "no optimization results")
    for i, run in enumerate(runs):
        line = common.gait_line(run["gait"])
        color = line["color"]
        history = run["record"]["history"]
        cost = np.array([h["cost"] for h in history], dtype=float)
        ax_cost.plot(np.arange(1, len(cost) + 1), cost, common.gait_marker(run["gait"]), color=color, ms=3,
                     mew=0.6, ls="none")
        ax_cost.plot(np.arange(1, len(cost) + 1), np.minimum.accumulate(cost), **line, label=run["label"])
        # everything relative to the box's start, so that the directions compare at a glance
        xy = np.asarray(run["box_xy"])
        start = xy[0].copy()
        xy = xy - start
        goal = np.asarray(run["record"]["settings"]["goal_world"]) - start
        ax_path.plot(xy[:, 0], xy[:, 1], **line, label=run["label"])
        ax_path.plot(xy[-1, 0], xy[-1, 1], "o", color=color, ms=4)
        ax_path.plot(goal[0], goal[1], "*", color=color, ms=9, mec="k", mew=0.5)
        first = history[0].get("box_final")
        if first is not None:
            ax_path.plot(first[0] - start[0], first[1] - start[1], "o", mfc="none", color=color, ms=6)
        n_failed = sum(1 for h in history if h.get("error"))
        if n_failed:
            ax_cost.annotate(f"{run['label']}: {n_failed} rollout(s) failed (cost {max(cost):g})",
                             (0.02, 0.97 - 0.07 * i), xycoords="axes fraction", fontsize=5.5,
                             va="top", color=color)
    ax_cost.set_yscale("log")
    ax_cost.set_xlabel("rollout")
    ax_cost.set_ylabel("cost J (dimensionless)")
    ax_cost.set_title("cost of each rollout; line: best so far")
    ax_path.plot(0.0, 0.0, "k+", ms=9)
    ax_path.set_xlabel("box dx from its start [m]")
    ax_path.set_ylabel("box dy [m]")
    ax_path.set_aspect("equal", adjustable="datalim")
    ax_path.set_title("box path of the optimum\n* goal, o end, ring: initial guess")
    if runs:
        ax_cost.legend(fontsize=6)
    note = common.MIRROR_NOTE if mirrored_pair(runs) else ""
    fig.suptitle(title + (f"\n{note}" if note else ""))
    return common.save(fig, out_dir, stem)
