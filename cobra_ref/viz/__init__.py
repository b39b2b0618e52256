"""See and share a run: MuJoCo's interactive viewer and offscreen rendering of a saved run.

``cobra-ref view`` (:mod:`cobra_ref.viz.view`) and ``cobra-ref render``
(:mod:`cobra_ref.viz.render`) on the scene of :mod:`cobra_ref.viz.scene`; the matplotlib drawing
of a scene (:mod:`cobra_ref.viz.drawing`) that fig. 3, its GIFs and the renderer's fallback share.
Importing this package imports neither mujoco nor matplotlib (the OpenGL backend is chosen before
mujoco's import).
"""

from .render import VideoSettings, render_file, render_gif
from .scene import load_run

__all__ = ["VideoSettings", "load_run", "render_file", "render_gif"]
