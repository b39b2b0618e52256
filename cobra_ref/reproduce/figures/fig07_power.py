"""Fig. 7: instantaneous locomotion power of each gait.

The paper's fig. 7 "shows the instantaneous power consumption by the robot to execute
locomotion for each of the considered gaits" (sidewinding has the large peaks). Plotted, one
panel per gait on a shared time axis, from ``analysis.locomotion_power``:

* P_loc = sum_j tau_j qdot_j [W] (solid; negative when the joints brake the motion),
* |P|_loc = sum_j |tau_j qdot_j| [W] (dashed; the power the actuators must supply),

with qdot_j the joint rate at each step's midpoint. Every panel has the same y scale, and it
holds every gait's peaks (the paper compares the gaits: "the large peaks in instantaneous power
from sidewinding", claim PP); above each panel, the mean, the 99th percentile
(``analysis.percentile_99``) and the peak of |P|_loc.
"""

from __future__ import annotations

import numpy as np

from ..analysis import locomotion_power, percentile_99
from . import common


def power_note(P_abs: np.ndarray) -> str:
    """The numbers above a panel, e.g. "|P|: mean 3.1, p99 9.2, peak 9.5 W".

    Fig. 7's annotation (mean, 99th percentile and peak of |P|_loc [W]).
    """
    if not len(P_abs):
        return ""
    return f"|P|: mean {P_abs.mean():.3g}, p99 {percentile_99(P_abs):.3g}, peak {P_abs.max():.3g} W"


def plot_power(ax, traj, color: str) -> np.ndarray:
    """P_loc solid and |P|_loc dashed over time [W]; returns |P|_loc (empty: "no steps").
    """
    t = common.step_times(traj)
    if len(t) == 0:
        common.empty_panel(ax, "no steps")
        return np.zeros(0)
    P, P_abs = locomotion_power(traj)
    t_plot, P_plot = common.minmax_decimate(t, P)
    ax.plot(t_plot, P_plot, color=color, label=r"$P_{loc}$")
    t_plot, A_plot = common.minmax_decimate(t, P_abs)
    ax.plot(t_plot, A_plot, color=color, ls="--", lw=0.7, label=r"$|P|_{loc}$")
    ax.axhline(0.0, color="0.5", lw=0.5)
    return P_abs


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig07_power.png/.pdf``: P_loc (solid) and |P|_loc (dashed) [W] per gait over time,
    on one y scale that holds every peak.

    Implements: [COBRA] fig. 7 with ``analysis.locomotion_power``. ``ensemble`` is accepted for a
    common signature and not drawn: the nominal runs only.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.ONE_COLUMN, 0.95 * max(len(rows), 1) + 0.8)
    axes = fig.subplots(max(len(rows), 1), 1, sharex=True, sharey=True, squeeze=False)[:, 0]
    if not rows:
        common.empty_panel(axes[0], "no gait to show")
    P_abs = []
    for ax, (gait, traj) in zip(axes, rows):
        color = common.gait_color(gait)
        P_abs.append(plot_power(ax, traj, color))
        ax.set_ylabel(f"{common.gait_label(gait, traj)}\npower [W]", color=color)
    # |P|_loc >= |P_loc| at every step: a scale that holds |P|_loc holds both lines
    common.common_ylim(list(axes[: len(rows)]), P_abs)
    for ax, values in zip(axes, P_abs):
        common.note_above(ax, power_note(values))
    fig.suptitle("Instantaneous locomotion power")
    if rows:
        fig.legend(handles=axes[0].get_lines()[:2], loc="outside lower center", ncol=2)
    axes[-1].set_xlabel("time [s]")
    return common.save(fig, out_dir, "fig07_power")


if __name__ == "__main__":
    common.main(make)
