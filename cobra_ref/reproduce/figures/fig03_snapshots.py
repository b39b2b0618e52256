"""Fig. 3: snapshots of the box push for each gait, rendered in 3-D.

The paper's fig. 3 shows "snapshots depicting simulated forward box push utilizing various
gaits" (C, S, J and sidewinding; the J gait mirrored moves the box the other way). Here each row
is one gait (J-mirror included when it was run) and each column one instant (``N_INSTANTS``
evenly spaced over the run), drawn by :mod:`cobra_ref.viz.drawing`: every body as its cylinder
posed by forward kinematics, the box as a cube, the box's path so far on the ground, the ground a
``GRID`` grid; a mirrored gait (J-mirror) seen by the reflected camera, so its panels are the
mirror images of the J panels. Nothing from ``analysis`` is plotted: this is geometry only.
"""

from __future__ import annotations

import numpy as np

from ...viz.drawing import GRID, draw_scene, is_mirrored, scene_limits
from . import common

N_INSTANTS = 4


def snapshot_steps(traj, n: int = N_INSTANTS) -> np.ndarray:
    """``n`` evenly spaced state indices from the first to the last state: the snapshot instants."""
    return np.unique(np.linspace(0, len(traj.q) - 1, n).round().astype(int))


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None) -> list[str]:
    """Write ``fig03_snapshots.png/.pdf``: one row per gait, one 3-D snapshot per column, a
    mirrored gait seen by the reflected camera.

    Implements: [COBRA] fig. 3 (snapshots of the forward box push for each gait). ``ensemble``
    is accepted for a common signature and not drawn: the nominal runs only.
    """
    rows = common.ordered(results)
    # 0.5 in beyond the rows: the title, and the last row's axis labels, which the layout does not
    # see on 3-D axes
    fig = common.new_figure(common.TWO_COLUMN, 1.55 * max(len(rows), 1) + 0.5)
    if not rows:
        common.empty_panel(fig.add_subplot(), "no gait to show")
        return common.save(fig, out_dir, "fig03_snapshots")
    for r, (gait, traj) in enumerate(rows):
        steps = snapshot_steps(traj)
        lim = scene_limits(model, traj, steps)
        for c, k in enumerate(steps):
            ax = fig.add_subplot(len(rows), N_INSTANTS, r * N_INSTANTS + c + 1, projection="3d")
            draw_scene(ax, model, traj, int(k), lim, axes_labels=(c == 0), mirror=is_mirrored(gait))
            ax.set_title(f"{common.gait_label(gait, traj)}, t = {traj.t[k]:.2f} s", pad=-2,
                         color=common.gait_color(gait))
    fig.suptitle(f"Box push snapshots (ground grid {GRID:g} m; black line: box path)")
    return common.save(fig, out_dir, "fig03_snapshots")


if __name__ == "__main__":
    common.main(make)
