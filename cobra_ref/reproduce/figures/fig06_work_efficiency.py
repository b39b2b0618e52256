"""Fig. 6: locomotion work against the work done on the box (the slope measures inefficiency).

The paper's fig. 6 "depicts the efficiency of each gait based on the total work done by the
robot for locomotion against total work done on the box. Larger slope indicates a less efficient
gait". Plotted, for every gait in one axes, the curve t -> (W_box(t), W_loc(t)) with

* W_loc(t) = integral sum_j |tau_j qdot_j| dt [J]          ``analysis.locomotion_work``
* W_box(t) = integral sum_c f_c . v_box(p_c) dt [J]         ``analysis.box_work``

and, dotted, the least-squares line W_loc = s W_box + b over the push (from the first
robot-box contact on; ``analysis.efficiency_fit``), whose slope s [J/J] is in the legend. Each
gait has its own colour and line style (``common.gait_line``): J-mirror, J's mirror image, does
the same work, so its dashed curve lies on J's solid one (the title says so). Note: W_box is on the horizontal
axis and W_loc on the vertical one so that the slope seen in the plot is the paper's "larger is
less efficient" slope (dW_loc / dW_box). A gait that never does work on the box has no finite
slope: its curve runs up the vertical axis and the legend says so.

With an ``ensemble`` ({gait: [``analysis.summary`` per member]}, each over the members' shorter
window), a second panel of its own shows the members' slopes (``efficiency_slope`` of each
summary: one dot per member and their 10-90 % range, ``common.draw_spread``); the 10 s runs of
the first panel and the members' window never share an axis. A member without a finite slope
(no work on the box) is counted under its gait. The slopes' axis is logarithmic when they are
all positive and span more than a decade.
"""

from __future__ import annotations

import numpy as np

from ..analysis import box_work, efficiency_fit, locomotion_work
from . import common

def slope_label(gait: str, traj, slope: float) -> str:
    """Legend entry: the gait and its slope dW_loc/dW_box [J/J] (or "no work on box").
    """
    name = common.gait_label(gait, traj)
    return f"{name}: slope {slope:.3g} J/J" if np.isfinite(slope) else f"{name}: no work on box"


def plot_work(ax, rows) -> None:
    """The curves W_loc against W_box [J] of the nominal runs, their end points and fitted lines
    (the slope in each curve's label).
    """
    for gait, traj in rows:
        line = common.gait_line(gait)
        w_loc, w_box = locomotion_work(traj), box_work(traj)
        slope, b = efficiency_fit(traj)
        ax.plot(w_box, w_loc, **line, label=slope_label(gait, traj, slope))
        ax.plot(w_box[-1:], w_loc[-1:], "o", color=line["color"], ms=3)
        if np.isfinite(slope):
            x = np.array([0.0, w_box.max(initial=0.0)])
            ax.plot(x, slope * x + b, color=line["color"], ls=":", lw=0.7)
    ax.set_xlabel(r"work done on the box $W_{box}$ [J]")
    ax.set_ylabel(r"locomotion work $W_{loc}$ [J]")


def plot_slopes(ax, rows, ensemble: dict) -> None:
    """Per gait, the slopes [J/J] of its ensemble members (over their window) and their range.
    """
    labels, drawn, n_members = [], [], 0
    for i, (gait, traj) in enumerate(rows):
        color, values = common.gait_color(gait), common.ensemble_values(ensemble, gait, "efficiency_slope")
        missing = common.draw_spread(ax, i, values, color, gait, width=0.4)
        drawn += [v for v in values if np.isfinite(v)]
        n_members = max(n_members, len(values))
        labels.append(common.gait_label(gait, traj) + (f"\n{missing} no push" if missing else ""))
    if drawn and min(drawn) > 0 and max(drawn) > 10 * min(drawn):
        ax.set_yscale("log")
    ax.set_xticks(range(len(rows)), labels, rotation=30, ha="right")
    ax.set_xlim(-0.6, len(rows) - 0.4)
    ax.set_ylabel("slope [J/J]")
    ax.grid(False, axis="x")
    window = common.ensemble_window(ensemble)
    ax.set_title(f"slope of each ensemble member" + (f", first {window:g} s" if window else ""), loc="left")
    ax.legend(handles=common.spread_handles(n_members, window), loc="upper left", fontsize=5.5)


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig06_work_efficiency.png/.pdf``: W_loc against W_box for every gait, with the fitted
    slope of each in the legend; with ``ensemble``, a panel of its own with the members' slopes.

    Implements: [COBRA] fig. 6 with ``analysis.locomotion_work``, ``box_work`` and
    ``efficiency_slope``.
    """
    rows = common.ordered(results)
    spread = bool(rows) and any(len(common.ensemble_values(ensemble, g, "efficiency_slope")) for g, _ in rows)
    fig = common.new_figure(common.ONE_COLUMN, 5.2 if spread else 3.3)
    axes = fig.subplots(2, 1, height_ratios=[2.0, 1.0]) if spread else [fig.add_subplot()]
    if not rows:
        common.empty_panel(axes[0], "no gait to show")
    plot_work(axes[0], rows)
    T = max((traj.duration for _, traj in rows), default=0.0)
    note = common.mirror_note(g for g, _ in rows)
    axes[0].set_title(f"Locomotion work vs work on the box, {T:g} s runs\n(dotted: fit over the push; steeper = less "
                      f"efficient)" + (f"\n{note}" if note else ""))
    if rows:
        axes[0].legend(loc="upper right", fontsize=5.5)  # the curves' labels: gait and slope
    if spread:
        plot_slopes(axes[1], rows, ensemble)
    return common.save(fig, out_dir, "fig06_work_efficiency")


if __name__ == "__main__":
    common.main(make)
