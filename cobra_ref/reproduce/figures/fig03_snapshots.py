"""Fig. 3: snapshots of the box push for each gait, seen from above on common axes.

The paper's fig. 3 shows "snapshots depicting simulated forward box push utilizing various
gaits" (C, S, J and sidewinding; the J gait mirrored moves the box the other way). Here each
gait is one top view (J-mirror included when it was run), every panel with the same x and y
limits and equal scale, x to the right and y up (the world axes, never reflected): the robot and
the box at ``N_INSTANTS`` instants evenly spaced over the run, the earlier ones fainter, each
labelled with its time at the head; the box's path (black), its start (+) and, for a gait
optimized towards a goal, the goal (star; ``settings.goal`` of its optimum, relative to the
box's start). Every body is its cylinder (``viz.drawing.scene_polygons``) seen from above, the
faces painted from the lowest up. Nothing from ``analysis`` is plotted: this is geometry only.
"""

from __future__ import annotations

import numpy as np
from matplotlib.collections import PolyCollection
from matplotlib.lines import Line2D

from ...viz.drawing import scene_limits, scene_polygons
from . import common

N_INSTANTS = 4
COLUMNS = 3  # panels per row
EARLIEST_ALPHA = 0.3  # the first snapshot's opacity; the last one is opaque


def snapshot_steps(traj, n: int = N_INSTANTS) -> np.ndarray:
    """``n`` evenly spaced state indices from the first to the last state: the snapshot instants."""
    return np.unique(np.linspace(0, len(traj.q) - 1, n).round().astype(int))


def goal_point(traj, goal) -> np.ndarray | None:
    """(2,) the goal in world x, y: the box's start plus ``goal`` (relative to it); None without one."""
    return None if goal is None else traj.box_pose[0, :2] + np.asarray(goal, dtype=float)[:2]


def common_limits(model, rows, goals: dict) -> np.ndarray:
    """(2, 2) x and y limits [m] that hold every gait's robot and box at its snapshots, its box
    path and its goal: one scale for every panel."""
    lims, points = [], []
    for gait, traj in rows:
        lims.append(scene_limits(model, traj, snapshot_steps(traj))[:2])
        goal = goal_point(traj, goals.get(gait))
        if goal is not None:
            points.append(goal)
    lo = np.min([lim[:, 0] for lim in lims] + [p - 0.1 for p in points], axis=0)
    hi = np.max([lim[:, 1] for lim in lims] + [p + 0.1 for p in points], axis=0)
    return np.stack([lo, hi], axis=1)


def draw_top_view(ax, model, traj, k: int, alpha: float) -> None:
    """The robot and the box at state k seen from above: every face projected to the ground and
    painted in the order of its height (lowest first), so upper faces cover lower ones."""
    polys, colors = scene_polygons(model, traj.q[k], traj.box_pose[k], light=np.array([0.0, 0.0, 1.0]))
    order = np.argsort([np.mean(p[:, 2]) for p in polys])
    faces = [np.asarray(polys[i])[:, :2] for i in order]
    ax.add_collection(PolyCollection(faces, facecolors=colors[order], edgecolors="none", alpha=alpha, zorder=2))


def draw_gait(ax, model, gait: str, traj, goal) -> None:
    """One gait's panel: its snapshots (fainter = earlier, the time at the head), the box's path,
    its start and the goal."""
    steps = snapshot_steps(traj)
    for alpha, k in zip(np.linspace(EARLIEST_ALPHA, 1.0, len(steps)), steps):
        draw_top_view(ax, model, traj, int(k), float(alpha))
        ax.annotate(f"{traj.t[k]:.3g} s", traj.q[k, :2], xytext=(2, 2), textcoords="offset points", fontsize=5,
                    color="0.2", zorder=4)
    path = traj.box_pose[:, :2]
    ax.plot(path[:, 0], path[:, 1], color="k", lw=0.8, zorder=3)
    ax.plot(*path[0], "k+", ms=6, zorder=3)
    point = goal_point(traj, goal)
    if point is not None:
        ax.plot(*point, "*", ms=9, mfc=common.gait_color(gait), mec="k", mew=0.5, zorder=4, gid=f"goal:{gait}")
    ax.set_title(common.gait_label(gait, traj), color=common.gait_color(gait), loc="left")


def legend_panel(ax, times: list) -> None:
    """The last, empty grid slot: what the marks mean."""
    ax.set_axis_off()
    handles = [Line2D([], [], color="k", lw=0.8, label="box path"),
               Line2D([], [], color="k", marker="+", ls="none", ms=6, label="box start"),
               Line2D([], [], marker="*", ls="none", ms=9, mfc="0.6", mec="k", mew=0.5,
                      label="goal of the gait's optimization"),
               Line2D([], [], color="0.5", lw=4, alpha=EARLIEST_ALPHA, label="earlier snapshots fainter")]
    ax.legend(handles=handles, loc="center", title="snapshots at t = " + ", ".join(f"{t:.3g}" for t in times) + " s")


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig03_snapshots.png/.pdf``: one top view per gait, all on the same axes, with the
    snapshots, the box's path and, from ``goals`` ({gait: (dx, dy)} relative to the box's start),
    each gait's goal.

    Implements: [COBRA] fig. 3 (snapshots of the forward box push for each gait). ``ensemble``
    is accepted for a common signature and not drawn: the nominal runs only.
    """
    rows, goals = common.ordered(results), goals or {}
    n_rows = max(1, -(-(len(rows) + 1) // COLUMNS))
    fig = common.new_figure(common.TWO_COLUMN, 2.9 * n_rows + 0.4)
    axes = fig.subplots(n_rows, COLUMNS, sharex=True, sharey=True, squeeze=False).ravel()
    if not rows:
        common.empty_panel(axes[0], "no gait to show")
        return common.save(fig, out_dir, "fig03_snapshots")
    lim = common_limits(model, rows, goals)
    for ax, (gait, traj) in zip(axes, rows):
        draw_gait(ax, model, gait, traj, goals.get(gait))
        ax.set(xlim=lim[0], ylim=lim[1], aspect="equal")
    for ax in axes[len(rows):]:
        ax.set_axis_off()
    legend_panel(axes[len(rows)], list(rows[0][1].t[snapshot_steps(rows[0][1])]))  # n_rows leaves it free
    for ax in axes:
        ax.tick_params(labelbottom=True, labelleft=True)
    fig.supxlabel("x [m]", fontsize=7)
    fig.supylabel("y [m]", fontsize=7)
    fig.suptitle("Box push snapshots, top view, every gait on the same axes")
    return common.save(fig, out_dir, "fig03_snapshots")


if __name__ == "__main__":
    common.main(make)
