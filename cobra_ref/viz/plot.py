"""One look at a run: the box's path, the contact forces and the joint torques, as matplotlib panels.

``plot_run(run)`` takes a ``Trajectory`` (what ``simulate`` returns) or the path of its NPZ (what
``cobra-ref simulate --out`` writes) and draws, one panel each, in the order asked for:

* ``"box"``: the box's centre seen from above, ``box_pose[:, :2]`` [m], equal axes, + at the start;
* ``"forces"``: per contact kind (robot-ground, robot-box, box-ground), the sum over the contact
  log's rows of each step of the normal force f . n [N] against the step's start time;
* ``"torques"``: the joint torques ``tau`` [N m], one line per joint, against the step's start time.

matplotlib is imported when a figure is drawn, not with this module.
"""

from __future__ import annotations

import numpy as np

from ..contact import KINDS as KIND_NAMES  # contact_kind 0, 1, 2
from ..trajectory import Trajectory

PANELS = ("box", "forces", "torques")


def as_trajectory(run) -> Trajectory:
    """``run`` if it is a Trajectory, else the Trajectory in the NPZ at path ``run``."""
    return run if isinstance(run, Trajectory) else Trajectory.from_npz(str(run))


def normal_forces(traj: Trajectory) -> dict:
    """{kind name: (N,) array}: the normal force [N] of each step summed over the contact log's rows of
    that kind (f . n, the force on body A along the normal from B to A)."""
    n_steps = len(traj.tau)
    c = traj.contacts
    steps = np.asarray(c["contact_step"], dtype=int)
    f_n = traj.contact_normal_force()
    kinds = np.asarray(c["contact_kind"], dtype=int)
    return {name: np.bincount(steps[kinds == k], weights=f_n[kinds == k], minlength=n_steps)[:n_steps]
            for k, name in enumerate(KIND_NAMES)}


def _box(ax, traj: Trajectory) -> None:
    xy = traj.box_pose[:, :2]
    ax.plot(xy[:, 0], xy[:, 1], color="tab:brown", label="box centre")
    ax.plot(xy[:1, 0], xy[:1, 1], "k+", ms=8, label="start")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("the box's path (top view)")


def _forces(ax, traj: Trajectory) -> None:
    t = traj.t[:len(traj.tau)]
    for name, f in normal_forces(traj).items():
        ax.plot(t, f, label=name)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("normal force [N]")
    ax.set_title("contact forces, summed per kind")
    ax.legend(fontsize="small")


def _torques(ax, traj: Trajectory) -> None:
    t = traj.t[:len(traj.tau)]
    for j in range(traj.tau.shape[1]):
        ax.plot(t, traj.tau[:, j], lw=0.8, label=f"J{j}")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("joint torque [N m]")
    ax.set_title("joint torques")
    ax.legend(fontsize="x-small", ncol=2)


DRAW = {"box": _box, "forces": _forces, "torques": _torques}


def plot_run(run, what=PANELS, ax=None):
    """Draw the panels ``what`` (names of ``PANELS``, module docstring) of ``run`` (a Trajectory or
    the path of its NPZ) and return the matplotlib Figure.

    ``ax``: None (a new figure, one row of panels, from ``matplotlib.pyplot``), one Axes (when
    ``what`` names one panel, or is that name as a string) or a sequence of Axes, one per panel;
    the figure returned is then theirs. ValueError for an unknown panel or a wrong number of Axes.
    """
    what = (what,) if isinstance(what, str) else tuple(what)
    unknown = [w for w in what if w not in DRAW]
    if unknown or not what:
        raise ValueError(f"what must name panels of {', '.join(PANELS)}, got {what!r}")
    traj = as_trajectory(run)
    if ax is None:
        import matplotlib.pyplot as plt

        fig, axes = plt.subplots(1, len(what), figsize=(4.2 * len(what), 3.6), layout="constrained", squeeze=False)
        axes = list(axes[0])
    else:
        axes = list(np.atleast_1d(np.asarray(ax, dtype=object)).ravel())
        if len(axes) != len(what):
            raise ValueError(f"{len(what)} panel(s) asked for, {len(axes)} Axes given")
        fig = axes[0].figure
    for name, a in zip(what, axes):
        DRAW[name](a, traj)
    return fig
