"""Which OpenGL backend MuJoCo's offscreen renderer works with here, found without harming this process.

MuJoCo reads ``MUJOCO_GL`` once, when it is first imported. Before that import, each candidate
(``MUJOCO_GL`` if the user set it, then ``egl``, then ``osmesa``) is tried in a short-lived
subprocess (a backend that fails, or crashes, cannot harm this process) and the first that renders
is written to ``os.environ["MUJOCO_GL"]``. If mujoco was imported earlier in this process with a
backend that does not render (a test session, the figure command), the frames are to be rendered
in a child process started with the backend that does (``process="child"``).
"""

from __future__ import annotations

import os
import subprocess
import sys

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
_choice: dict = {}


def gl_candidates() -> list[str]:
    """The ``MUJOCO_GL`` values to try, in order: the user's own, then egl and osmesa (Linux), or
    MuJoCo's platform default elsewhere ("")."""
    own = os.environ.get("MUJOCO_GL", "").strip().lower()
    tried = [own] if own else []
    defaults = ["egl", "osmesa"] if sys.platform.startswith("linux") else [""]
    return tried + [name for name in defaults if name not in tried]


def probe_gl(name: str, timeout: float = 120.0) -> str:
    """Render a 16 x 16 image in a subprocess with ``MUJOCO_GL=name``; "" if it worked, else the
    reason (the last line of its error). A backend that crashes cannot harm this process."""
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
    """The ``MUJOCO_GL`` value mujoco was imported with in this process ("" = platform default)."""
    try:
        from mujoco.rendering.classic import gl_context
    except ImportError:
        return os.environ.get("MUJOCO_GL", "")
    return getattr(gl_context, "_MUJOCO_GL", os.environ.get("MUJOCO_GL", ""))


def renders_here() -> str:
    """Try a 16 x 16 offscreen render in this process (mujoco already imported): "" if it worked,
    else the reason."""
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
    candidate's failure, "" for the one that worked). The answer is kept for the process (module
    docstring)."""
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


def no_gl_reason(choice: dict) -> str:
    """Why MuJoCo cannot render, from a ``choose_gl`` answer whose ``gl`` is None."""
    tried = choice["tried"]
    return tried.get("mujoco") or "no OpenGL backend renders: " + "; ".join(f"{k}: {v}" for k, v in tried.items())
