"""Offscreen rendering of a saved run to a still (PNG), an animated GIF or an MP4 video: the job.

``cobra-ref render`` and :func:`render_gif` (for the figure command) check the request
(``check_request``), pick the frames' states (``frame_steps``), find where MuJoCo renders
(:mod:`cobra_ref.viz.gl`), draw the frames (:mod:`cobra_ref.viz.frames`: MuJoCo's offscreen
rendering, else the matplotlib drawing of :mod:`cobra_ref.viz.drawing`, and the result says why)
and write them (:mod:`cobra_ref.viz.encode`). If mujoco was imported in this process with a
backend that does not render, the frames are rendered in one child process (``python -c``)
started with the backend that does (``render_in_child``).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import asdict

import numpy as np

from . import scene
from .encode import RenderError, mp4_writer_problem, output_format, write_frames
from .frames import VideoSettings, matplotlib_frames, mujoco_frames, stamp, time_text
from .gl import choose_gl, no_gl_reason

GIF_MAX_FPS = 50  # browsers play GIF delays under 20 ms as 100 ms
MAX_SIZE = (1920, 1080)  # the scene's offscreen framebuffer
GIF_VIDEO = VideoSettings(fps=15.0, width=480, height=320)  # render_gif's default (its docstring)
CHILD = "import sys; from cobra_ref.viz.render import render_request; render_request(sys.argv[1])"
RENDERERS = ("auto", "mujoco", "matplotlib")

__all__ = ["GIF_VIDEO", "RenderError", "VideoSettings", "check_request", "frame_steps", "output_format",
           "render_file", "render_gif", "render_here", "render_in_child", "render_request"]


def frame_steps(traj, video: VideoSettings, at: float | None) -> np.ndarray:
    """State indices of the frames: the state nearest ``at`` (a still), else one per 1 / fps of
    video, ``video.speed`` simulated seconds per video second (:func:`cobra_ref.viz.scene.frame_times`)."""
    if at is not None:
        return scene.state_indices(traj, [traj.t[0] + at])
    return scene.state_indices(traj, scene.frame_times(traj, video.fps, video.speed))


def check_request(traj, path: str, video: VideoSettings, at) -> str:
    """Check every setting before a frame is rendered and return the output format; a RenderError
    names the problem."""
    fmt = output_format(path)
    for name, value in (("fps", video.fps), ("speed", video.speed), ("force scale", video.force_scale)):
        if not (np.isfinite(value) and value > 0):
            raise RenderError(f"{name} must be positive and finite, got {value}")
    for name, value, most in (("width", video.width, MAX_SIZE[0]), ("height", video.height, MAX_SIZE[1])):
        if int(value) != value or not 16 <= value <= most:
            raise RenderError(f"{name} must be a whole number of pixels from 16 to {most}, got {value}")
    if at is not None:
        if fmt != "png":
            raise RenderError(f"--at renders one still frame: write it to a .png, not a .{fmt}")
        if not (np.isfinite(at) and 0.0 <= at <= traj.duration + 1e-9):
            raise RenderError(f"--at {at} s is outside the run (0 to {traj.duration:g} s)")
    if fmt == "gif" and video.fps > GIF_MAX_FPS:
        raise RenderError(f"a GIF plays at most {GIF_MAX_FPS} frames per second (browsers slow faster GIFs down), "
                          f"got --fps {video.fps:g}")
    if fmt == "mp4":
        if video.width % 2 or video.height % 2:
            raise RenderError("MP4 (H.264, yuv420p) needs an even width and height, "
                              f"got {video.width} x {video.height}")
        problem = mp4_writer_problem()
        if problem:
            raise RenderError(problem)
    return fmt


def render_file(traj, path: str, video: VideoSettings = VideoSettings(), at: float | None = None,
                renderer: str = "auto", progress=None) -> dict:
    """Render a run to ``path`` (.png: the still at ``at`` seconds, default the last state; .gif or
    .mp4: the whole run at ``video.fps``, ``video.speed`` times real time) and return what was done:
    ``renderer`` ("mujoco" or "matplotlib"), ``gl`` and ``process`` (MuJoCo's OpenGL backend and
    where it ran), ``fallback_reason`` (why matplotlib), ``frames``, ``seconds`` (wall time),
    ``bytes``, ``camera`` (the first and last frame's free camera).

    ``renderer``: "auto" (MuJoCo if it renders here, else matplotlib), "mujoco" (RenderError if it
    cannot) or "matplotlib". ``video``: size, rate, speed, arrows, title, antialiasing
    (``VideoSettings``).
    """
    if renderer not in RENDERERS:
        raise RenderError(f"unknown renderer {renderer!r}: auto, mujoco or matplotlib")
    if at is None and output_format(path) == "png":
        at = traj.duration
    fmt = check_request(traj, path, video, at)
    steps = frame_steps(traj, video, at)
    info = {"out": path, "format": fmt, "renderer": renderer, "gl": None, "process": None, "fallback_reason": None,
            "frames": int(len(steps)), "width": int(video.width), "height": int(video.height),
            "fps": float(video.fps), "speed": float(video.speed)}
    if renderer != "matplotlib":
        choice = choose_gl()
        info.update(gl=choice["gl"], process=choice["process"])
        if choice["gl"] is None:
            if renderer == "mujoco":
                raise RenderError(no_gl_reason(choice))
            info["fallback_reason"] = no_gl_reason(choice)
        elif choice["process"] == "child":
            start = time.perf_counter()
            info.update(render_in_child(choice["gl"], traj, path, steps, video),
                        renderer="mujoco", seconds=round(time.perf_counter() - start, 3))
            return info
    used = "mujoco" if renderer != "matplotlib" and info["gl"] is not None else "matplotlib"
    start = time.perf_counter()
    info.update(render_here(traj, path, steps, video, used, progress))
    info.update(renderer=used, seconds=round(time.perf_counter() - start, 3))
    return info


def render_here(traj, path: str, steps, video: VideoSettings, renderer: str, progress=None) -> dict:
    """Render the frames ``steps`` in this process with ``renderer`` ("mujoco" or "matplotlib") and
    write them in the format of ``path``; return ``bytes`` and ``camera``. Called by
    :func:`render_file` directly, or in a child process by :func:`render_request`."""
    camera = None
    if renderer == "mujoco":
        m, d = scene.build_scene()
        if not video.antialias:
            m.vis.quality.offsamples = 0  # read when the renderer creates its offscreen buffers
        cam = scene.follow_camera(m, d, traj, steps, video.width, video.height)
        camera = {"lookat_first": cam["lookat"][0].tolist(), "lookat_last": cam["lookat"][-1].tolist(),
                  "distance": float(cam["distance"]), "azimuth": cam["azimuth"], "elevation": cam["elevation"]}
        raw = mujoco_frames(traj, steps, video, progress, (m, d), cam)
    else:
        raw = matplotlib_frames(traj, steps, video, progress)
    frames = (stamp(f, time_text(traj, int(k), video.title), video.force_scale) for f, k in zip(raw, steps))
    write_frames(path, output_format(path), frames, len(steps), video.fps)
    return {"bytes": os.path.getsize(path), "camera": camera}


def render_in_child(gl: str, traj, path: str, steps, video: VideoSettings) -> dict:
    """Run :func:`render_here` with MuJoCo in a fresh Python process whose ``MUJOCO_GL`` is ``gl``;
    return its record: rendering after mujoco was imported here with a backend that does not
    render. The run and the request go through a temporary directory; the child is ``python -c``
    (no re-import of the caller's main module)."""
    with tempfile.TemporaryDirectory(prefix="cobra_ref_render_") as tmp:
        run_path, request = os.path.join(tmp, "run.npz"), os.path.join(tmp, "request.json")
        traj.to_npz(run_path)
        with open(request, "w") as f:
            json.dump({"run": run_path, "path": os.path.abspath(path), "steps": [int(k) for k in steps],
                       "video": asdict(video)}, f)
        env = dict(os.environ, MUJOCO_GL=gl)
        env.pop("PYOPENGL_PLATFORM", None)
        child = subprocess.run([sys.executable, "-c", CHILD, request], env=env, capture_output=True, text=True)
    if child.returncode != 0:
        lines = child.stderr.strip().splitlines() or [f"exit code {child.returncode}"]
        raise RenderError(f"rendering in a child process with MUJOCO_GL={gl} failed: {lines[-1]}")
    return json.loads(child.stdout.strip().splitlines()[-1])


def render_request(request_path: str) -> None:
    """Render what a JSON request of :func:`render_in_child` asks and print the record as JSON: the
    child process's side of :func:`render_in_child`."""
    with open(request_path) as f:
        req = json.load(f)
    traj = scene.load_run(req["run"])
    record = render_here(traj, req["path"], np.array(req["steps"], dtype=int), VideoSettings(**req["video"]), "mujoco")
    print(json.dumps(record))


def render_gif(traj, path: str, video: VideoSettings = GIF_VIDEO, renderer: str = "auto") -> dict:
    """Write the GIF of a trajectory (MuJoCo's rendering, else matplotlib's) and return
    :func:`render_file`'s record (``renderer`` says which was used, ``fallback_reason`` why): the
    figure command's animations. The default ``GIF_VIDEO`` (15 fps, 480 x 320) keeps a 10 s run's
    GIF small enough to commit (docs/results.md, "Rendering a run")."""
    if output_format(path) != "gif":
        raise RenderError(f"render_gif writes a .gif, got {path}")
    return render_file(traj, path, video, renderer=renderer)
