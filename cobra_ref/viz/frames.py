"""The frames of a rendered run: MuJoCo's offscreen rendering, or the matplotlib drawing, then the text.

MuJoCo's frames (``mujoco_frames``) show the scene of :mod:`cobra_ref.viz.scene` with the
contact-force arrows and the box's path from the run's log, from a camera that follows the robot
and keeps the box in view. Shadows are off (a software OpenGL renders much faster without them;
the transparent bodies and the grid give the depth). Without MuJoCo or OpenGL the frames are the
3-D drawing of :mod:`cobra_ref.viz.drawing` (``matplotlib_frames``: its fixed view and limits)
with the same arrows. The time stamp and the legend are drawn onto each frame with Pillow
(``stamp``; ``mujoco.Renderer`` has no text overlay).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import scene


@dataclass(frozen=True)
class VideoSettings:
    """How a run is rendered: ``fps`` frames per second of video, ``width`` x ``height`` pixels,
    ``speed`` simulated seconds per video second, ``force_scale`` [m/N] of the contact-force
    arrows, ``title`` (text before each frame's time stamp, e.g. the gait's name) and
    ``antialias`` (MuJoCo's multisampling, ``vis.quality.offsamples``; False renders faster in a
    software OpenGL, at the price of jagged edges). Checked by ``render.check_request``."""

    fps: float = 30.0
    width: int = 640
    height: int = 480
    speed: float = 1.0
    force_scale: float = scene.FORCE_SCALE
    title: str = ""
    antialias: bool = True


def stamp(frame: np.ndarray, text: str, force_scale: float) -> np.ndarray:
    """The frame with the time stamp ``text`` (top left) and the arrows' legend (bottom left), in
    Pillow's text, on the frames of both renderers."""
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
    """``t = 1.234 s / 10.000 s`` for state k, after ``title`` (e.g. the gait's name) if given."""
    text = f"t = {traj.t[k] - traj.t[0]:.3f} s / {traj.duration:.3f} s"
    return f"{title}   {text}" if title else text


def mujoco_frames(traj, steps, video: VideoSettings, progress=None, scene_md=None, camera=None):
    """Yield one RGB frame (height, width, 3) per state index in ``steps``, rendered offscreen by
    MuJoCo with the markers of :func:`cobra_ref.viz.scene.add_markers`, without text.

    ``MUJOCO_GL`` must be settled before (:func:`cobra_ref.viz.gl.choose_gl`). ``scene_md`` =
    (MjModel, MjData) and ``camera`` (:func:`cobra_ref.viz.scene.follow_camera`) are built when not
    given.
    """
    import mujoco

    m, d = scene_md or scene.build_scene()
    camera = camera or scene.follow_camera(m, d, traj, steps, video.width, video.height)
    renderer = mujoco.Renderer(m, video.height, video.width)
    renderer.scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = False  # module docstring
    try:
        for i, k in enumerate(steps):
            scene.set_state(m, d, traj, int(k))
            renderer.update_scene(d, scene.make_camera(camera, i))
            scene.add_markers(renderer.scene, traj, int(k), video.force_scale)
            yield renderer.render()
            if progress:
                progress(i + 1, len(steps))
    finally:
        renderer.close()


def matplotlib_frames(traj, steps, video: VideoSettings, progress=None):
    """Yield one RGB frame per state index in ``steps``: the 3-D scene of
    :func:`cobra_ref.viz.drawing.draw_scene` (fixed limits from ``drawing.scene_limits``) with the
    contact-force arrows as a quiver; the renderer's fallback without MuJoCo or OpenGL."""
    from . import drawing

    model = scene.cobra_model()
    lim = drawing.scene_limits(model, traj, steps)
    dpi = 100
    fig = drawing.scene_figure(video.width / dpi, video.height / dpi)
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0), projection="3d")
    for i, k in enumerate(steps):
        ax.cla()
        drawing.draw_scene(ax, model, traj, int(k), lim)
        arrows = scene.contact_arrows(traj, int(k))
        if len(arrows["points"]):
            p, f = arrows["points"], video.force_scale * arrows["forces"]
            ax.quiver(p[:, 0], p[:, 1], p[:, 2], f[:, 0], f[:, 1], f[:, 2], colors=scene.KIND_RGBA[arrows["kinds"]],
                      linewidths=0.8, zorder=3)
        fig.canvas.draw()
        yield np.asarray(fig.canvas.buffer_rgba())[..., :3].copy()
        if progress:
            progress(i + 1, len(steps))
