"""Fig. 4: robot-ground contacts of the links and their normal and tangential forces.

The paper's fig. 4 shows, for the C, S, J and sidewinding gaits, "the contact points and
unilateral ground reaction forces" of the links L1..L10 (numbered from the head), split into the
normal force f_N,i and the tangential force f_T,i. Here each gait is one row of three panels:

* contact timeline: which body touches the ground when (a bar in the body's colour);
* f_N,i(t) [N] per link, f_N = f . n;
* |f_T,i|(t) [N] per link, |f_T| = |f - f_N n|;

both from ``analysis.contact_forces(traj, ROBOT_GROUND, model.nb)`` (forces ON the link, summed
over a link's contact spheres at each step). Each body has its own colour of a qualitative
palette (``BODY_COLORS``), the same in every panel, named in the legend below the panels; the
force panels of a column share one y scale, which holds every peak, so the gaits compare at a
glance. The title names, per gait, the bodies that never touch the ground in the run
(``lifted_bodies``; e.g. C's head and L8-L10 in its optimum's run).

Note: the head and the tail are shown too (rows above L1 and below L10), although the paper's
figure names only L1..L10: in our runs they carry a good part of the robot's weight, and leaving
them out would hide where that weight goes.
"""

from __future__ import annotations

import textwrap

import numpy as np
from matplotlib.colors import to_rgba
from matplotlib.lines import Line2D

from ..analysis import ROBOT_GROUND, contact_forces
from . import common

# Kelly's colours of maximum contrast (K. L. Kelly, "Twenty-two colors of maximum contrast",
# Color Engineering 3(6), 1965), white left out: 12 bodies, head (black) to tail, that stay
# apart; the palette repeats for a robot with more bodies
BODY_COLORS = ("#222222", "#f3c300", "#875692", "#f38400", "#a1caf1", "#be0032", "#c2b280", "#848482",
               "#008856", "#e68fac", "#0067a5", "#f99379")


def link_colors(n: int) -> list:
    """n colours from ``BODY_COLORS``, head end first.

    The same colour for a body in every panel.
    """
    return [BODY_COLORS[i % len(BODY_COLORS)] for i in range(n)]


def plot_timeline(ax, t: np.ndarray, in_contact: np.ndarray, names: list[str], colors: list) -> None:
    """Contact timeline: one row per body (head on top), in the body's colour where it touches the
    ground, white elsewhere.

    Fig. 4's "which link touches the ground when".
    """
    if len(t) == 0 or not in_contact.any():
        common.empty_panel(ax)
    dt = t[1] - t[0] if len(t) > 1 else 1.0
    extent = (t[0] if len(t) else 0.0, (t[-1] + dt) if len(t) else 1.0, len(names) + 0.5, 0.5)
    # (N, n_bodies, 4) RGBA image, transposed to one row per body
    rgba = np.where(in_contact[..., None], np.array([to_rgba(c) for c in colors]), 1.0)
    ax.imshow(rgba.transpose(1, 0, 2), aspect="auto", interpolation="nearest", extent=extent)
    ax.set_yticks(range(1, len(names) + 1), names)
    ax.tick_params(axis="y", labelsize=5.5)
    ax.grid(False)


def plot_per_link(ax, t: np.ndarray, force: np.ndarray, colors: list) -> np.ndarray:
    """One line per body of a (N, n_bodies) force array [N], as means over ``common.FORCE_WINDOW``
    (20 ms); "no contact" when it is all zero. Returns the plotted non-zero means (for the y scale).
    """
    if len(t) == 0 or not np.any(force):
        common.empty_panel(ax)
        return np.zeros(0)
    t_mean, f_mean = common.window_mean(t, force)
    for j, color in enumerate(colors):
        if np.any(force[:, j]):
            ax.plot(t_mean, f_mean[:, j], color=color, lw=0.7)
    return f_mean[f_mean > 0]


def lifted_bodies(model, traj) -> list[str]:
    """Names of the robot's bodies that never touch the ground in ``traj``, head to tail."""
    touched = contact_forces(traj, ROBOT_GROUND, model.nb).in_contact.any(axis=0)
    return [name for name, i in common.robot_bodies(model) if not touched[i]]


def name_ranges(names: list[str], order: list[str]) -> str:
    """``names`` with runs of three or more neighbours in ``order`` shortened, e.g. "head, L8-L10"."""
    pos = sorted(order.index(n) for n in names)
    runs = []
    for p in pos:
        if runs and p == runs[-1][-1] + 1:
            runs[-1].append(p)
        else:
            runs.append([p])
    return ", ".join(f"{order[r[0]]}-{order[r[-1]]}" if len(r) >= 3 else ", ".join(order[p] for p in r)
                     for r in runs)


def lifted_note(model, rows) -> str:
    """The title: per gait, the bodies that never touch the ground ("none" when all do)."""
    order = [n for n, _ in common.robot_bodies(model)]
    parts = [f"{gait}: {name_ranges(lifted_bodies(model, traj), order) or 'none'}" for gait, traj in rows]
    # wrapped to the width of a two-column figure
    return "Robot-ground contacts; bodies that never touch the ground in the run:\n" + textwrap.fill("; ".join(parts), 100)


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig04_robot_contacts.png/.pdf``: per gait, the ground-contact timeline of head,
    L1..L10 and tail, and the normal and tangential robot-ground forces per body over time.

    Implements: [COBRA] fig. 4 with ``analysis.contact_forces(traj, ROBOT_GROUND, nb)``.
    ``ensemble`` is accepted for a common signature and not drawn: the nominal runs only.
    """
    rows = common.ordered(results)
    bodies = common.robot_bodies(model)
    names, idx = [n for n, _ in bodies], [i for _, i in bodies]
    colors = link_colors(len(bodies))
    fig = common.new_figure(common.TWO_COLUMN, 1.35 * max(len(rows), 1) + 0.7)
    axes = fig.subplots(max(len(rows), 1), 3, sharex=True, sharey="col", squeeze=False)
    if not rows:
        common.empty_panel(axes[0, 0], "no gait to show")
    plotted = {1: [], 2: []}  # per force column, each row's plotted values
    for r, (gait, traj) in enumerate(rows):
        cf = contact_forces(traj, ROBOT_GROUND, model.nb)
        t = common.step_times(traj)
        plot_timeline(axes[r, 0], t, cf.in_contact[:, idx], names, colors)
        plotted[1].append(plot_per_link(axes[r, 1], t, cf.normal[:, idx], colors))
        plotted[2].append(plot_per_link(axes[r, 2], t, cf.tangential[:, idx], colors))
        axes[r, 0].set_ylabel(f"{common.gait_label(gait, traj)}\nbody", color=common.gait_color(gait))
        axes[r, 1].set_ylabel(r"$f_{N,i}$ [N]")
        axes[r, 2].set_ylabel(r"$\|f_{T,i}\|$ [N]")
    for c, values in plotted.items():
        common.common_ylim(list(axes[: len(values), c]), values, bottom=0.0)
    for ax, title in zip(axes[0], ("ground contact", "normal force", "tangential force")):
        ax.set_title(title, loc="left")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    _body_legend(fig, names, colors)
    if rows:
        fig.suptitle(lifted_note(model, rows))
    return common.save(fig, out_dir, "fig04_robot_contacts")


def _body_legend(fig, names: list[str], colors: list) -> None:
    """One legend below the panels naming the body of each colour, head to tail."""
    if not names:
        return
    handles = [Line2D([], [], color=c, lw=2.0, label=n) for n, c in zip(names, colors)]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(names), handlelength=1.2,
               columnspacing=0.9, title=f"body ({names[0]}, L1..L10 numbered from the head, {names[-1]}); "
                                        f"forces are means over {1e3 * common.FORCE_WINDOW:g} ms")


if __name__ == "__main__":
    common.main(make)
