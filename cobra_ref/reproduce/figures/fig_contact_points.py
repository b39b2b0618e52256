"""Figs. 4-5's contact points: where on the ground and where on the box's faces the contacts act.

The paper's figs. 4 and 5 speak of "the contact points" of the links with the ground and of the
box with the robot and the ground. Drawn from the contact log (``traj.contacts``: one row per
loaded contact and step, its world point ``contact_point``), one column per gait:

* top: the robot-ground contact points seen from above (world x, y, equal scale), coloured by
  body as in fig. 4 (``fig04_robot_contacts.link_colors``), and the box's path (black);
* bottom: the box's faces unfolded (``face_coordinates``): the four side faces in a row (-y, +x,
  +y, -x of the box's frame, height z up), the top face above the +x face and the bottom face
  below it; the robot-box contact points coloured by the link, the box-ground ones grey crosses
  (a point on an edge or a corner is drawn on the top or bottom face).

Every ``STRIDE``-th step is drawn (a 10 s run has tens of thousands of rows).
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Rectangle

from ...quaternion import quat_to_rot
from ..analysis import BOX_GROUND, ROBOT_BOX, ROBOT_GROUND
from . import common
from .fig04_robot_contacts import link_colors

STRIDE = 20  # draw the contacts of every STRIDE-th step
GROUND_MARK = "0.35"  # colour of the box-ground contacts' crosses
SIDES = ((1, -1.0), (0, 1.0), (1, 1.0), (0, -1.0))  # (axis, sign) of the side faces, left to right


def log_rows(traj, kind: int, stride: int = STRIDE) -> np.ndarray:
    """Indices of the contact log's rows of ``kind`` in every ``stride``-th step."""
    c = traj.contacts
    return np.flatnonzero((c["contact_kind"] == kind) & (c["contact_step"].astype(int) % stride == 0))


def in_box_frame(traj, rows: np.ndarray) -> np.ndarray:
    """(len(rows), 3) the contact points of ``rows`` in the box's frame at their step's start [m]."""
    c = traj.contacts
    steps = c["contact_step"][rows].astype(int)
    pose = traj.box_pose[steps]
    R = np.array([quat_to_rot(qt) for qt in pose[:, 3:]]) if len(rows) else np.zeros((0, 3, 3))
    return np.einsum("kji,kj->ki", R, c["contact_point"][rows] - pose[:, :3])


def side_offsets(half) -> list[float]:
    """Centres along the unfolded strip of the side faces ``SIDES``: each face as wide as the box
    edge along it, the faces side by side."""
    widths = [2.0 * half[1 - axis] for axis, _ in SIDES]
    return list(np.cumsum([0.0] + widths[:-1]) + 0.5 * (np.array(widths) - widths[0]))


def face_coordinates(p: np.ndarray, half) -> np.ndarray:
    """(n, 2) the points ``p`` (box frame, on its surface) on the unfolded box: a side face's
    point at (strip offset + its coordinate along the face, z); the top face attached above the
    +x face, the bottom face below it (the point at x = +half_x on the shared edge)."""
    half = np.asarray(half, dtype=float)
    offsets = side_offsets(half)
    # tangential coordinate along each side face, walking round the box anticlockwise from above
    along = {(1, -1.0): p[:, 0], (0, 1.0): p[:, 1], (1, 1.0): -p[:, 0], (0, -1.0): -p[:, 1]}
    ratio = np.abs(p) / half
    # a point within 1 % of an edge or corner (the box-ground contacts) goes to the top or bottom face
    ratio[:, 2] += 0.01
    face = np.argmax(ratio, axis=1)
    sign = np.sign(p[np.arange(len(p)), face])
    out = np.zeros((len(p), 2))
    for (axis, s), u0 in zip(SIDES, offsets):
        on = (face == axis) & (sign == s)
        out[on] = np.stack([u0 + along[(axis, s)][on], p[on, 2]], axis=1)
    x_face = offsets[1]
    for s in (1.0, -1.0):  # top (+z) and bottom (-z)
        on = (face == 2) & (sign == s)
        out[on] = np.stack([x_face + p[on, 1], s * (half[2] + half[0] - p[on, 0])], axis=1)
    return out


def draw_box_net(ax, half) -> None:
    """The outlines of the unfolded box's six faces, each named."""
    half = np.asarray(half, dtype=float)
    names = ("-y", "+x", "+y", "-x")
    for (axis, _), u0, name in zip(SIDES, side_offsets(half), names):
        w = half[1 - axis]
        ax.add_patch(Rectangle((u0 - w, -half[2]), 2 * w, 2 * half[2], fill=False, lw=0.6, ec="0.3"))
        ax.text(u0, 0.0, name, ha="center", va="center", fontsize=5.5, color="0.6", zorder=1)
    u0 = side_offsets(half)[1]
    for s, name in ((1.0, "top"), (-1.0, "bottom")):
        y0 = half[2] if s > 0 else -half[2] - 2 * half[0]
        ax.add_patch(Rectangle((u0 - half[1], y0), 2 * half[1], 2 * half[0], fill=False, lw=0.6, ec="0.3"))
        ax.text(u0, s * (half[2] + half[0]), name, ha="center", va="center", fontsize=5.5, color="0.6", zorder=1)
    ax.set_aspect("equal")
    ax.autoscale_view()


def plot_ground(ax, traj, colors: list, idx: list) -> None:
    """Robot-ground contact points (top view, world) coloured by body, and the box's path."""
    c, rows = traj.contacts, log_rows(traj, ROBOT_GROUND)
    body = c["contact_body"][rows].astype(int)
    point_color = {b: colors[j] for j, b in enumerate(idx)}
    if len(rows):
        ax.scatter(c["contact_point"][rows, 0], c["contact_point"][rows, 1], s=0.6, lw=0,
                   c=[point_color.get(b, "0.5") for b in body], rasterized=True)
    else:
        common.empty_panel(ax)
    ax.plot(traj.box_pose[:, 0], traj.box_pose[:, 1], color="k", lw=0.8)
    ax.set_aspect("equal", adjustable="datalim")


def plot_box(ax, model, traj, colors: list, idx: list) -> None:
    """Robot-box (by link colour) and box-ground (grey) contact points on the unfolded box."""
    half = model.boxes[0].half
    draw_box_net(ax, half)
    point_color = {b: colors[j] for j, b in enumerate(idx)}
    for kind in (BOX_GROUND, ROBOT_BOX):
        rows = log_rows(traj, kind)
        if not len(rows):
            continue
        uv = face_coordinates(in_box_frame(traj, rows), half)
        body = traj.contacts["contact_body"][rows].astype(int)
        if kind == BOX_GROUND:
            ax.scatter(uv[:, 0], uv[:, 1], s=8.0, marker="x", lw=0.5, c=GROUND_MARK, zorder=3, rasterized=True)
        else:
            ax.scatter(uv[:, 0], uv[:, 1], s=2.0, lw=0, c=[point_color.get(b, "0.5") for b in body], zorder=3,
                       rasterized=True)
    ax.set_xticks([])
    ax.set_yticks([])
    ax.grid(False)


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig_contact_points.png/.pdf``: per gait, the robot-ground contact points from above
    and the robot-box and box-ground contact points on the box's unfolded faces.

    Implements: the "contact points" of [COBRA] figs. 4 and 5, from the contact log.
    ``ensemble`` is accepted for a common signature and not drawn: the nominal runs only.
    """
    rows = common.ordered(results)
    bodies = common.robot_bodies(model)
    idx, colors = [i for _, i in bodies], link_colors(len(bodies))
    fig = common.new_figure(common.TWO_COLUMN, 3.6)
    axes = fig.subplots(2, max(len(rows), 1), squeeze=False, height_ratios=[1.6, 1.0])
    if not rows or common.box_body(model) is None:
        common.empty_panel(axes[0, 0], "no gait or no box to show")
        return common.save(fig, out_dir, "fig_contact_points")
    for c, (gait, traj) in enumerate(rows):
        plot_ground(axes[0, c], traj, colors, idx)
        plot_box(axes[1, c], model, traj, colors, idx)
        axes[0, c].set_title(common.gait_label(gait, traj), color=common.gait_color(gait), loc="left")
        axes[0, c].set_xlabel("x [m]")
    axes[0, 0].set_ylabel("robot-ground, top view\ny [m]")
    axes[1, 0].set_ylabel("on the box's faces\n(box frame, unfolded)")
    handles = [Line2D([], [], marker="o", ls="none", ms=3, color=col, label=name)
               for (name, _), col in zip(bodies, colors)]
    handles += [Line2D([], [], marker="x", ls="none", ms=3, mew=0.6, color=GROUND_MARK, label="box-ground"),
                Line2D([], [], color="k", lw=0.8, label="box path")]
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles) // 2 + 1, handletextpad=0.2,
               columnspacing=0.8)
    fig.suptitle(f"Contact points (every {STRIDE}th step): on the ground, and on the box's faces")
    return common.save(fig, out_dir, "fig_contact_points")


if __name__ == "__main__":
    common.main(make)
