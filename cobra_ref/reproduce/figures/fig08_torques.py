"""Fig. 8: torques of the central pitch joint J5 and the central yaw joint J6.

The paper's fig. 8 "depicts the torque profile for the central yawing (J6) and pitching (J5)
joints for each gait". Plotted: the logged joint torques tau_J5(t) and tau_J6(t) [N m]
(``traj.tau``, held over each step; no ``analysis`` formula), one row per gait, with the actuator
limit +-tau_max (``model.tau_limit`` of that joint, the XH540-W270 stall torque 9.2 N m) drawn as
dotted lines and the region beyond it shaded red.
"""

from __future__ import annotations

import numpy as np

from . import common

JOINTS = ("J5", "J6")


def tau_column(model, joint: str) -> int:
    """Column of ``traj.tau`` that holds joint ``joint`` (tau holds the revolute joints in body order).

    Helper: maps a joint name to its torque column without hard-coding COBRA's numbering.
    """
    revolute = [i for i, jt in enumerate(model.joint_type) if jt != "free"]
    return revolute.index(model.joint_names.index(joint))


def plot_torque(ax, t: np.ndarray, tau: np.ndarray, limit: float, color: str) -> None:
    """tau(t) [N m] with the limits +-``limit`` dotted and the forbidden region shaded.

    Helper: one panel of fig. 8.
    """
    if len(t) == 0:
        common.empty_panel(ax, "no steps")
        return
    t_plot, y = common.minmax_decimate(t, tau)
    ax.plot(t_plot, y, color=color)
    common.robust_ylim(ax, tau, unit="N m", quantile=0.995)
    if np.isfinite(limit):
        lo, hi = ax.get_ylim()
        reach = max(abs(lo), abs(hi), 1.3 * limit)
        for sign in (-1.0, 1.0):
            ax.axhline(sign * limit, color="tab:red", ls=":", lw=0.8)
            ax.axhspan(sign * limit, sign * reach, color="tab:red", alpha=0.08, lw=0)
        ax.set_ylim(min(lo, -1.3 * limit), max(hi, 1.3 * limit))


@common.paper_style
def make(results: dict, out_dir: str, model) -> list[str]:
    """Write ``fig08_torques.png/.pdf``: tau of J5 and J6 [N m] per gait with the +-tau_max limit.

    Implements: [COBRA] fig. 8 (central pitch J5 and yaw J6 torques) with the limit of [COBRA]
    eq. (7) constraint (3), |tau| <= tau_max.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.TWO_COLUMN, 1.0 * max(len(rows), 1) + 0.6)
    axes = fig.subplots(max(len(rows), 1), len(JOINTS), sharex=True, squeeze=False)
    if not rows:
        common.empty_panel(axes[0, 0], "no gait to show")
    for r, (gait, traj) in enumerate(rows):
        color, t = common.gait_color(gait), common.step_times(traj)
        for c, joint in enumerate(JOINTS):
            limit = model.tau_limit[model.joint_names.index(joint)]
            plot_torque(axes[r, c], t, traj.tau[:, tau_column(model, joint)], limit, color)
            axes[r, c].set_ylabel(f"{common.gait_label(gait, traj)}\n" + r"$\tau$ [N m]", color=color)
    axes[0, 0].set_title("J5 (central pitch joint)")
    axes[0, 1].set_title("J6 (central yaw joint)")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    limit = model.tau_limit[model.joint_names.index(JOINTS[0])]
    fig.suptitle(f"Joint torques; dotted: stall-torque limit $\\pm${limit:g} N m")
    return common.save(fig, out_dir, "fig08_torques")


if __name__ == "__main__":
    common.main(make)
