"""The real interactive viewer: ``cobra-ref view RUN.npz --once`` in a child process, on the display
this session has or on an Xvfb server the test starts. It must play the run to its end and exit 0;
a replay stuck on its first frame either times out or reports ``last_time_shown`` 0.

Skipped, saying why, where neither a display nor Xvfb is available, or where GLFW cannot open a
window on it (mujoco's viewer needs one).
"""

import json
import os
import shutil
import subprocess
import sys

import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def start_xvfb():
    """(process, ":N") of an Xvfb server on a display number it picks itself (``-displayfd``)."""
    read_end, write_end = os.pipe()
    proc = subprocess.Popen(["Xvfb", "-displayfd", str(write_end), "-screen", "0", "1024x768x24", "-nolisten", "tcp"],
                            pass_fds=(write_end,), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_end)
    with os.fdopen(read_end) as pipe:
        number = pipe.readline().strip()  # Xvfb writes the number once it accepts clients
    if not number:
        proc.kill()
        proc.wait()
        pytest.skip("Xvfb started but reported no display number")
    return proc, f":{number}"


@pytest.fixture(scope="module")
def display():
    """A DISPLAY on which GLFW can open a window: this session's, else a new Xvfb's."""
    pytest.importorskip("mujoco")
    pytest.importorskip("glfw")
    from cobra_ref.viz import view

    if not sys.platform.startswith("linux"):
        pytest.skip("the viewer test starts Xvfb, which is Linux's (macOS's viewer needs mjpython)")
    proc = None
    if view.display_problem() is None:
        name = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")
    elif shutil.which("Xvfb") is None:
        pytest.skip("no usable display and no Xvfb to make one (apt-get install xvfb)")
    else:
        proc, name = start_xvfb()
    saved = os.environ.get("DISPLAY")
    os.environ["DISPLAY"] = name
    try:
        problem = view.display_problem()
        if problem:
            pytest.skip(f"GLFW cannot open a window on {name}: {problem}")
        yield name
    finally:
        if saved is None:
            os.environ.pop("DISPLAY", None)
        else:
            os.environ["DISPLAY"] = saved
        if proc is not None:
            proc.terminate()
            proc.wait(10)


@pytest.fixture(scope="module")
def run_file(tmp_path_factory):
    from cobra_ref.gaits import gait
    from cobra_ref.robots import cobra_model
    from cobra_ref.simulate import simulate

    path = str(tmp_path_factory.mktemp("view") / "run.npz")
    simulate(cobra_model(), gait("C"), 0.3).to_npz(path)
    return path


def test_view_once_plays_the_run_to_its_end_in_the_real_viewer(display, run_file):
    env = {k: v for k, v in os.environ.items() if k not in ("MUJOCO_GL", "PYOPENGL_PLATFORM")}
    env["DISPLAY"] = display
    env["PYTHONPATH"] = os.pathsep.join([ROOT] + [p for p in [env.get("PYTHONPATH")] if p])
    try:
        child = subprocess.run([sys.executable, "-m", "cobra_ref", "view", run_file, "--once"], env=env,
                               capture_output=True, text=True, timeout=180)
    except subprocess.TimeoutExpired as exc:
        pytest.fail(f"the viewer did not finish a 0.3 s run within 180 s (stuck on a frame?): {exc.stderr!r}")
    assert child.returncode == 0, child.stderr[-2000:]
    shown = json.loads(child.stdout.strip().splitlines()[-1])
    assert shown["frames_shown"] >= 2
    # the replay advanced: the last frame shown is the run's last state (0.3 s), not t = 0
    assert shown["last_time_shown"] == pytest.approx(0.3, abs=1e-9)
