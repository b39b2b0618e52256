"""Fig. 4: robot-ground contacts of the links and their normal and tangential forces.

The paper's fig. 4 shows, for the C, S, J and sidewinding gaits, "the contact points and
unilateral ground reaction forces" of the links L1..L10 (numbered from the head), split into the
normal force f_N,i and the tangential force f_T,i. Here each gait is one row of three panels:

* contact timeline: which body touches the ground when (dark = in contact);
* f_N,i(t) [N] per link, f_N = f . n;
* |f_T,i|(t) [N] per link, |f_T| = |f - f_N n|;

both from ``analysis.contact_forces(traj, ROBOT_GROUND, model.nb)`` (forces ON the link, summed
over a link's contact spheres at each step). Bodies share one colour scale (colour bar).

Note: the head and the tail are shown too (rows above L1 and below L10), although the paper's
figure names only L1..L10: in our runs they carry a good part of the robot's weight, and leaving
them out would hide where that weight goes.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.cm import ScalarMappable
from matplotlib.colors import BoundaryNorm, ListedColormap

from ...analysis import ROBOT_GROUND, contact_forces
from . import common

LINK_CMAP = "viridis"


def link_colors(n: int) -> list:
    """n colours along ``LINK_CMAP``, head end first.

    Helper: the same colour for a body in every panel.
    """
    cmap = colormaps[LINK_CMAP]
    return [cmap(x) for x in np.linspace(0.0, 0.9, n)]


def plot_timeline(ax, t: np.ndarray, in_contact: np.ndarray, names: list[str]) -> None:
    """Contact timeline: one row per body (head on top), dark where it touches the ground.

    Helper: fig. 4's "which link touches the ground when".
    """
    if len(t) == 0 or not in_contact.any():
        common.empty_panel(ax)
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    extent = (t[0] if len(t) else 0.0, (t[-1] + dt) if len(t) else 1.0, len(names) + 0.5, 0.5)
    ax.imshow(in_contact.T.astype(float), aspect="auto", interpolation="nearest", cmap="Greys",
              vmin=0, vmax=1.25, extent=extent)
    ax.set_yticks(range(1, len(names) + 1), names)
    ax.tick_params(axis="y", labelsize=5.5)
    ax.grid(False)


def plot_per_link(ax, t: np.ndarray, force: np.ndarray, colors: list) -> None:
    """One line per body of a (N, n_bodies) force array [N], as means over ``common.FORCE_WINDOW``
    (20 ms); "no contact" when it is all zero.

    Helper: the f_N and f_T panels.
    """
    if len(t) == 0 or not np.any(force):
        common.empty_panel(ax)
        return
    t_mean, f_mean = common.window_mean(t, force)
    for j, color in enumerate(colors):
        if np.any(force[:, j]):
            ax.plot(t_mean, f_mean[:, j], color=color, lw=0.7)
    ax.set_ylim(bottom=0.0)
    common.robust_ylim(ax, f_mean[f_mean > 0])


@common.paper_style
def make(results: dict, out_dir: str, model) -> list[str]:
    """Write ``fig04_robot_contacts.png/.pdf``: per gait, the ground-contact timeline of head,
    L1..L10 and tail, and the normal and tangential robot-ground forces per body over time.

    Implements: [COBRA] fig. 4 with ``analysis.contact_forces(traj, ROBOT_GROUND, nb)``.
    """
    rows = common.ordered(results)
    bodies = common.robot_bodies(model)
    names, idx = [n for n, _ in bodies], [i for _, i in bodies]
    colors = link_colors(len(bodies))
    fig = common.new_figure(common.TWO_COLUMN, 1.35 * max(len(rows), 1) + 0.5)
    axes = fig.subplots(max(len(rows), 1), 3, sharex=True, squeeze=False)
    if not rows:
        common.empty_panel(axes[0, 0], "no gait to show")
    for r, (gait, traj) in enumerate(rows):
        cf = contact_forces(traj, ROBOT_GROUND, model.nb)
        t = common.step_times(traj)
        plot_timeline(axes[r, 0], t, cf.in_contact[:, idx], names)
        plot_per_link(axes[r, 1], t, cf.normal[:, idx], colors)
        plot_per_link(axes[r, 2], t, cf.tangential[:, idx], colors)
        axes[r, 0].set_ylabel(f"{common.gait_label(gait, traj)}\nbody", color=common.gait_color(gait))
        axes[r, 1].set_ylabel(r"$f_{N,i}$ [N]")
        axes[r, 2].set_ylabel(r"$\|f_{T,i}\|$ [N]")
    axes[0, 0].set_title("ground contact (dark = touching)")
    axes[0, 1].set_title("normal force per body (20 ms means)")
    axes[0, 2].set_title("tangential force per body (20 ms means)")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    _link_colorbar(fig, axes[:, 1:], names)
    return common.save(fig, out_dir, "fig04_robot_contacts")


def _link_colorbar(fig, axes, names: list[str]) -> None:
    """A discrete colour bar naming the body of each line colour."""
    if not names:
        return
    n = len(names)
    sm = ScalarMappable(norm=BoundaryNorm(np.arange(n + 1) + 0.5, n), cmap=ListedColormap(link_colors(n)))
    cb = fig.colorbar(sm, ax=axes.ravel().tolist(), ticks=range(1, n + 1), aspect=40, pad=0.01)
    cb.ax.set_yticklabels(names, fontsize=5.5)
    cb.ax.invert_yaxis()
    cb.set_label("body (L1..L10 numbered from the head)")


if __name__ == "__main__":
    common.main(make)
