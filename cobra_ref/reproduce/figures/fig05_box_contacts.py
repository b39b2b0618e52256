"""Fig. 5: the box's contacts: robot-box and box-ground normal and tangential forces.

The paper's fig. 5 shows, for the C, S, J and sidewinding gaits, the contact forces "of the
manipulated object with the robot and with the ground", split into normal f_N and tangential
f_T. Here each gait is one row of two panels, both from ``analysis.contact_forces``:

* robot-box (``ROBOT_BOX``): f_N (solid) and |f_T| (dashed) [N] summed over all links touching
  the box at each step; the links that touched it are named in the panel;
* box-ground (``BOX_GROUND``): f_N (solid) and |f_T| (dashed) [N] summed over the box's corners,
  with the box's weight m g dotted for reference (f_N = m g when nothing else pushes down).

f_N = f . n and |f_T| = |f - f_N n| for the contact force f of the log; the magnitudes are the
same on either body of a contact pair (action = reaction). The panels of a column share one y
scale, which holds every peak, so the gaits compare at a glance. The title gives, per gait, how
hard the box presses the ground while a link pushes it (``wedging``: the mean box-ground f_N
over the robot-box steps, in units of the box's weight): a rolling link pushes on the box above
its centre and wedges it down (assumption A22), so the box-ground force is several times m g.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from ..analysis import BOX_GROUND, ROBOT_BOX, contact_forces
from . import common


def plot_normal_tangential(ax, t: np.ndarray, f_N: np.ndarray, f_T: np.ndarray, color: str) -> np.ndarray:
    """f_N solid and |f_T| dashed over time [N], as means over ``common.FORCE_WINDOW`` (20 ms);
    "no contact" when both are zero. Returns the plotted means (empty for "no contact"), for the
    y scale.
    """
    if len(t) == 0 or not (np.any(f_N) or np.any(f_T)):
        common.empty_panel(ax)
        return np.zeros(0)
    t_mean, f_N = common.window_mean(t, f_N)
    f_T = common.window_mean(t, f_T)[1]
    ax.plot(t_mean, f_N, color=color)
    ax.plot(t_mean, f_T, color=color, ls="--", lw=0.8)
    return np.concatenate([f_N, f_T])


def plot_box_ground(ax, model, traj, t: np.ndarray, color: str) -> np.ndarray:
    """Box-ground f_N and |f_T| [N] (summed over the corners) and the box's weight m g dotted;
    returns the plotted means.
    """
    box = common.box_body(model)
    if box is None:
        common.empty_panel(ax, "no box in the model")
        return np.zeros(0)
    bg = contact_forces(traj, BOX_GROUND, model.nb)
    plotted = plot_normal_tangential(ax, t, bg.normal[:, box], bg.tangential[:, box], color)
    if len(plotted):
        ax.axhline(-model.mass[box] * model.gravity[2], color="0.3", ls=":", lw=0.8)
    return plotted


def wedging(model, traj) -> float:
    """Mean box-ground normal force over the steps with a robot-box contact, divided by the box's
    weight m g (nan when no link touched the box)."""
    box = common.box_body(model)
    pushed = contact_forces(traj, ROBOT_BOX, model.nb).in_contact.any(axis=1)
    if box is None or not pushed.any():
        return float("nan")
    f_N = contact_forces(traj, BOX_GROUND, model.nb).normal[:, box]
    return float(f_N[pushed].mean() / (-model.mass[box] * model.gravity[2]))


def wedging_note(model, rows) -> str:
    """The title's lines on the wedging force, per gait ``wedging``, e.g. ".. C 3.2, S 2.4 .."."""
    ratios = [(gait, wedging(model, traj)) for gait, traj in rows]
    shown = [f"{g} {r:.1f}" for g, r in ratios if np.isfinite(r)]
    return ("box-ground $f_N$ while a link pushes the box, mean, in units of the box's weight $mg$:\n"
            + ", ".join(shown) + " (the pushing link wedges the box down, A22)") if shown else ""


def touching_links(model, in_contact: np.ndarray) -> str:
    """Names of the bodies that touched the box at least once, e.g. "L5, L6".

    The "contact points" of the paper's fig. 5, as a list of links.
    """
    bodies = np.flatnonzero(in_contact.any(axis=0))
    return ", ".join(model.body_names[i] for i in bodies)


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig05_box_contacts.png/.pdf``: per gait, robot-box and box-ground normal and
    tangential forces over time.

    Implements: [COBRA] fig. 5 with ``analysis.contact_forces`` of kinds ROBOT_BOX and BOX_GROUND.
    ``ensemble`` is accepted for a common signature and not drawn: the nominal runs only.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.TWO_COLUMN, 1.2 * max(len(rows), 1) + 0.5)
    axes = fig.subplots(max(len(rows), 1), 2, sharex=True, sharey="col", squeeze=False)
    if not rows:
        common.empty_panel(axes[0, 0], "no gait to show")
    plotted = [[], []]  # per column, each row's plotted values
    for r, (gait, traj) in enumerate(rows):
        color, t = common.gait_color(gait), common.step_times(traj)
        rb = contact_forces(traj, ROBOT_BOX, model.nb)
        plotted[0].append(plot_normal_tangential(axes[r, 0], t, rb.normal.sum(axis=1), rb.tangential.sum(axis=1),
                                                 color))
        if len(plotted[0][-1]):
            axes[r, 0].text(0.01, 0.97, "links: " + touching_links(model, rb.in_contact),
                            transform=axes[r, 0].transAxes, va="top", fontsize=6)
        plotted[1].append(plot_box_ground(axes[r, 1], model, traj, t, color))
        for ax in axes[r]:
            ax.set_ylabel(f"{common.gait_label(gait, traj)}\nforce [N]", color=color)
    for c, values in enumerate(plotted):
        common.common_ylim(list(axes[: len(values), c]), values, bottom=0.0)
    axes[0, 0].set_title("robot-box contact, sum over links", loc="left")
    axes[0, 1].set_title("box-ground contact, sum over corners", loc="left")
    _legend(fig, wedging_note(model, rows) if common.box_body(model) is not None else "")
    for ax in axes[-1]:
        ax.set_xlabel("time [s]")
    return common.save(fig, out_dir, "fig05_box_contacts")


def _legend(fig, note: str) -> None:
    """One legend for the line styles, above the panels, under the ``note`` on the wedging force."""
    handles = [Line2D([], [], color="0.2", label=r"normal $f_N$"),
               Line2D([], [], color="0.2", ls="--", lw=0.8, label=r"tangential $\|f_T\|$"),
               Line2D([], [], color="0.3", ls=":", lw=0.8, label="box weight $mg$")]
    fig.legend(handles=handles, loc="outside upper center", ncol=3,
               title=(note + "\n" if note else "") + f"forces: means over {1e3 * common.FORCE_WINDOW:g} ms windows")


if __name__ == "__main__":
    common.main(make)
