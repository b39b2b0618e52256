"""Fig. 7: instantaneous locomotion power of each gait.

The paper's fig. 7 "shows the instantaneous power consumption by the robot to execute
locomotion for each of the considered gaits" (sidewinding has the large peaks). Plotted, one
panel per gait on a shared time axis, from ``analysis.locomotion_power``:

* P_loc = sum_j tau_j qdot_j [W] (solid; negative when the joints brake the motion),
* |P|_loc = sum_j |tau_j qdot_j| [W] (dashed; the power the actuators must supply),

with qdot_j the joint rate at each step's midpoint; the mean and peak of |P|_loc are written in
each panel's corner.
"""

from __future__ import annotations

from ...analysis import locomotion_power
from . import common


def plot_power(ax, traj, color: str) -> None:
    """P_loc solid and |P|_loc dashed over time [W], with mean and peak |P| written in the panel.

    Helper: one panel of fig. 7.
    """
    t = common.step_times(traj)
    if len(t) == 0:
        common.empty_panel(ax, "no steps")
        return
    P, P_abs = locomotion_power(traj)
    t_plot, P_plot = common.minmax_decimate(t, P)
    ax.plot(t_plot, P_plot, color=color, label=r"$P_{loc}$")
    t_plot, A_plot = common.minmax_decimate(t, P_abs)
    ax.plot(t_plot, A_plot, color=color, ls="--", lw=0.7, label=r"$|P|_{loc}$")
    ax.axhline(0.0, color="0.5", lw=0.5)
    common.robust_ylim(ax, P_abs, unit="W", quantile=0.995)
    ax.set_title(f"mean |P| {P_abs.mean():.3g} W, peak |P| {P_abs.max():.3g} W", loc="right",
                 fontsize=6, pad=2)


@common.paper_style
def make(results: dict, out_dir: str, model) -> list[str]:
    """Write ``fig07_power.png/.pdf``: P_loc (solid) and |P|_loc (dashed) [W] per gait over time.

    Implements: [COBRA] fig. 7 with ``analysis.locomotion_power``.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.ONE_COLUMN, 0.95 * max(len(rows), 1) + 0.6)
    axes = fig.subplots(max(len(rows), 1), 1, sharex=True, squeeze=False)[:, 0]
    if not rows:
        common.empty_panel(axes[0], "no gait to show")
    for ax, (gait, traj) in zip(axes, rows):
        color = common.gait_color(gait)
        plot_power(ax, traj, color)
        ax.set_ylabel(f"{common.gait_label(gait, traj)}\npower [W]", color=color)
    fig.suptitle("Instantaneous locomotion power")
    if rows:
        axes[0].legend(loc="upper left", ncol=2)
    axes[-1].set_xlabel("time [s]")
    return common.save(fig, out_dir, "fig07_power")


if __name__ == "__main__":
    common.main(make)
