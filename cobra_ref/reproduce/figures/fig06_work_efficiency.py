"""Fig. 6: locomotion work against the work done on the box (the slope measures inefficiency).

The paper's fig. 6 "depicts the efficiency of each gait based on the total work done by the
robot for locomotion against total work done on the box. Larger slope indicates a less efficient
gait". Plotted, for every gait in one axes, the curve t -> (W_box(t), W_loc(t)) with

* W_loc(t) = integral sum_j |tau_j qdot_j| dt [J]          ``analysis.locomotion_work``
* W_box(t) = integral sum_c f_c . v_box(p_c) dt [J]         ``analysis.box_work``

and, dashed, the least-squares line W_loc = s W_box + b over the push (from the first
robot-box contact on; ``analysis.efficiency_fit``), whose slope s [J/J] is in the legend. Note: W_box is on the horizontal
axis and W_loc on the vertical one so that the slope seen in the plot is the paper's "larger is
less efficient" slope (dW_loc / dW_box). A gait that never does work on the box has no finite
slope: its curve runs up the vertical axis and the legend says so.

With an ``ensemble`` ({gait: [``analysis.summary`` per member]}), every member's end point
(W_box(T), W_loc(T)) is a small dot beside the nominal curve's end, and a second panel compares
the slopes: the nominal run's (diamond) beside its members' (``efficiency_slope`` of each
summary: one dot per member and their 10-90 % range, ``common.draw_spread``); a member without a
finite slope (no work on the box) is counted under its gait. The slopes' axis is logarithmic
when they are all positive and span more than a decade.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from ..analysis import box_work, efficiency_fit, locomotion_work
from . import common

ENDPOINTS_GID = "ensemble-endpoints"  # the members' (W_box(T), W_loc(T)) dots: "<gid>:<gait>"


def slope_label(gait: str, traj, slope: float) -> str:
    """Legend entry: the gait and its slope dW_loc/dW_box [J/J] (or "no work on box").
    """
    name = common.gait_label(gait, traj)
    return f"{name}: slope {slope:.3g} J/J" if np.isfinite(slope) else f"{name}: no work on box"


def plot_work(ax, rows, ensemble: dict | None) -> dict:
    """The curves W_loc against W_box [J], their end points and fitted lines, and with an
    ensemble its members' end points; returns {gait: nominal slope}.
    """
    slopes = {}
    for gait, traj in rows:
        color = common.gait_color(gait)
        w_loc, w_box = locomotion_work(traj), box_work(traj)
        slopes[gait], b = efficiency_fit(traj)
        ax.plot(w_box, w_loc, color=color, label=slope_label(gait, traj, slopes[gait]))
        ax.plot(w_box[-1:], w_loc[-1:], "o", color=color, ms=3)
        if np.isfinite(slopes[gait]):
            x = np.array([0.0, w_box.max(initial=0.0)])
            ax.plot(x, slopes[gait] * x + b, color=color, ls="--", lw=0.7)
        members = [common.ensemble_values(ensemble, gait, k) for k in ("box_work", "locomotion_work")]
        if len(members[0]):
            ax.plot(*members, "o", ls="none", ms=1.8, mfc="none", mec=color, mew=0.5, gid=f"{ENDPOINTS_GID}:{gait}")
    ax.set_xlabel(r"work done on the box $W_{box}$ [J]")
    ax.set_ylabel(r"locomotion work $W_{loc}$ [J]")
    return slopes


def plot_slopes(ax, rows, slopes: dict, ensemble: dict) -> None:
    """Per gait, the nominal slope [J/J] (diamond) and its ensemble members beside it.
    """
    labels, drawn, n_members = [], [], 0
    for i, (gait, traj) in enumerate(rows):
        color, values = common.gait_color(gait), common.ensemble_values(ensemble, gait, "efficiency_slope")
        if np.isfinite(slopes[gait]):
            ax.plot(i - 0.22, slopes[gait], "D", color=color, ms=3.5, gid=f"nominal:{gait}")
        missing = common.draw_spread(ax, i + 0.12, values, color, gait, width=0.22)
        drawn += [v for v in [slopes[gait], *values] if np.isfinite(v)]
        n_members = max(n_members, len(values))
        labels.append(common.gait_label(gait, traj) + (f"\n{missing} no push" if missing else ""))
    if drawn and min(drawn) > 0 and max(drawn) > 10 * min(drawn):
        ax.set_yscale("log")
    ax.set_xticks(range(len(rows)), labels, rotation=30, ha="right")
    ax.set_xlim(-0.6, len(rows) - 0.4)
    ax.set_ylabel("slope [J/J]")
    ax.grid(False, axis="x")
    T = max((traj.duration for _, traj in rows), default=0.0)
    ax.legend(handles=[Line2D([], [], marker="D", ls="none", ms=3.5, color="0.4", label=f"nominal run ({T:g} s)")]
              + common.spread_handles(n_members, common.ensemble_window(ensemble)), loc="lower center", bbox_to_anchor=(0.5, 1.0),
              ncol=1, fontsize=5.5)  # one column: three side by side are wider than the figure


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None) -> list[str]:
    """Write ``fig06_work_efficiency.png/.pdf``: W_loc against W_box for every gait, with the fitted
    slope of each in the legend; with ``ensemble``, the members' end points and a panel of the
    slopes' spread.

    Implements: [COBRA] fig. 6 with ``analysis.locomotion_work``, ``box_work`` and
    ``efficiency_slope``.
    """
    rows = common.ordered(results)
    spread = bool(rows) and any(len(common.ensemble_values(ensemble, g, "efficiency_slope")) for g, _ in rows)
    fig = common.new_figure(common.ONE_COLUMN, 5.2 if spread else 3.3)
    axes = fig.subplots(2, 1, height_ratios=[2.0, 1.0]) if spread else [fig.add_subplot()]
    if not rows:
        common.empty_panel(axes[0], "no gait to show")
    slopes = plot_work(axes[0], rows, ensemble)
    axes[0].set_title("Locomotion work vs work on the box\n(dashed: fit over the push; steeper = less efficient)")
    if rows:
        fig.legend(loc="outside lower center", ncol=2)  # the curves' labels: gait and slope
    if spread:
        plot_slopes(axes[1], rows, slopes, ensemble)
    return common.save(fig, out_dir, "fig06_work_efficiency")


if __name__ == "__main__":
    common.main(make)
