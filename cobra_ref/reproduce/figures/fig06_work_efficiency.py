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
"""

from __future__ import annotations

import numpy as np

from ...analysis import box_work, efficiency_fit, locomotion_work
from . import common


def slope_label(gait: str, traj, slope: float) -> str:
    """Legend entry: the gait and its slope dW_loc/dW_box [J/J] (or "no work on box").

    Helper: fig. 6 legend.
    """
    name = common.gait_label(gait, traj)
    return f"{name}: slope {slope:.3g} J/J" if np.isfinite(slope) else f"{name}: no work on box"


@common.paper_style
def make(results: dict, out_dir: str, model) -> list[str]:
    """Write ``fig06_work_efficiency.png/.pdf``: W_loc against W_box for every gait, with the fitted
    slope of each in the legend.

    Implements: [COBRA] fig. 6 with ``analysis.locomotion_work``, ``box_work`` and
    ``efficiency_slope``.
    """
    fig = common.new_figure(common.ONE_COLUMN, 2.9)
    ax = fig.add_subplot()
    rows = common.ordered(results)
    if not rows:
        common.empty_panel(ax, "no gait to show")
    for gait, traj in rows:
        color = common.gait_color(gait)
        w_loc, w_box = locomotion_work(traj), box_work(traj)
        s, b = efficiency_fit(traj)
        ax.plot(w_box, w_loc, color=color, label=slope_label(gait, traj, s))
        ax.plot(w_box[-1:], w_loc[-1:], "o", color=color, ms=3)
        if np.isfinite(s):
            x = np.array([0.0, w_box.max(initial=0.0)])
            ax.plot(x, s * x + b, color=color, ls="--", lw=0.7)
    ax.set_xlabel(r"work done on the box $W_{box}$ [J]")
    ax.set_ylabel(r"locomotion work $W_{loc}$ [J]")
    ax.set_title("Locomotion work vs work on the box\n(dashed: fit over the push; steeper = less efficient)")
    if rows:
        ax.legend(loc="best")
    return common.save(fig, out_dir, "fig06_work_efficiency")


if __name__ == "__main__":
    common.main(make)
