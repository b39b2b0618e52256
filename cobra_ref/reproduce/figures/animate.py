"""Animated GIFs of the box push, one per gait (``anim_<gait>.gif``).

Not a paper figure: a moving version of fig. 3 (the paper's "snapshots depicting simulated
forward box push") to check a run at a glance. Each frame is the 3-D rendering of
:func:`cobra_ref.figures.fig03_snapshots.draw_scene` (cylinders of every body posed by forward
kinematics, the box cube, its path on the 0.1 m ground grid). No ``analysis`` formula is plotted.

Frames are evenly spaced over the run, at most ``FPS`` per simulated second and at most
``MAX_FRAMES`` in all, so a short run plays in real time and a 10 s run has 60 frames (played
faster than real time); at 500 x 320 pixels a 60-frame GIF is about 0.6 MB.
"""

from __future__ import annotations

import os

import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter

from . import common
from .fig03_snapshots import draw_scene, scene_limits

FPS = 12
MAX_FRAMES = 60
SIZE_IN, GIF_DPI = (5.0, 3.2), 100


def frame_steps(traj, max_frames: int = MAX_FRAMES, fps: float = FPS) -> np.ndarray:
    """State indices of at most ``max_frames`` frames, evenly spaced from the first state to the
    last, at most ``fps`` frames per simulated second.

    Helper: subsampling of the trajectory for the GIF.
    """
    n = len(traj.q)
    duration = float(traj.t[n - 1] - traj.t[0]) if n else 0.0
    n_frames = min(max_frames, int(duration * fps) + 1, n)
    return np.unique(np.linspace(0, n - 1, n_frames).round().astype(int))


def animate_gait(model, gait: str, traj, path: str) -> str:
    """Write the GIF of one trajectory to ``path`` (atomically) and return ``path``.

    Helper: one ``FuncAnimation`` whose frames redraw the fig. 3 scene at the sampled steps.
    """
    steps = frame_steps(traj)
    lim = scene_limits(model, traj, steps)
    fig = common.new_figure(*SIZE_IN)
    fig.set_layout_engine("none")
    ax = fig.add_axes((0.0, 0.0, 1.0, 0.92), projection="3d")
    label = common.gait_label(gait, traj)

    def draw(k):
        ax.cla()
        draw_scene(ax, model, traj, int(k), lim)
        fig.suptitle(f"{label}, t = {traj.t[k]:.2f} s", fontsize=9, color=common.gait_color(gait))

    anim = FuncAnimation(fig, draw, frames=steps, init_func=lambda: None, cache_frame_data=False)
    common.atomic_write(path, lambda tmp: anim.save(tmp, writer=PillowWriter(fps=FPS), dpi=GIF_DPI))
    return path


@common.paper_style
def make(results: dict, out_dir: str, model) -> list[str]:
    """Write ``anim_<gait>.gif`` for every gait in ``results``; return their paths.

    Implements: an animated [COBRA] fig. 3 (the box push of each gait), drawn as in
    :mod:`cobra_ref.figures.fig03_snapshots`.
    """
    os.makedirs(out_dir, exist_ok=True)
    return [animate_gait(model, gait, traj, os.path.join(out_dir, f"anim_{gait}.gif"))
            for gait, traj in common.ordered(results) if len(traj.q)]


if __name__ == "__main__":
    common.main(make)
