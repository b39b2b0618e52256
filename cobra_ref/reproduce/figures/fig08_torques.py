"""Fig. 8: torques of the central pitch joint J5 and the central yaw joint J6.

The paper's fig. 8 "depicts the torque profile for the central yawing (J6) and pitching (J5)
joints for each gait". Plotted: the logged joint torques tau_J5(t) and tau_J6(t) [N m]
(``traj.tau``, held over each step; no ``analysis`` formula), one row per gait, with the actuator
limit +-tau_max (``model.tau_limit`` of that joint, the XH540-W270 stall torque 9.2 N m) drawn as
dotted lines and the region beyond it shaded red. Every panel has the same y scale, so the gaits
and the two joints compare at a glance; above each panel, the 99th percentile of |tau|
(``analysis.percentile_99``) and its peak, marked "(clipped)" when the peak is beyond the scale.
"""

from __future__ import annotations

import numpy as np

from ..analysis import percentile_99
from . import common

JOINTS = ("J5", "J6")
LIMIT_VIEW = 1.3  # the y scale shows at least +-1.3 tau_max


def tau_column(model, joint: str) -> int:
    """Column of ``traj.tau`` that holds joint ``joint`` (tau holds the revolute joints in body order).

    Maps a joint name to its torque column without hard-coding COBRA's numbering.
    """
    revolute = [i for i, jt in enumerate(model.joint_type) if jt != "free"]
    return revolute.index(model.joint_names.index(joint))


def torque_note(tau: np.ndarray, clipped: bool) -> str:
    """The numbers above a panel, e.g. "|tau|: p99 8.1, peak 37.2 N m (clipped)".

    Fig. 8's annotation (99th percentile and peak of |tau| [N m]).
    """
    if not len(tau):
        return ""
    text = rf"$|\tau|$: p99 {percentile_99(np.abs(tau)):.3g}, peak {np.abs(tau).max():.3g} N m"
    return text + (" (clipped)" if clipped else "")


def plot_torque(ax, t: np.ndarray, tau: np.ndarray, color: str) -> None:
    """tau(t) [N m], min-max decimated.
    """
    if len(t) == 0:
        common.empty_panel(ax, "no steps")
        return
    t_plot, y = common.minmax_decimate(t, tau)
    ax.plot(t_plot, y, color=color)


def draw_limits(axes, limit: float) -> None:
    """The limits +-``limit`` [N m] dotted and the region beyond them shaded on every axes, the y
    scale widened to at least +-``LIMIT_VIEW`` x limit.

    Fig. 8's actuator limit (call it after the y scale is set).
    """
    if not (axes and np.isfinite(limit)):
        return
    lo, hi = axes[0].get_ylim()
    lo, hi = min(lo, -LIMIT_VIEW * limit), max(hi, LIMIT_VIEW * limit)
    for ax in axes:
        for sign, reach in ((-1.0, lo), (1.0, hi)):
            ax.axhline(sign * limit, color="tab:red", ls=":", lw=0.8)
            ax.axhspan(sign * limit, reach, color="tab:red", alpha=0.08, lw=0)
        ax.set_ylim(lo, hi)


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None) -> list[str]:
    """Write ``fig08_torques.png/.pdf``: tau of J5 and J6 [N m] per gait with the +-tau_max limit,
    on one y scale.

    Implements: [COBRA] fig. 8 (central pitch J5 and yaw J6 torques) with the limit of [COBRA]
    eq. (7) constraint (3), |tau| <= tau_max. ``ensemble`` is accepted for a common signature
    and not drawn: the nominal runs only.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.TWO_COLUMN, 1.0 * max(len(rows), 1) + 0.6)
    axes = fig.subplots(max(len(rows), 1), len(JOINTS), sharex=True, sharey=True, squeeze=False)
    if not rows:
        common.empty_panel(axes[0, 0], "no gait to show")
    panels, taus = [], []
    for r, (gait, traj) in enumerate(rows):
        color, t = common.gait_color(gait), common.step_times(traj)
        for c, joint in enumerate(JOINTS):
            taus.append(traj.tau[:, tau_column(model, joint)])
            panels.append(axes[r, c])
            plot_torque(axes[r, c], t, taus[-1], color)
            axes[r, c].set_ylabel(f"{common.gait_label(gait, traj)}\n" + r"$\tau$ [N m]", color=color)
    for ax, tau, peak in zip(panels, taus, common.robust_ylim(panels, taus, quantile=0.995)):
        common.note_above(ax, torque_note(tau, peak is not None))
    for c, joint in enumerate(JOINTS):
        draw_limits(list(axes[: len(rows), c]), model.tau_limit[model.joint_names.index(joint)])
    axes[0, 0].set_title("J5 (central pitch joint)", loc="left")
    axes[0, 1].set_title("J6 (central yaw joint)", loc="left")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    limit = model.tau_limit[model.joint_names.index(JOINTS[0])]
    fig.suptitle(f"Joint torques; dotted: stall-torque limit $\\pm${limit:g} N m")
    return common.save(fig, out_dir, "fig08_torques")


if __name__ == "__main__":
    common.main(make)
