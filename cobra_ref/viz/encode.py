"""The renderer's writers: a still (PNG), an animated GIF or an MP4 video, each written atomically.

PNG and GIF with Pillow (which matplotlib brings); MP4 with imageio and imageio-ffmpeg (the
optional extra ``pip install 'cobra-ref[video]'``). GIF frame delays are whole centiseconds: they
alternate (30, 40, 30, 30, 40, ... ms at 30 fps) so that the GIF plays in real time.
"""

from __future__ import annotations

import os

import numpy as np

from ..infra.output import atomic_write
from .scene import KIND_RGBA

FORMATS = ("png", "gif", "mp4")


class RenderError(ValueError):
    """Bad input to the renderer, or a writer that is not installed (the message says which)."""


def output_format(path: str) -> str:
    """``png``, ``gif`` or ``mp4`` from the file name; RenderError for anything else."""
    ext = os.path.splitext(path)[1].lower().lstrip(".")
    if ext not in FORMATS:
        raise RenderError(f"unknown output format {os.path.splitext(path)[1] or '(none)'!r} of {path}: "
                          f"use .png (a still), .gif or .mp4")
    return ext


def mp4_writer_problem() -> str | None:
    """Why MP4 cannot be written here (imageio or its ffmpeg missing), or None; checked before any
    frame is rendered."""
    try:
        import imageio  # noqa: F401
        import imageio_ffmpeg

        imageio_ffmpeg.get_ffmpeg_exe()
    except Exception as exc:  # ImportError, or imageio-ffmpeg without its ffmpeg binary
        return (f"MP4 needs imageio and imageio-ffmpeg ({type(exc).__name__}: {exc}); install the optional "
                f"extra: pip install 'cobra-ref[video]', or write a .gif")
    return None


def gif_durations(n: int, fps: float) -> list[int]:
    """Per-frame delays [ms] in whole centiseconds whose running sum follows frame j at j / fps
    (30 fps: 30, 40, 30, 30, 40, ... ms, 33.3 ms on average)."""
    ends = np.round(100.0 * np.arange(1, n + 1) / fps).astype(int)
    return [int(10 * c) for c in np.diff(np.concatenate([[0], ends]))]


def write_png(path: str, frame: np.ndarray) -> None:
    """One frame as PNG, atomically (the still, ``--at``)."""
    from PIL import Image

    atomic_write(path, lambda tmp: Image.fromarray(frame).save(tmp, format="PNG"))


def write_gif(path: str, frames, n: int, fps: float) -> None:
    """``n`` frames (an iterable) as a looping GIF playing at ``fps``, atomically.

    One palette for every frame, without dithering: 255 colours taken from the first frame and the
    arrows' colours (the scene's colours do not change), so a later frame's pixels map to the same
    entries, which makes the GIF smaller and faster to encode than a palette per frame.
    """
    from PIL import Image

    it = iter(frames)
    first = np.asarray(next(it))
    swatch = np.repeat(np.round(255 * KIND_RGBA[:, :3]).astype(np.uint8), 8, axis=0)
    source = np.vstack([first.reshape(-1, 3), swatch])[None]
    palette = Image.fromarray(source).quantize(colors=255, dither=Image.Dither.NONE)

    def indexed(frame):
        return Image.fromarray(np.asarray(frame)).quantize(palette=palette, dither=Image.Dither.NONE)

    head = indexed(first)
    rest = (indexed(f) for f in it)
    atomic_write(path, lambda tmp: head.save(tmp, format="GIF", save_all=True, append_images=rest,
                                             duration=gif_durations(n, fps), loop=0))


def write_mp4(path: str, frames, fps: float) -> None:
    """Frames as an H.264 MP4 (yuv420p, playable everywhere) at ``fps``, atomically, with
    imageio-ffmpeg (the optional extra ``video``)."""
    import imageio.v2 as imageio

    def write(tmp):
        with imageio.get_writer(tmp, format="FFMPEG", mode="I", fps=fps, codec="libx264", pixelformat="yuv420p",
                                macro_block_size=2, ffmpeg_log_level="error") as w:
            for f in frames:
                w.append_data(f)

    atomic_write(path, write)


def write_frames(path: str, fmt: str, frames, n: int, fps: float) -> None:
    """Write ``n`` frames (a generator) to ``path`` as ``fmt``: the first frame alone for a PNG."""
    if fmt == "png":
        write_png(path, next(frames))
        frames.close()
    elif fmt == "gif":
        write_gif(path, frames, n, fps)
    else:
        write_mp4(path, frames, fps)
