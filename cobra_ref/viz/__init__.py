"""See and share a run: MuJoCo's interactive viewer and offscreen rendering of a saved run.

Helper: ``cobra-ref view`` (:mod:`cobra_ref.viz.view`) and ``cobra-ref render``
(:mod:`cobra_ref.viz.render`) on the scene of :mod:`cobra_ref.viz.scene`. Importing this
package imports neither mujoco nor matplotlib (the OpenGL backend is chosen before mujoco's
import).
"""

from .render import render_file, render_gif
from .scene import load_run

__all__ = ["load_run", "render_file", "render_gif"]
