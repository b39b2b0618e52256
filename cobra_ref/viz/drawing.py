"""The matplotlib drawing of a run's scene in 3-D: COBRA's bodies, the box, its path and the ground.

Every body of COBRA is drawn as its cylinder (``model.visual_cylinders``: length, radius and axial
offset in the body frame, axis = body x), posed by ``kinematics.forward_kinematics(model, q)``; the
box is a cube of half sizes ``model.boxes[0].half`` posed by ``traj.box_pose``. The box's path so
far is a line on the ground, the ground a ``GRID`` grid. Geometry only: nothing from ``analysis``
is drawn.

Camera: elevation ``ELEV``, azimuth ``AZIM`` (matplotlib's view angles, degrees). A mirrored gait
(named "<gait>-mirror": <gait> reflected about the robot's start heading, the x axis, y -> -y) is
seen by the reflected camera, azimuth -``AZIM``, and lit by the reflected light (``is_mirrored``,
``draw_scene``): its pictures are then the mirror images of the original's.

Used by fig. 3 (:mod:`cobra_ref.reproduce.figures.fig03_snapshots`), the paper-figure GIFs
(:mod:`cobra_ref.reproduce.figures.animate`) and the renderer's fallback without MuJoCo
(:mod:`cobra_ref.viz.render`).
"""

from __future__ import annotations

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator
from mpl_toolkits.mplot3d.art3d import Line3DCollection, Poly3DCollection

from ..kinematics import forward_kinematics
from ..quaternion import quat_to_rot

GRID = 0.1  # ground grid spacing [m]
N_FACETS = 14  # facets around each cylinder (coarse is fine at paper size)
LIGHT = np.array([-0.3, -0.5, 1.0]) / np.linalg.norm([-0.3, -0.5, 1.0])
# zoomed 3-D scenes may overhang their axes: draw them whole, and keep them out of the layout
UNCLIPPED = {"clip_on": False, "in_layout": False}
HEAD_COLOR, LINK_COLORS, TAIL_COLOR, BOX_COLOR = "#8c2d2d", ("#4a6fa5", "#9db4d6"), "#555555", "#e0a040"
ELEV, AZIM = 35.0, -60.0  # the camera's view angles [deg]
MIRROR_SUFFIX = "-mirror"  # a gait named "<gait>-mirror" is <gait> reflected about the x axis (y -> -y)


def scene_figure(width: float, height: float) -> Figure:
    """A Figure of ``width`` x ``height`` inches with its own Agg canvas (no pyplot state) and no
    layout engine: the 3-D axes are placed by hand."""
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    fig.set_layout_engine("none")
    return fig


def cylinder_polygons(length: float, radius: float, x_offset: float, R: np.ndarray, p: np.ndarray,
                      n: int = N_FACETS) -> tuple[list, list]:
    """Side quads and the two end caps of a cylinder along the body x axis, in world coordinates.

    A point c in body coordinates is at p + R c in the world; the cylinder spans
    x in [x_offset - L/2, x_offset + L/2] with radius r. Returns (polygons, outward normals).
    """
    theta = np.linspace(0.0, 2 * np.pi, n + 1)
    ring = np.stack([np.zeros(n + 1), radius * np.cos(theta), radius * np.sin(theta)], axis=1)
    ends = [x_offset - length / 2, x_offset + length / 2]
    rings = [(ring + [x, 0.0, 0.0]) @ R.T + p for x in ends]
    radial = np.stack([np.zeros(n), np.cos(theta[:-1] + np.pi / n), np.sin(theta[:-1] + np.pi / n)], axis=1)
    polys = [np.array([rings[0][k], rings[0][k + 1], rings[1][k + 1], rings[1][k]]) for k in range(n)]
    normals = list(radial @ R.T)
    # end caps as fans of (degenerate) quads: every polygon has 4 vertices, so mplot3d does not
    # pad ragged polygons (its padding is uninitialised memory and raises overflow warnings)
    for ring, sign in zip(rings, (-1.0, 1.0)):
        centre = ring[:-1].mean(axis=0)
        polys += [np.array([centre, ring[k], ring[k + 1], centre]) for k in range(n)]
        normals += [sign * R[:, 0]] * n
    return polys, normals


def cube_polygons(half: np.ndarray, R: np.ndarray, p: np.ndarray) -> tuple[list, list]:
    """The six faces of a box with half sizes ``half``, posed by (R, p), and their outward normals:
    corners p + R (s * half) for the sign patterns s in {-1, 1}^3."""
    polys, normals = [], []
    for axis in range(3):
        u, v = [a for a in range(3) if a != axis]
        for side in (-1.0, 1.0):
            corners = []
            for su, sv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                s = np.zeros(3)
                s[axis], s[u], s[v] = side, su, sv
                corners.append(p + R @ (s * half))
            polys.append(np.array(corners))
            normals.append(side * R[:, axis])
    return polys, normals


def body_color(model, i: int) -> str:
    """The colour of body i: head dark red, body links alternating two blues, tail grey, anything
    else (box) orange."""
    name = model.body_names[i]
    if name == "head":
        return HEAD_COLOR
    if name == "tail":
        return TAIL_COLOR
    return LINK_COLORS[i % 2] if name.startswith("L") else BOX_COLOR


def shade(color: str, normals: list, light: np.ndarray = LIGHT) -> np.ndarray:
    """(n, 4) RGBA of faces lit by a directional light l: k = 0.45 + 0.55 max(0, n . l) (Lambert
    shading, so the round cylinders read as round)."""
    rgba = np.array(to_rgba(color))
    k = 0.45 + 0.55 * np.clip(np.asarray(normals) @ light, 0.0, 1.0)
    out = np.tile(rgba, (len(normals), 1))
    out[:, :3] *= k[:, None]
    return out


def scene_polygons(model, q: np.ndarray, box_pose: np.ndarray, light: np.ndarray = LIGHT) -> tuple[list, np.ndarray]:
    """All faces of the robot's cylinders and of the box at one instant, with their colours
    shaded by the light direction ``light``, in one list, so that matplotlib depth-sorts robot and
    box faces together.
    """
    kin = forward_kinematics(model, q)
    polys, colors = [], []
    for i, cyl in enumerate(getattr(model, "visual_cylinders", ())):
        if cyl is None:
            continue
        p_i, n_i = cylinder_polygons(*cyl, kin.R[i], kin.o[i])
        polys += p_i
        colors.append(shade(body_color(model, i), n_i, light))
    half = model.boxes[0].half if model.boxes else np.full(3, 0.05)
    p_b, n_b = cube_polygons(np.asarray(half), quat_to_rot(box_pose[3:]), box_pose[:3])
    polys += p_b
    colors.append(shade(BOX_COLOR, n_b, light))
    return polys, np.concatenate(colors)


def scene_limits(model, traj, steps) -> np.ndarray:
    """(3, 2) axis limits [m] that hold the robot and the box at all ``steps`` (plus a margin):
    fixed limits per gait, so every snapshot (and every GIF frame) has the same scale."""
    pts = [traj.box_pose[:, :3]]
    for k in steps:
        pts += scene_polygons(model, traj.q[k], traj.box_pose[k])[0]
    pts = np.concatenate(pts)
    lo, hi = pts.min(axis=0) - 0.05, pts.max(axis=0) + 0.05
    lo[2], hi[2] = 0.0, max(hi[2], 0.25)
    return np.stack([lo, hi], axis=1)


def ground_grid(lim: np.ndarray) -> Line3DCollection:
    """Grey lines every ``GRID`` metres on the ground plane z = 0 inside the limits (the spacing
    gives the scale)."""
    xs = np.arange(np.floor(lim[0, 0] / GRID), np.ceil(lim[0, 1] / GRID) + 1) * GRID
    ys = np.arange(np.floor(lim[1, 0] / GRID), np.ceil(lim[1, 1] / GRID) + 1) * GRID
    segs = [[(x, ys[0], 0), (x, ys[-1], 0)] for x in xs] + [[(xs[0], y, 0), (xs[-1], y, 0)] for y in ys]
    return Line3DCollection(segs, colors="0.8", linewidths=0.4, zorder=0, **UNCLIPPED)


def is_mirrored(gait: str) -> bool:
    """True for a gait named "<gait>-mirror" (``MIRROR_SUFFIX``): <gait> reflected, y -> -y, which
    ``draw_scene`` shows with the reflected camera."""
    return gait.endswith(MIRROR_SUFFIX)


def draw_scene(ax, model, traj, k: int, lim: np.ndarray, axes_labels: bool = True, mirror: bool = False) -> None:
    """Draw the ground, the box's path up to step k, the box and the robot at step k on a 3-D axes.

    Equal scale on x, y, z (``set_box_aspect`` with the
    limits' extents, zoomed; ``UNCLIPPED`` so nothing is cut at the axes' edge); explicit z-orders
    (ground < path < bodies) because mplot3d sorts whole artists, while the faces inside the one
    body collection are depth-sorted. The camera: elevation ``ELEV``, azimuth ``AZIM``; with
    ``mirror``, the reflection of camera and light about the x-z plane (y -> -y): the direction
    (cos el cos az, cos el sin az, sin el) becomes the one of azimuth -az, so a mirrored run looks
    like the mirror image of the original.
    """
    light = LIGHT * np.array([1.0, -1.0, 1.0]) if mirror else LIGHT
    ax.computed_zorder = False
    ax.set(xlim=lim[0], ylim=lim[1], zlim=lim[2])
    ax.set_autoscale_on(False)
    ax.add_collection3d(ground_grid(lim), autolim=False)
    path = traj.box_pose[: k + 1]
    ax.plot(path[:, 0], path[:, 1], np.full(len(path), 1e-3), color="k", lw=0.9, zorder=1, **UNCLIPPED)
    polys, colors = scene_polygons(model, traj.q[k], traj.box_pose[k], light)
    ax.add_collection3d(Poly3DCollection(polys, facecolors=colors, edgecolors="none", zorder=2, **UNCLIPPED),
                        autolim=False)
    ax.set_box_aspect(tuple(lim[:, 1] - lim[:, 0]), zoom=1.3)
    ax.view_init(elev=ELEV, azim=-AZIM if mirror else AZIM)
    style_3d_axes(ax, axes_labels)


def style_3d_axes(ax, labels: bool) -> None:
    """Transparent panes, few ticks, and the unit on each labelled axis: small 3-D panels stay
    legible."""
    for axis in (ax.xaxis, ax.yaxis, ax.zaxis):
        axis.set_pane_color((1, 1, 1, 0))
        axis.set_major_locator(MaxNLocator(3))
    ax.grid(False)
    ax.tick_params(labelsize=5, pad=-3)
    if labels:
        ax.set_xlabel("x [m]", labelpad=-9, fontsize=6)
        ax.set_ylabel("y [m]", labelpad=-9, fontsize=6)
    ax.set_zticks([])  # the height is small; the ground grid and equal scale show it
