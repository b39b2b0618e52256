"""Fig. 9: how far each gait moved the box in the same time.

The paper's fig. 9 "depicts the total distance the robot moves the box for each gait in the
same amount of time". Plotted, from ``analysis.box_distance``, d_box(t) = |x_box(t) - x_box(0)|
(horizontal) [m] for every gait in one axes, and a bar of the final distance per gait. A third
panel shows the box's horizontal path relative to its start, x_box(t) - x_box(0) [m], which
shows the direction as well: the mirrored J gait should move the box the other way.
"""

from __future__ import annotations

from matplotlib.ticker import MaxNLocator

from ...analysis import box_distance
from . import common


def plot_paths(ax, rows) -> None:
    """The box's horizontal displacement x_box(t) - x_box(0) [m] per gait (top view, equal scale).

    Helper: the direction in which each gait pushed the box.
    """
    for gait, traj in rows:
        d = traj.box_pose[:, :2] - traj.box_pose[0, :2]
        ax.plot(d[:, 0], d[:, 1], color=common.gait_color(gait))
        ax.plot(d[-1:, 0], d[-1:, 1], "o", ms=3, color=common.gait_color(gait))
    ax.plot([0.0], [0.0], "k+", ms=6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.set_xlabel(r"$\Delta x_{box}$ [m]")
    ax.set_ylabel(r"$\Delta y_{box}$ [m]")
    ax.set_title("box path, top view (+ = start)")


@common.paper_style
def make(results: dict, out_dir: str, model) -> list[str]:
    """Write ``fig09_box_distance.png/.pdf``: box distance [m] vs time, final distance per gait, and
    the box's path.

    Implements: [COBRA] fig. 9 with ``analysis.box_distance``.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.TWO_COLUMN, 2.3)
    ax_t, ax_bar, ax_xy = fig.subplots(1, 3, width_ratios=[1.4, 1.0, 1.0])
    if not rows:
        for ax in (ax_t, ax_bar, ax_xy):
            common.empty_panel(ax, "no gait to show")
    labels, finals, colors = [], [], []
    for gait, traj in rows:
        d = box_distance(traj)
        ax_t.plot(traj.t[: len(d)], d, color=common.gait_color(gait), label=common.gait_label(gait, traj))
        labels.append(common.gait_label(gait, traj))
        finals.append(float(d[-1]) if len(d) else 0.0)
        colors.append(common.gait_color(gait))
    ax_t.set_xlabel("time [s]")
    ax_t.set_ylabel(r"box distance $d_{box}$ [m]")
    ax_t.set_title("distance the box moved")
    if rows:
        ax_t.legend(loc="upper left")
        bars = ax_bar.bar(range(len(rows)), finals, color=colors)
        ax_bar.bar_label(bars, [f"{1e3 * d:.3g} mm" for d in finals], fontsize=5.5, rotation=90, padding=2)
        ax_bar.margins(y=0.25)
        ax_bar.set_xticks(range(len(rows)), labels, rotation=30, ha="right")
        plot_paths(ax_xy, rows)
    ax_bar.set_ylabel(r"final $d_{box}$ [m]")
    ax_bar.set_title(f"after {max((t.duration for _, t in rows), default=0):.3g} s")
    return common.save(fig, out_dir, "fig09_box_distance")


if __name__ == "__main__":
    common.main(make)
