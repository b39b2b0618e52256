"""Fig. 8: every joint's torque, the central pitch joint J5 and yaw joint J6 in bold, with the phase lags.

The paper's fig. 8 "depicts the torque profile for the central yawing (J6) and pitching (J5)
joints for each gait. Other joints show similar profiles offset by a phase angle based on the
executed gait". Plotted: the logged joint torques tau_j(t) [N m] (``traj.tau``, held over each
step), one row per gait, the pitch joints (J1, J3, .., J9) in the left panel and the yaw joints
(J0, J2, .., J10) in the right one; each joint has its own colour (``joint_colors``, head to
tail), the central joints J5 and J6 are drawn bold and black. Each joint's legend entry gives its phase
lag against J0 in gait periods (``analysis.joint_phase_correlation``, over the steady part of
the run; "n/a" where the period is unknown). The actuator limit +-tau_max (``model.tau_limit``,
the XH540-W270 stall torque 9.2 N m) is dotted and the region beyond it shaded red. Every panel
has the same y scale, which holds every peak; above each panel, the 99th percentile of the
panel's largest |tau_j| per step (``analysis.percentile_99``) and its peak.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps

from ..analysis import joint_phase_correlation, percentile_99
from . import common

CENTRAL = {"Ry": "J5", "Rz": "J6"}  # the paper's central pitch and yaw joints, drawn bold
AXIS_NAMES = {"Ry": "pitch", "Rz": "yaw"}
LIMIT_VIEW = 1.3  # the y scale shows at least +-1.3 tau_max


def tau_column(model, joint: str) -> int:
    """Column of ``traj.tau`` that holds joint ``joint`` (tau holds the revolute joints in body order).

    Maps a joint name to its torque column without hard-coding COBRA's numbering.
    """
    revolute = [i for i, jt in enumerate(model.joint_type) if jt != "free"]
    return revolute.index(model.joint_names.index(joint))


def joints_by_axis(model) -> dict:
    """{"Ry": [pitch joint names], "Rz": [yaw joint names]}, each head to tail."""
    out = {axis: [] for axis in CENTRAL}
    for name, jt in zip(model.joint_names, model.joint_type):
        if jt in out:
            out[jt].append(name)
    return out


def joint_colors(model) -> dict:
    """{joint name: colour}: the revolute joints along ``viridis`` from the head (dark) to the tail."""
    names = [n for n, jt in zip(model.joint_names, model.joint_type) if jt != "free"]
    return {n: colormaps["viridis"](x) for n, x in zip(names, np.linspace(0.0, 0.9, len(names)))}


def lag_label(joint: str, lag: float) -> str:
    """Legend entry of a joint: its name and its phase lag against J0, e.g. "J3 +0.16 T"."""
    if joint == "J0":
        return "J0 (reference)"
    return f"{joint} {lag:+.2f} T" if np.isfinite(lag) else f"{joint} lag n/a"


def torque_note(tau: np.ndarray) -> str:
    """The numbers above a panel, e.g. "p99 8.1, peak 9.2 N m".

    Fig. 8's annotation: of the largest |tau| of the panel's joints at each step [N m].
    """
    if not tau.size:
        return ""
    per_step = np.abs(tau).reshape(len(tau), -1).max(axis=1)
    return f"p99 {percentile_99(per_step):.3g}, peak {per_step.max():.3g} N m"


def plot_joints(ax, model, traj, joints: list, lags: list) -> np.ndarray:
    """tau_j(t) [N m] of ``joints``, min-max decimated, each in its colour, the central one bold,
    labelled with its phase lag; returns the (N, len(joints)) torques plotted."""
    t = common.step_times(traj)
    if len(t) == 0:
        common.empty_panel(ax, "no steps")
        return np.zeros((0, len(joints)))
    colors = joint_colors(model)
    tau = traj.tau[:, [tau_column(model, j) for j in joints]]
    for k, joint in enumerate(joints):
        bold = joint in CENTRAL.values()
        t_plot, y = common.minmax_decimate(t, tau[:, k])
        ax.plot(t_plot, y, color="k" if bold else colors[joint], lw=1.1 if bold else 0.6, zorder=3 if bold else 2,
                label=lag_label(joint, lags[model.joint_names.index(joint) - 1]))
    ax.legend(loc="center left", bbox_to_anchor=(1.0, 0.5), fontsize=5, handlelength=1.2, borderaxespad=0.3)
    return tau


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
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig08_torques.png/.pdf``: per gait, tau [N m] of every pitch joint (left) and every
    yaw joint (right), J5 and J6 bold, each labelled with its phase lag, with the +-tau_max limit,
    on one y scale.

    Implements: [COBRA] fig. 8 (central pitch J5 and yaw J6 torques, the other joints offset by a
    phase) with ``analysis.joint_phase_correlation`` and the limit of [COBRA] eq. (7) constraint
    (3), |tau| <= tau_max. ``ensemble`` is accepted for a common signature and not drawn.
    """
    rows, groups = common.ordered(results), joints_by_axis(model)
    fig = common.new_figure(common.TWO_COLUMN, 1.1 * max(len(rows), 1) + 0.6)
    axes = fig.subplots(max(len(rows), 1), len(groups), sharex=True, sharey=True, squeeze=False)
    if not rows:
        common.empty_panel(axes[0, 0], "no gait to show")
    taus = []
    for r, (gait, traj) in enumerate(rows):
        lags = joint_phase_correlation(traj)[1]
        for c, joints in enumerate(groups.values()):
            taus.append(plot_joints(axes[r, c], model, traj, joints, lags))
            axes[r, c].set_ylabel(f"{common.gait_label(gait, traj)}\n" + r"$\tau$ [N m]", color=common.gait_color(gait))
    panels = list(axes[: len(rows)].ravel())
    common.common_ylim(panels, taus)
    for ax, tau in zip(panels, taus):
        common.note_above(ax, torque_note(tau))
    limit = max((model.tau_limit[model.joint_names.index(j)] for j in CENTRAL.values()), default=np.inf)
    draw_limits(panels, limit)
    for c, axis in enumerate(groups):
        axes[0, c].set_title(f"{AXIS_NAMES[axis]} joints ({CENTRAL[axis]} black)", loc="left")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    fig.suptitle(f"Joint torques of every joint; legend: phase lag behind J0 in gait periods T\n"
                 f"above each panel: p99 and peak of max$_j|\\tau_j|$; dotted: stall-torque limit $\\pm${limit:g} N m")
    return common.save(fig, out_dir, "fig08_torques")


if __name__ == "__main__":
    common.main(make)
