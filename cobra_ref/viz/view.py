"""Replay a saved run in MuJoCo's interactive viewer (``mujoco.viewer.launch_passive``).

``cobra-ref view``. The viewer shows the scene of :mod:`cobra_ref.viz.scene`; this module's loop
poses it at the state of the current replay time (qpos = q[k], then ``mj_forward``; nothing is
simulated), draws the contact arrows and points of the run's log and the box's path into the
viewer's ``user_scn``, and shows the time (the viewer's info panel reads ``data.time``, and a text
overlay). Replay time runs at ``speed`` times real time (0.25 = four times slower); the space bar
pauses; the run starts again from the beginning when it ends (``loop``), or the replay ends after
showing its last state.
The camera's point of interest follows the robot and the box (``follow``); the mouse still turns and
zooms it.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
import time

import numpy as np

from . import scene

FRAME_PERIOD = 1.0 / 60.0  # [s] between viewer updates
SPACE = 32  # GLFW key code of the space bar
GLFW_PROBE = "import glfw, sys; ok = glfw.init(); glfw.terminate(); sys.exit(0 if ok else 1)"


def display_problem() -> str | None:
    """Why no window can be opened here, or None: on Linux, no DISPLAY / WAYLAND_DISPLAY, or GLFW
    cannot initialize on it (tried in a subprocess: the viewer's thread would otherwise wait forever
    for a window that never opens).

    ``cobra-ref view`` fails clearly without a display.
    """
    if not sys.platform.startswith("linux"):
        return None
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        return "no display: neither DISPLAY nor WAYLAND_DISPLAY is set"
    try:
        probe = subprocess.run([sys.executable, "-c", GLFW_PROBE], capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        return "GLFW did not answer within 60 s on this display"
    if probe.returncode != 0:
        last = (probe.stderr.strip().splitlines() or ["glfw.init() failed"])[-1]
        return f"cannot open a window on display {os.environ.get('DISPLAY') or os.environ.get('WAYLAND_DISPLAY')} " \
               f"({last})"
    return None


def replay(traj, speed: float = 1.0, loop: bool = True, follow: bool = True,
           force_scale: float = scene.FORCE_SCALE, launch=None, max_frames: int | None = None) -> dict:
    """Replay ``traj`` in the viewer until its window is closed (or, with ``loop`` False, until the
    run's last state has been shown); return ``{"frames_shown": n, "last_time_shown": t}``, t [s]
    from the run's start.

    ``cobra-ref view``. ``launch`` defaults to ``mujoco.viewer.launch_passive`` (tests pass their
    own); ``max_frames`` ends the loop early (tests).
    """
    import mujoco

    if launch is None:
        import mujoco.viewer

        launch = mujoco.viewer.launch_passive
    if not (np.isfinite(speed) and speed > 0):
        raise ValueError(f"speed must be positive and finite, got {speed}")
    m, d = scene.build_scene()
    scene.set_state(m, d, traj, 0)
    camera = scene.follow_camera(m, d, traj, scene.state_indices(traj, scene.frame_times(traj, 10.0)), 16, 9)
    lookat = camera["lookat"]
    paused = {"on": False}

    def on_key(key: int) -> None:
        if key == SPACE:
            paused["on"] = not paused["on"]

    before = set(threading.enumerate())
    handle = launch(m, d, key_callback=on_key)
    viewer_threads = [t for t in threading.enumerate() if t not in before]
    with handle.lock():
        handle.cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        handle.cam.lookat[:] = lookat[0]
        handle.cam.distance, handle.cam.azimuth = camera["distance"], camera["azimuth"]
        handle.cam.elevation = camera["elevation"]
    replay_time, last, frames, shown = 0.0, time.perf_counter(), 0, 0.0
    while handle.is_running() and (max_frames is None or frames < max_frames):
        now = time.perf_counter()
        if not paused["on"]:
            replay_time += (now - last) * speed
        last = now
        ended = replay_time > traj.duration
        if ended:
            replay_time = 0.0 if loop else traj.duration
        k = int(scene.state_indices(traj, [traj.t[0] + replay_time])[0])
        with handle.lock():
            scene.set_state(m, d, traj, k)
            handle.user_scn.ngeom = 0
            scene.add_markers(handle.user_scn, traj, k, force_scale)
            if follow:
                handle.cam.lookat[:] = lookat[min(int(round(replay_time * 10.0)), len(lookat) - 1)]
        shown = float(traj.t[k] - traj.t[0])
        state = "paused (space)" if paused["on"] else f"speed x{speed:g} (space: pause)"
        show_time(handle, shown, traj.duration, state)
        handle.sync()
        frames += 1
        if ended and not loop:
            break
        time.sleep(max(0.0, FRAME_PERIOD - (time.perf_counter() - now)))
    close(handle, viewer_threads)
    return {"frames_shown": frames, "last_time_shown": shown}


def show_time(handle, shown: float, duration: float, state: str) -> None:
    """The overlay text: the time shown of the run's duration [s] and the replay's state.

    Called outside ``handle.lock()``: ``set_texts`` waits for the viewer's render thread, which
    takes that lock, so calling it under the lock stops the replay on its first frame.
    """
    import mujoco

    if hasattr(handle, "set_texts"):
        handle.set_texts((None, mujoco.mjtGridPos.mjGRID_BOTTOMLEFT, "replay",
                          f"t = {shown:.3f} s / {duration:.3f} s, {state}"))


def close(handle, threads, timeout: float = 10.0) -> None:
    """Close the viewer's window and wait (up to ``timeout`` [s]) for its threads to end.

    ``launch_passive`` runs the window in a daemon thread; a process that exits while that thread
    still renders dies of a segmentation fault, so the replay waits for it.
    """
    if hasattr(handle, "close") and handle.is_running():
        handle.close()
    for thread in threads:
        thread.join(timeout)
