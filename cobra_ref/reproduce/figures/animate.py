"""Animated GIFs of the box push, one per gait (``anim_<gait>.gif``), and a note of how each was made.

Not a paper figure: a moving version of fig. 3 (the paper's "snapshots depicting simulated
forward box push") to check a run at a glance. No ``analysis`` formula is plotted.

Two renderers, chosen per call of ``make``:

* MuJoCo (:func:`cobra_ref.viz.render.render_gif`), when mujoco is installed and an OpenGL
  backend renders offscreen (``render.choose_gl``): the bodies, the box, its path and the
  contact-force arrows of the run's log, from a camera that follows the robot, the gait's name
  and the time stamped on each frame. ``GIF_FPS`` frames per second of GIF, ``GIF_SIZE`` pixels,
  without multisampling (``antialias=False``: faster in a software OpenGL), and a run longer
  than ``GIF_SECONDS`` plays faster than real time, in ``GIF_SECONDS`` (``playback_speed``): a
  10 s run is 51 frames.
* matplotlib, otherwise (or if the MuJoCo rendering fails): each frame the 3-D drawing of
  :func:`cobra_ref.viz.drawing.draw_scene` (cylinders of every body posed by forward
  kinematics, the box cube, its path on the 0.1 m ground grid; the mirrored gait seen by the
  reflected camera), evenly spaced over the run, at most ``FPS`` per simulated second and at
  most ``MAX_FRAMES`` in all (``frame_steps``), so a short run plays in real time and a 10 s run
  has 60 frames.

Which renderer made each GIF (and why not MuJoCo, if it could not) is said on stderr, one line
per GIF, and written to ``animations.json`` beside the GIFs (``NOTE``): {GIF file name: {renderer,
gl, fallback_reason, frames, fps, speed, width, height, seconds, bytes}}.
"""

from __future__ import annotations

import json
import os
import sys
import time

import numpy as np
from matplotlib.animation import FuncAnimation, PillowWriter

from ...infra.output import OutputError, write_text
from ...viz.drawing import draw_scene, is_mirrored, scene_limits
from . import common

# the matplotlib GIFs
FPS = 12
MAX_FRAMES = 60
SIZE_IN, GIF_DPI = (5.0, 3.2), 100
# the MuJoCo GIFs
GIF_FPS = 10
GIF_SIZE = (480, 320)  # width, height [px]
GIF_SECONDS = 5.0  # a longer run plays faster than real time, in this many seconds
NOTE = "animations.json"
NOTE_KEYS = ("renderer", "gl", "fallback_reason", "frames", "fps", "speed", "width", "height", "seconds", "bytes")


def frame_steps(traj, max_frames: int = MAX_FRAMES, fps: float = FPS) -> np.ndarray:
    """State indices of at most ``max_frames`` frames, evenly spaced from the first state to the
    last, at most ``fps`` frames per simulated second.

    Subsampling of the trajectory for the matplotlib GIF.
    """
    n = len(traj.q)
    duration = float(traj.t[n - 1] - traj.t[0]) if n else 0.0
    n_frames = min(max_frames, int(duration * fps) + 1, n)
    return np.unique(np.linspace(0, n - 1, n_frames).round().astype(int))


def playback_speed(traj) -> float:
    """Simulated seconds per second of GIF: 1 (real time) up to a ``GIF_SECONDS`` run, else
    duration / ``GIF_SECONDS`` (a 10 s run plays twice as fast, in 5 s).
    """
    return max(1.0, traj.duration / GIF_SECONDS)


def animate_gait(model, gait: str, traj, path: str) -> str:
    """Write the matplotlib GIF of one trajectory to ``path`` (atomically) and return ``path``.

    One ``FuncAnimation`` whose frames redraw the fig. 3 scene at the sampled steps.
    """
    steps = frame_steps(traj)
    lim = scene_limits(model, traj, steps)
    fig = common.new_figure(*SIZE_IN)
    fig.set_layout_engine("none")
    ax = fig.add_axes((0.0, 0.0, 1.0, 0.92), projection="3d")
    label = common.gait_label(gait, traj)

    def draw(k):
        ax.cla()
        draw_scene(ax, model, traj, int(k), lim, mirror=is_mirrored(gait))
        fig.suptitle(f"{label}, t = {traj.t[k]:.2f} s", fontsize=9, color=common.gait_color(gait))

    anim = FuncAnimation(fig, draw, frames=steps, init_func=lambda: None, cache_frame_data=False)
    common.atomic_write(path, lambda tmp: anim.save(tmp, writer=PillowWriter(fps=FPS), dpi=GIF_DPI))
    return path


def mujoco_problem() -> str | None:
    """Why the MuJoCo renderer cannot be used here (mujoco missing, no OpenGL backend renders),
    or None when it can.

    The choice of renderer (``render.choose_gl``, which probes the backends once per process, each
    in a short-lived subprocess).
    """
    try:
        from ...viz import gl, render
    except ImportError as exc:
        return f"the MuJoCo renderer cannot be imported ({exc})"
    choice = render.choose_gl()
    return None if choice["gl"] is not None else gl.no_gl_reason(choice)


def mujoco_gif(gait: str, traj, path: str) -> dict:
    """Render the GIF of one trajectory with MuJoCo; return ``render_gif``'s record.

    ``GIF_FPS``, ``GIF_SIZE``, ``playback_speed``, no multisampling, the gait's name on every frame;
    RenderError if MuJoCo cannot render.
    """
    from ...viz import render

    video = render.VideoSettings(fps=GIF_FPS, width=GIF_SIZE[0], height=GIF_SIZE[1], speed=playback_speed(traj),
                                 title=common.gait_label(gait, traj), antialias=False)
    return render.render_gif(traj, path, video, renderer="mujoco")


def matplotlib_gif(model, gait: str, traj, path: str, reason: str | None) -> dict:
    """Write the matplotlib GIF of one trajectory; return a record like ``render_gif``'s.

    The fallback renderer (``reason``: why not MuJoCo).
    """
    start = time.perf_counter()
    animate_gait(model, gait, traj, path)
    n_frames = len(frame_steps(traj))
    # the frames span the run and play at FPS: (n_frames - 1) / FPS seconds of GIF
    speed = traj.duration * FPS / max(n_frames - 1, 1)
    return {"renderer": "matplotlib", "gl": None, "fallback_reason": reason, "frames": n_frames, "fps": float(FPS),
            "speed": round(speed, 3), "width": int(SIZE_IN[0] * GIF_DPI), "height": int(SIZE_IN[1] * GIF_DPI),
            "seconds": round(time.perf_counter() - start, 3)}


def animate_one(model, gait: str, traj, path: str, problem: str | None) -> dict:
    """Write ``path`` with MuJoCo when ``problem`` is None, else (or when MuJoCo fails) with
    matplotlib; return the note's record of it.
    """
    if problem is None:
        try:
            record = mujoco_gif(gait, traj, path)
        except OutputError:  # the GIF cannot be written (a full disk): no other renderer would write it
            raise
        except Exception as exc:  # RenderError, or an OpenGL failure mid-way: the GIF is still made
            problem = f"MuJoCo rendering failed: {type(exc).__name__}: {exc}"
    if problem is not None:
        record = matplotlib_gif(model, gait, traj, path, problem)
    record["bytes"] = os.path.getsize(path)
    return {k: record.get(k) for k in NOTE_KEYS}


def say(name: str, record: dict) -> None:
    """One line on stderr: which renderer made the GIF ``name``, its frames and time (and why not
    MuJoCo, for the fallback).
    """
    line = f"animate: {name}: {record['renderer']}, {record['frames']} frames, {record['seconds']:.1f} s"
    if record["renderer"] == "mujoco":
        line += f" (MUJOCO_GL={record['gl']})"
    elif record["fallback_reason"]:
        line += f" (MuJoCo not used: {record['fallback_reason']})"
    print(line, file=sys.stderr)


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``anim_<gait>.gif`` for every gait in ``results`` (MuJoCo's rendering if it works
    here, else matplotlib's) and the note ``animations.json``; return their paths, the note last.

    Implements: an animated [COBRA] fig. 3 (the box push of each gait); the module docstring
    says how each renderer frames it. ``ensemble`` is accepted for a common signature and not
    drawn: the nominal runs only.
    """
    os.makedirs(out_dir, exist_ok=True)
    runs = [(g, t) for g, t in common.ordered(results) if len(t.q)]
    problem = mujoco_problem() if runs else None
    paths, note = [], {}
    for gait, traj in runs:
        paths.append(os.path.join(out_dir, f"anim_{gait}.gif"))
        note[os.path.basename(paths[-1])] = animate_one(model, gait, traj, paths[-1], problem)
        say(os.path.basename(paths[-1]), note[os.path.basename(paths[-1])])
    write_text(os.path.join(out_dir, NOTE), json.dumps(note, indent=1) + "\n")
    return paths + [os.path.join(out_dir, NOTE)]


if __name__ == "__main__":
    common.main(make)
