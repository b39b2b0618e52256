"""Offscreen rendering of a saved run to a still (PNG), an animated GIF or an MP4 video.

Helper: ``cobra-ref render`` and :func:`render_gif` (for the figure command). Frames come from
MuJoCo's offscreen ``mujoco.Renderer`` on the scene of :mod:`cobra_ref.viz.scene`, with the
contact-force arrows and the box's path from the run's log and a camera that follows the robot
and keeps the box in view; the time stamp and the legend are drawn onto each frame with Pillow
(``mujoco.Renderer`` has no text overlay).

OpenGL backend: MuJoCo reads ``MUJOCO_GL`` once, when it is first imported. Before that import,
each candidate (``MUJOCO_GL`` if the user set it, then ``egl``, then ``osmesa``) is tried in a
short-lived subprocess (a backend that fails, or crashes, cannot harm this process) and the first
that renders is written to ``os.environ["MUJOCO_GL"]``. If mujoco was imported earlier in this
process with a backend that does not render (a test session, the figure command), the frames are
rendered in one child process (``python -c``) started with the backend that does. Without mujoco
or any backend, the frames are the 3-D drawing of the paper-figure GIFs
(:mod:`cobra_ref.reproduce.figures.animate`: its fixed view and limits) with the same arrows, and
the result says why.

Writers: PNG and GIF with Pillow (which matplotlib brings); MP4 with imageio and imageio-ffmpeg
(the optional extra ``pip install 'cobra-ref[video]'``). GIF frame delays are whole
centiseconds: they alternate (30, 40, 30, 30, 40, ... ms at 30 fps) so that the GIF plays in
real time. Shadows are off (a software OpenGL renders a frame three times faster without them).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from ..infra.output import atomic_write
from . import scene

FORMATS = ("png", "gif", "mp4")
GIF_MAX_FPS = 50  # browsers play GIF delays under 20 ms as 100 ms
MAX_SIZE = (1920, 1080)  # the scene's offscreen framebuffer
PROBE = """
import mujoco
m = mujoco.MjModel.from_xml_string('<mujoco><worldbody><geom type="sphere" size="1"/></worldbody></mujoco>')
d = mujoco.MjData(m)
mujoco.mj_forward(m, d)
with mujoco.Renderer(m, 16, 16) as r:
    r.update_scene(d)
    assert r.render().std() > 0, "blank image"
print("ok")
"""
CHILD = "import sys; from cobra_ref.viz.render import render_request; render_request(sys.argv[1])"
_choice: dict = {}


class RenderError(ValueError):
    """Bad input to the renderer, or a writer that is not installed (the message says which)."""


def output_format(path: str) -> str:
    """``png``, ``gif`` or ``mp4`` from the file name; RenderError for anything else.

    Helper: the renderer's writers.
    """
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    if ext not in FORMATS:
        raise RenderError(f"unknown output format {os.path.splitext(path)[1] or '(none)'!r} of {path}: "
                          f"use .png (a still), .gif or .mp4")
    return ext


def mp4_writer_problem() -> str | None:
    """Why MP4 cannot be written here (imageio or its ffmpeg missing), or None.

    Helper: checked before any frame is rendered.
    """
    try:
        import imageio  # noqa: F401
        import imageio_ffmpeg

        imageio_ffmpeg.get_ffmpeg_exe()
    except Exception as exc:  # ImportError, or imageio-ffmpeg without its ffmpeg binary
        return (f"MP4 needs imageio and imageio-ffmpeg ({type(exc).__name__}: {exc}); install the optional "
                f"extra: pip install 'cobra-ref[video]', or write a .gif")
    return None


def gl_candidates() -> list[str]:
    """The ``MUJOCO_GL`` values to try, in order: the user's own, then egl and osmesa (Linux), or
    MuJoCo's platform default elsewhere ("").

    Helper: backend detection.
    """
    own = os.environ.get("MUJOCO_GL", "").strip().lower()
    tried = [own] if own else []
    defaults = ["egl", "osmesa"] if sys.platform.startswith("linux") else [""]
    return tried + [name for name in defaults if name not in tried]


def probe_gl(name: str, timeout: float = 120.0) -> str:
    """Render a 16 x 16 image in a subprocess with ``MUJOCO_GL=name``; "" if it worked, else the
    reason (the last line of its error).

    Helper: backend detection that cannot crash this process.
    """
    env = dict(os.environ)
    env.pop("PYOPENGL_PLATFORM", None)  # mujoco's egl and osmesa modules set it to match
    if name:
        env["MUJOCO_GL"] = name
    else:
        env.pop("MUJOCO_GL", None)
    try:
        run = subprocess.run([sys.executable, "-c", PROBE], env=env, capture_output=True, text=True,
                             timeout=timeout)
    except subprocess.TimeoutExpired:
        return f"no answer within {timeout:g} s"
    if run.returncode == 0 and run.stdout.strip().endswith("ok"):
        return ""
    lines = [line for line in (run.stderr or run.stdout).strip().splitlines() if line.strip()]
    return lines[-1].strip() if lines else f"exit code {run.returncode}"


def imported_gl() -> str:
    """The ``MUJOCO_GL`` value mujoco was imported with in this process ("" = platform default).

    Helper: backend detection after mujoco's import.
    """
    try:
        from mujoco.rendering.classic import gl_context
    except ImportError:
        return os.environ.get("MUJOCO_GL", "")
    return getattr(gl_context, "_MUJOCO_GL", os.environ.get("MUJOCO_GL", ""))


def renders_here() -> str:
    """Try a 16 x 16 offscreen render in this process (mujoco already imported): "" if it worked,
    else the reason.

    Helper: backend detection after mujoco's import.
    """
    import warnings

    import mujoco

    try:
        m = mujoco.MjModel.from_xml_string(
            '<mujoco><worldbody><geom type="sphere" size="1"/></worldbody></mujoco>')
        d = mujoco.MjData(m)
        mujoco.mj_forward(m, d)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # glfw warns about a missing display before it fails
            with mujoco.Renderer(m, 16, 16) as r:
                r.update_scene(d)
                return "" if r.render().std() > 0 else "blank image"
    except Exception as exc:
        return f"{type(exc).__name__}: {exc}".splitlines()[0]


def choose_gl(refresh: bool = False) -> dict:
    """Find an OpenGL backend MuJoCo renders with: ``gl`` (the ``MUJOCO_GL`` value, None if none
    works), ``process`` ("this" or "child": where the frames are rendered), ``tried`` (each
    candidate's failure, "" for the one that worked).

    Helper: backend detection (module docstring); the answer is kept for the process.
    """
    if _choice and not refresh:
        return dict(_choice)
    try:
        import importlib.util

        has_mujoco = importlib.util.find_spec("mujoco") is not None
    except (ImportError, ValueError):
        has_mujoco = False
    tried: dict = {}
    result = {"gl": None, "process": None, "tried": tried}
    if not has_mujoco:
        tried["mujoco"] = "mujoco is not installed (pip install mujoco)"
    elif "mujoco" not in sys.modules:
        for name in gl_candidates():
            tried[name or "default"] = probe_gl(name)
            if not tried[name or "default"]:
                if name:
                    os.environ["MUJOCO_GL"] = name
                result.update(gl=name or "default", process="this")
                break
    else:
        here = imported_gl()
        tried[f"{here or 'default'} (imported)"] = renders_here()
        if not tried[f"{here or 'default'} (imported)"]:
            result.update(gl=here or "default", process="this")
        else:
            for name in [n for n in gl_candidates() if n and n != here]:
                tried[name] = probe_gl(name)
                if not tried[name]:
                    result.update(gl=name, process="child")
                    break
    _choice.clear()
    _choice.update(result)
    return dict(result)


def render_in_child(gl: str, traj, path: str, fmt: str, steps, fps: float, width: int, height: int,
                    force_scale: float, title: str = "", antialias: bool = True) -> dict:
    """Run :func:`render_here` with MuJoCo in a fresh Python process whose ``MUJOCO_GL`` is ``gl``;
    return its record.

    Helper: rendering after mujoco was imported here with a backend that does not render. The run
    and the request go through a temporary directory; the child is ``python -c`` (no re-import of
    the caller's main module).
    """
    with tempfile.TemporaryDirectory(prefix="cobra_ref_render_") as tmp:
        run_path, request = os.path.join(tmp, "run.npz"), os.path.join(tmp, "request.json")
        traj.to_npz(run_path)
        with open(request, "w") as f:
            json.dump({"run": run_path, "path": os.path.abspath(path), "fmt": fmt,
                       "steps": [int(k) for k in steps], "fps": fps, "width": width, "height": height,
                       "force_scale": force_scale, "title": title, "antialias": antialias}, f)
        env = dict(os.environ, MUJOCO_GL=gl)
        env.pop("PYOPENGL_PLATFORM", None)
        child = subprocess.run([sys.executable, "-c", CHILD, request], env=env, capture_output=True, text=True)
    if child.returncode != 0:
        lines = child.stderr.strip().splitlines() or [f"exit code {child.returncode}"]
        raise RenderError(f"rendering in a child process with MUJOCO_GL={gl} failed: {lines[-1]}")
    return json.loads(child.stdout.strip().splitlines()[-1])


def render_request(request_path: str) -> None:
    """Render what a JSON request of :func:`render_in_child` asks, print the record as JSON.

    Helper: the child process's side of :func:`render_in_child`.
    """
    with open(request_path) as f:
        req = json.load(f)
    traj = scene.load_run(req["run"])
    record = render_here(traj, req["path"], req["fmt"], np.array(req["steps"], dtype=int), req["fps"], req["width"],
                         req["height"], req["force_scale"], "mujoco", title=req.get("title", ""),
                         antialias=req.get("antialias", True))
    print(json.dumps(record))


# ------------------------------------------------------------------------------ frames


def stamp(frame: np.ndarray, text: str, force_scale: float) -> np.ndarray:
    """The frame with the time stamp ``text`` (top left) and the arrows' legend (bottom left).

    Helper: Pillow text on every frame of both renderers.
    """
    from PIL import Image, ImageDraw, ImageFont

    img = Image.fromarray(np.ascontiguousarray(frame[..., :3]))
    draw = ImageDraw.Draw(img)
    size = max(10, img.height // 28)
    try:
        font = ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: one bitmap size
        font = ImageFont.load_default()
    pad = max(3, size // 3)
    box = draw.textbbox((pad, pad), text, font=font)
    draw.rectangle((box[0] - pad, box[1] - pad, box[2] + pad, box[3] + pad), fill=(255, 255, 255))
    draw.text((pad, pad), text, fill=(0, 0, 0), font=font)
    small = ImageFont.load_default(size=max(9, int(size * 0.75))) if size > 10 else font
    parts = [(f"arrows: contact force, {100 * force_scale:g} cm per N:", (0, 0, 0))] + [
        (name, tuple(int(255 * c) for c in scene.KIND_RGBA[i, :3])) for i, name in enumerate(scene.KIND_NAMES)]
    x, y = pad, img.height - pad - (small.getbbox("Ag")[3] if hasattr(small, "getbbox") else size)
    for part, color in parts:
        draw.text((x, y), part, fill=color, font=small)
        x = draw.textbbox((x, y), part + "  ", font=small)[2]
    return np.asarray(img)


def time_text(traj, k: int, title: str = "") -> str:
    """``t = 1.234 s / 10.000 s`` for state k, after ``title`` (e.g. the gait's name) if given.

    Helper: the time stamp.
    """
    text = f"t = {traj.t[k] - traj.t[0]:.3f} s / {traj.duration:.3f} s"
    return f"{title}   {text}" if title else text


def mujoco_frames(traj, steps, width: int, height: int, force_scale: float = scene.FORCE_SCALE, progress=None,
                  scene_md=None, camera=None):
    """Yield one RGB frame (height, width, 3) per state index in ``steps``, rendered offscreen by
    MuJoCo with the markers of :func:`cobra_ref.viz.scene.add_markers`, without text.

    Helper: the MuJoCo renderer (``MUJOCO_GL`` must be settled before: :func:`choose_gl`).
    ``scene_md`` = (MjModel, MjData) and ``camera`` (:func:`cobra_ref.viz.scene.follow_camera`)
    are built when not given.
    """
    import mujoco

    m, d = scene_md or scene.build_scene()
    camera = camera or scene.follow_camera(m, d, traj, steps, width, height)
    renderer = mujoco.Renderer(m, height, width)
    # shadows triple the time of a frame in a software OpenGL (measured with Mesa's llvmpipe:
    # 81 ms without, 233 ms with, 640 x 480); the transparent bodies and the grid give the depth
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False
    try:
        for i, k in enumerate(steps):
            scene.set_state(m, d, traj, int(k))
            renderer.update_scene(d, scene.make_camera(camera, i))
            scene.add_markers(renderer.scene, traj, int(k), force_scale)
            yield renderer.render()
            if progress:
                progress(i + 1, len(steps))
    finally:
        renderer.close()


def matplotlib_frames(traj, steps, width: int, height: int, force_scale: float = scene.FORCE_SCALE, progress=None):
    """Yield one RGB frame per state index in ``steps``: the 3-D scene of the paper-figure GIFs
    (``animate.draw_scene``, fixed limits from ``animate.scene_limits``) with the contact-force
    arrows as a quiver.

    Helper: the renderer's fallback without MuJoCo or OpenGL.
    """
    from ..reproduce.figures import animate

    model = scene.cobra_model()
    lim = animate.scene_limits(model, traj, steps)
    dpi = 100
    fig = animate.common.new_figure(width / dpi, height / dpi)
    fig.set_layout_engine("none")
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0), projection="3d")
    for i, k in enumerate(steps):
        ax.cla()
        animate.draw_scene(ax, model, traj, int(k), lim)
        arrows = scene.contact_arrows(traj, int(k))
        if len(arrows["points"]):
            p, f = arrows["points"], force_scale * arrows["forces"]
            ax.quiver(p[:, 0], p[:, 1], p[:, 2], f[:, 0], f[:, 1], f[:, 2], colors=scene.KIND_RGBA[arrows["kinds"]],
                      linewidths=0.8, zorder=3)
        fig.canvas.draw()
        yield np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
        if progress:
            progress(i + 1, len(steps))


# ------------------------------------------------------------------------------ writers


def gif_durations(n: int, fps: float) -> list[int]:
    """Per-frame delays [ms] in whole centiseconds whose running sum follows frame j at j / fps.

    Helper: the GIF writer (30 fps: 30, 40, 30, 30, 40, ... ms, 33.3 ms on average).
    """
    ends = np.round(100.0 * np.arange(1, n + 1) / fps).astype(int)
    return [int(10 * c) for c in np.diff(np.concatenate([[0], ends]))]


def write_png(path: str, frame: np.ndarray) -> None:
    """One frame as PNG, atomically.

    Helper: the still (``--at``).
    """
    from PIL import Image

    atomic_write(path, lambda tmp: Image.fromarray(frame).save(tmp, format="PNG"))


def write_gif(path: str, frames, n: int, fps: float) -> None:
    """``n`` frames (an iterable) as a looping GIF playing at ``fps``, atomically.

    Helper: GIF output with Pillow. One palette for every frame, without dithering: 255 colours
    taken from the first frame and the arrows' colours (the scene's colours do not change), so a
    later frame's pixels map to the same entries and compress better (measured: 30 % smaller and
    five times faster to encode than a palette per frame).
    """
    from PIL import Image

    it = iter(frames)
    first = np.asarray(next(it))
    swatch = np.repeat(np.round(255 * scene.KIND_RGBA[:, :3]).astype(np.uint8), 8, axis=0)
    source = np.vstack([first.reshape(-1, 3), swatch])[None]
    palette = Image.fromarray(source).quantize(colors=255, dither=Image.Dither.NONE)

    def indexed(frame):
        return Image.fromarray(np.asarray(frame)).quantize(palette=palette, dither=Image.Dither.NONE)

    head = indexed(first)
    rest = (indexed(f) for f in it)
    atomic_write(path, lambda tmp: head.save(tmp, format="GIF", save_all=True, append_images=rest,
                                             duration=gif_durations(n, fps), loop=0))


def write_mp4(path: str, frames, fps: float) -> None:
    """Frames as an H.264 MP4 (yuv420p, playable everywhere) at ``fps``, atomically.

    Helper: MP4 output with imageio-ffmpeg (the optional extra ``video``).
    """
    import imageio.v2 as imageio

    def write(tmp):
        with imageio.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264", pixelformat="yuv420p",
                                macro_block_size=2, ffmpeg_log_level="error") as w:
            for f in frames:
                w.append_data(f)

    atomic_write(path, write)


# ------------------------------------------------------------------------------ the job


def frame_steps(traj, fps: float, speed: float, at: float | None) -> np.ndarray:
    """State indices of the frames: the state nearest ``at`` (a still), else one per 1 / fps of
    video, ``speed`` simulated seconds per video second.

    Helper: the renderer's frame sampling (:func:`cobra_ref.viz.scene.frame_times`).
    """
    if at is not None:
        return scene.state_indices(traj, [traj.t[0] + at])
    return scene.state_indices(traj, scene.frame_times(traj, fps, speed))


def check_request(traj, path: str, fps: float, width: int, height: int, at, speed: float, force_scale: float) -> str:
    """Check every setting before a frame is rendered; return the output format.

    Helper: bad input gives a RenderError that names the problem.
    """
    fmt = output_format(path)
    for name, value in (("fps", fps), ("speed", speed), ("force scale", force_scale)):
        if not (np.isfinite(value) and value > 0):
            raise RenderError(f"{name} must be positive and finite, got {value}")
    for name, value, most in (("width", width, MAX_SIZE[0]), ("height", height, MAX_SIZE[1])):
        if int(value) != value or not 16 <= value <= most:
            raise RenderError(f"{name} must be a whole number of pixels from 16 to {most}, got {value}")
    if at is not None:
        if fmt != "png":
            raise RenderError(f"--at renders one still frame: write it to a .png, not a .{fmt}")
        if not (np.isfinite(at) and 0.0 <= at <= traj.duration + 1e-9):
            raise RenderError(f"--at {at} s is outside the run (0 to {traj.duration:g} s)")
    if fmt == "gif" and fps > GIF_MAX_FPS:
        raise RenderError(f"a GIF plays at most {GIF_MAX_FPS} frames per second (browsers slow faster GIFs down), "
                          f"got --fps {fps:g}")
    if fmt == "mp4":
        if width % 2 or height % 2:
            raise RenderError(f"MP4 (H.264, yuv420p) needs an even width and height, got {width} x {height}")
        problem = mp4_writer_problem()
        if problem:
            raise RenderError(problem)
    return fmt


def render_file(traj, path: str, fps: float = 30.0, width: int = 640, height: int = 480, at: float | None = None,
                speed: float = 1.0, force_scale: float = scene.FORCE_SCALE, renderer: str = "auto",
                progress=None, title: str = "", antialias: bool = True) -> dict:
    """Render a run to ``path`` (.png: the still at ``at`` seconds, default the last state; .gif or
    .mp4: the whole run at ``fps``, ``speed`` times real time) and return what was done:
    ``renderer`` ("mujoco" or "matplotlib"), ``gl`` and ``process`` (MuJoCo's OpenGL backend and
    where it ran), ``fallback_reason`` (why matplotlib), ``frames``, ``seconds`` (wall time),
    ``bytes``, ``camera`` (the first and last frame's free camera).

    Helper: ``cobra-ref render`` and :func:`render_gif`. ``renderer``: "auto" (MuJoCo if it
    renders here, else matplotlib), "mujoco" (RenderError if it cannot) or "matplotlib".
    ``title``: text before each frame's time stamp. ``antialias``: MuJoCo's multisampling
    (``vis.quality.offsamples``); False renders without it, about 3 times faster in a software
    OpenGL (Mesa's llvmpipe, 480 x 320: 31 ms a frame instead of 84 ms) at the price of jagged
    edges.
    """
    if renderer not in ("auto", "mujoco", "matplotlib"):
        raise RenderError(f"unknown renderer {renderer!r}: auto, mujoco or matplotlib")
    if at is None and output_format(path) == "png":
        at = traj.duration
    fmt = check_request(traj, path, fps, width, height, at, speed, force_scale)
    steps = frame_steps(traj, fps, speed, at)
    info = {"out": path, "format": fmt, "renderer": renderer, "gl": None, "process": None, "fallback_reason": None,
            "frames": int(len(steps)), "width": int(width), "height": int(height), "fps": float(fps),
            "speed": float(speed)}
    if renderer != "matplotlib":
        choice = choose_gl()
        info.update(gl=choice["gl"], process=choice["process"])
        if choice["gl"] is None:
            tried = choice["tried"]
            reason = tried["mujoco"] if "mujoco" in tried else \
                "no OpenGL backend renders: " + "; ".join(f"{k}: {v}" for k, v in tried.items())
            if renderer == "mujoco":
                raise RenderError(reason)
            info["fallback_reason"] = reason
        elif choice["process"] == "child":
            start = time.perf_counter()
            info.update(render_in_child(choice["gl"], traj, path, fmt, steps, fps, width, height, force_scale,
                                        title, antialias),
                        renderer="mujoco", seconds=round(time.perf_counter() - start, 3))
            return info
    used = "mujoco" if renderer != "matplotlib" and info["gl"] is not None else "matplotlib"
    start = time.perf_counter()
    info.update(render_here(traj, path, fmt, steps, fps, width, height, force_scale, used, progress, title=title,
                            antialias=antialias))
    info.update(renderer=used, seconds=round(time.perf_counter() - start, 3))
    return info


def render_here(traj, path: str, fmt: str, steps, fps: float, width: int, height: int, force_scale: float,
                renderer: str, progress=None, title: str = "", antialias: bool = True) -> dict:
    """Render the frames ``steps`` in this process with ``renderer`` and write them; return
    ``bytes`` and ``camera``.

    Helper: :func:`render_file` (directly, or in a child process: :func:`render_request`);
    ``title`` and ``antialias`` as there.
    """
    camera = None
    if renderer == "mujoco":
        m, d = scene.build_scene()
        if not antialias:
            m.vis.quality.offsamples = 0  # read when the renderer creates its offscreen buffers
        cam = scene.follow_camera(m, d, traj, steps, width, height)
        camera = {"lookat_first": cam["lookat"][0].tolist(), "lookat_last": cam["lookat"][-1].tolist(),
                  "distance": float(cam["distance"]), "azimuth": cam["azimuth"], "elevation": cam["elevation"]}
        raw = mujoco_frames(traj, steps, width, height, force_scale, progress, (m, d), cam)
    else:
        raw = matplotlib_frames(traj, steps, width, height, force_scale, progress)
    frames = (stamp(f, time_text(traj, int(k), title), force_scale) for f, k in zip(raw, steps))
    if fmt == "png":
        write_png(path, next(frames))
        frames.close()
    elif fmt == "gif":
        write_gif(path, frames, len(steps), fps)
    else:
        write_mp4(path, frames, fps)
    return {"bytes": os.path.getsize(path), "camera": camera}


def render_gif(traj, path: str, fps: float = 15.0, width: int = 480, height: int = 320, speed: float = 1.0,
               force_scale: float = scene.FORCE_SCALE, renderer: str = "auto", title: str = "",
               antialias: bool = True) -> dict:
    """Write the GIF of a trajectory (MuJoCo's rendering, else matplotlib's) and return
    :func:`render_file`'s record (``renderer`` says which was used, ``fallback_reason`` why);
    ``title`` and ``antialias`` as in :func:`render_file`.

    Helper: the figure command's animations. The defaults keep a 10 s run's GIF small enough to
    commit: 151 frames, 2.9 MB (at 30 fps: 5.2 MB; measured on the 10 s C-gait push).
    """
    if output_format(path) != "gif":
        raise RenderError(f"render_gif writes a .gif, got {path}")
    return render_file(traj, path, fps=fps, width=width, height=height, speed=speed, force_scale=force_scale,
                       renderer=renderer, title=title, antialias=antialias)
