"""Seeing a run: offscreen rendering to PNG, GIF and MP4, the viewer's replay loop (viewer mocked), and
the commands' errors. The run is a 0.2 s C-gait push, simulated once for the module."""

import io
import json
import sys

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.viz import encode, render, scene, view

W, H = 320, 240
VIDEO = render.VideoSettings(fps=30, width=W, height=H)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from cobra_ref.gaits import gait
    from cobra_ref.robots import cobra_model
    from cobra_ref.simulate import simulate

    path = str(tmp_path_factory.mktemp("run") / "run.npz")
    simulate(cobra_model(), gait("C"), 0.2).to_npz(path)
    return path, scene.load_run(path)


@pytest.fixture(scope="module")
def gl():
    """The OpenGL backend MuJoCo renders with (chosen before the first import of mujoco when this module
    is the first to need it); the rendering tests are skipped, saying why, when there is none."""
    choice = render.choose_gl()
    if choice["gl"] is None:
        pytest.skip(f"no OpenGL backend for MuJoCo's offscreen renderer: {choice['tried']}")
    return choice


def positions_in_image(traj, k, camera, lookat):
    """Image coordinates (column, row, depth) of the robot's 12 body frames and of the box's centre at
    state k, through the free camera the renderer used."""
    import mujoco

    m, d = scene.build_scene()
    scene.set_state(m, d, traj, k)
    cam = scene.make_camera({**camera, "lookat": [lookat]}, 0)
    scn = mujoco.MjvScene(m, maxgeom=1000)
    mujoco.mjv_updateScene(m, d, mujoco.MjvOption(), None, cam, mujoco.mjtCatBit.mjCAT_ALL, scn)
    pts = scene.scene_points(m, d, traj, k)
    return scene.project(scn, pts["robot"], W, H), scene.project(scn, pts["box"], W, H)[0]


def assert_in_image(uvz, what):
    uvz = np.atleast_2d(uvz)
    assert np.all(uvz[:, 2] > 0), f"{what} behind the camera"
    assert np.all((uvz[:, 0] >= 0) & (uvz[:, 0] < W) & (uvz[:, 1] >= 0) & (uvz[:, 1] < H)), \
        f"{what} outside the {W} x {H} image: {uvz[:, :2].round(1).tolist()}"


def assert_not_blank(image):
    """A blank (uniform) frame has variance 0; the rendered scene's is in the hundreds (measured ~900)."""
    assert image.shape == (H, W, 3)
    assert float(np.var(image.astype(float))) > 100.0


def test_png_still_shows_the_robot_and_the_box(run, gl, tmp_path):
    from PIL import Image

    path, traj = run
    out = tmp_path / "still.png"
    info = render.render_file(traj, str(out), VIDEO, at=0.1)
    assert info["renderer"] == "mujoco" and info["gl"] == gl["gl"] and info["frames"] == 1
    image = np.asarray(Image.open(out).convert("RGB"))
    assert_not_blank(image)
    k = 100  # t = 0.1 s at dt = 1 ms
    robot, box = positions_in_image(traj, k, info["camera"], info["camera"]["lookat_first"])
    assert_in_image(robot, "robot")
    assert_in_image(box, "box")
    # the projection is the renderer's: the box's centre pixel is the box's orange (red well above
    # blue), not the grey ground (red = blue) or a blue link
    c, r = int(box[0]), int(box[1])
    patch = image[r - 2:r + 3, c - 2:c + 3].reshape(-1, 3).astype(int)
    red, blue = np.median(patch[:, 0]), np.median(patch[:, 2])
    assert red - blue > 40, f"box pixel {np.median(patch, axis=0)} is not orange"


def test_gif_plays_the_run_in_real_time_with_robot_and_box_in_frame(run, gl, tmp_path):
    from PIL import Image

    path, traj = run
    out = tmp_path / "run.gif"
    info = render.render_file(traj, str(out), VIDEO)
    assert info["renderer"] == "mujoco" and info["frames"] == 7  # t = 0, 1/30, ..., 6/30 <= 0.2 s
    gif = Image.open(out)
    assert gif.n_frames == 7
    frames, durations = [], []
    for i in range(gif.n_frames):
        gif.seek(i)
        frames.append(np.asarray(gif.convert("RGB")))
        durations.append(gif.info["duration"])
    for f in frames:
        assert_not_blank(f)
    assert sum(durations) == pytest.approx(7 * 1000 / 30, abs=10)  # centisecond delays: 230 ms for 233.3
    assert np.abs(frames[0].astype(int) - frames[-1].astype(int)).max() > 0  # the time stamp at least moved
    for k, lookat in ((0, info["camera"]["lookat_first"]), (200, info["camera"]["lookat_last"])):
        robot, box = positions_in_image(traj, k, info["camera"], lookat)
        assert_in_image(robot, f"robot at state {k}")
        assert_in_image(box, f"box at state {k}")


def test_mp4_holds_every_frame(run, gl, tmp_path):
    pytest.importorskip("imageio_ffmpeg", reason="MP4 needs the optional extra video (imageio, imageio-ffmpeg)")
    import imageio.v2 as imageio

    path, traj = run
    out = tmp_path / "run.mp4"
    info = render.render_file(traj, str(out), VIDEO)
    assert info["frames"] == 7
    with imageio.get_reader(str(out)) as reader:
        assert reader.count_frames() == 7
        assert_not_blank(reader.get_data(3))


def test_gif_delays_are_whole_centiseconds_that_keep_real_time():
    d = encode.gif_durations(30, 30.0)
    assert all(x % 10 == 0 for x in d) and set(d) == {30, 40}
    assert sum(d) == 1000  # 30 frames at 30 fps = 1 s exactly
    assert encode.gif_durations(4, 25.0) == [40, 40, 40, 40]


def test_frame_times_and_nearest_states(run):
    path, traj = run
    times = scene.frame_times(traj, fps=30, speed=1.0)
    assert len(times) == 7 and times[-1] == pytest.approx(0.2)
    assert scene.frame_times(traj, fps=30, speed=0.25).shape == (25,)  # 0.2 s four times slower at 30 fps
    assert scene.state_indices(traj, [0.0, 0.0334, 0.0336, 0.2, 5.0]).tolist() == [0, 33, 34, 200, 200]


def test_matplotlib_fallback_without_an_opengl_backend(run, tmp_path, monkeypatch):
    from PIL import Image

    path, traj = run
    monkeypatch.setattr(render, "choose_gl", lambda refresh=False: {"gl": None, "process": None,
                                                                      "tried": {"egl": "no EGL here (test)"}})
    info = render.render_file(traj, str(tmp_path / "still.png"), VIDEO, at=0.05)
    assert info["renderer"] == "matplotlib" and "no EGL here (test)" in info["fallback_reason"]
    assert_not_blank(np.asarray(Image.open(tmp_path / "still.png").convert("RGB")))
    with pytest.raises(render.RenderError, match="no OpenGL backend"):
        render.render_file(traj, str(tmp_path / "x.png"), VIDEO, renderer="mujoco")


def test_a_child_process_renders_the_same_image(run, gl, tmp_path, monkeypatch):
    """The path taken when mujoco was imported here with a backend that cannot render: the same
    frame, rendered by a fresh process with the working backend (same OpenGL: equal to 1 level)."""
    from PIL import Image

    path, traj = run
    here = render.render_file(traj, str(tmp_path / "here.png"), VIDEO, at=0.15)
    monkeypatch.setattr(render, "choose_gl", lambda refresh=False: {**gl, "process": "child"})
    child = render.render_file(traj, str(tmp_path / "child.png"), VIDEO, at=0.15)
    assert child["process"] == "child" and child["camera"] == here["camera"]  # the same run, read back exactly
    a, b = (np.asarray(Image.open(tmp_path / f"{n}.png").convert("RGB")).astype(int) for n in ("here", "child"))
    assert np.abs(a - b).max() <= 1


def test_render_gif_says_which_renderer_it_used(run, gl, tmp_path):
    path, traj = run
    info = render.render_gif(traj, str(tmp_path / "anim.gif"), render.VideoSettings(fps=10, width=W, height=H))
    assert info["renderer"] == "mujoco" and info["frames"] == 3 and info["bytes"] > 0
    with pytest.raises(render.RenderError, match="writes a .gif"):
        render.render_gif(traj, str(tmp_path / "anim.mp4"))


class FakeViewer:
    """What the replay loop uses of mujoco.viewer.Handle; records what each synced frame shows."""

    def __init__(self, m, d, frames):
        import mujoco

        self.m, self.d, self.left = m, d, frames
        self.cam = mujoco.MjvCamera()
        self.user_scn = mujoco.MjvScene(m, maxgeom=2000)
        self.shown, self.texts = [], []

    def is_running(self):
        return self.left > 0

    def lock(self):
        import contextlib

        return contextlib.nullcontext()

    def close(self):
        self.left = 0

    def set_texts(self, texts):
        self.texts.append(texts)

    def sync(self):
        starts, forces = scene.arrows_in_scene(self.user_scn)
        self.shown.append((float(self.d.time), np.array(self.d.qpos), starts, forces))
        self.left -= 1


def test_view_draws_the_logged_contact_forces_of_the_shown_step(run, monkeypatch, capsys):
    pytest.importorskip("mujoco")
    import mujoco.viewer

    path, traj = run
    viewers = []

    def fake_launch(m, d, key_callback=None):
        assert m.nq == 25 and callable(key_callback)
        viewers.append(FakeViewer(m, d, frames=20))
        return viewers[-1]

    monkeypatch.setattr(view, "display_problem", lambda: None)
    monkeypatch.setattr(mujoco.viewer, "launch_passive", fake_launch)
    assert main(["view", path, "--speed", "0.5"]) == 0
    assert json.loads(capsys.readouterr().out)["frames_shown"] == 20
    (viewer,) = viewers
    with np.load(path) as z:
        log = {k: z[k] for k in ("contact_step", "contact_point", "contact_force")}
    drawn = 0
    for time, qpos, starts, forces in viewer.shown:
        k = int(np.argmin(np.abs(traj.t - time)))
        assert traj.t[k] == pytest.approx(time, abs=1e-12)
        np.testing.assert_array_equal(qpos, traj.q[k])  # the pose is the run's state, not simulated
        rows = log["contact_step"] == min(k, len(traj.t) - 2)
        assert rows.sum() == len(forces) > 0
        # float32 geoms: 1e-5 relative, 1e-4 N absolute
        np.testing.assert_allclose(forces, log["contact_force"][rows], rtol=1e-5, atol=1e-4)
        np.testing.assert_allclose(starts, log["contact_point"][rows], atol=1e-6)
        drawn += len(forces)
    assert drawn >= 20 * 5  # at least five contacts (the lying snake's links) per frame
    assert "t = " in viewer.texts[-1][3]


def test_view_without_a_display_says_so_and_suggests_render(run, monkeypatch):
    if not sys.platform.startswith("linux"):
        pytest.skip("the display check is the X11 / Wayland one")
    pytest.importorskip("mujoco")
    path, _ = run
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    with pytest.raises(SystemExit) as exc:
        main(["view", path])
    message = str(exc.value.code)
    assert message.startswith("error:") and "display" in message and "cobra-ref render" in message


@pytest.mark.parametrize("args, message", [
    (["render", "{run}", "--out", "{tmp}/x.txt"], "unknown output format"),
    (["render", "{run}", "--out", "{tmp}/x.gif", "--at", "0.1"], "still frame"),
    (["render", "{run}", "--out", "{tmp}/x.png", "--at", "3"], "outside the run"),
    (["render", "{run}", "--out", "{tmp}/x.gif", "--fps", "0"], "--fps = 0 1/s is out of range (allowed: (0, 120]"),
    (["render", "{run}", "--out", "{tmp}/x.gif", "--fps", "60"], "at most 50 frames"),
    (["render", "{run}", "--out", "{tmp}/x.png", "--width", "5000"], "--width = 5000 px is out of range"),
    (["render", "{run}", "--out", "{tmp}/x.png", "--width", "6.5"], "--width"),
    (["view", "{run}", "--speed", "-1"], "--speed = -1 is out of range"),
    (["render", "{run}", "--out", "{tmp}/nope/x.png"], "output directory does not exist"),
    (["render", "{tmp}/missing.npz", "--out", "{tmp}/x.png"], "no such run file"),
    (["render", "{tmp}/bad.npz", "--out", "{tmp}/x.png"], "not a readable NPZ"),
    (["view", "{tmp}/missing.npz"], "no such run file"),
])
def test_bad_input_names_the_problem_and_writes_nothing(run, tmp_path, capsys, args, message):
    """Each bad input exits with a message that names it (argparse's range errors on stderr,
    exit status 2; the renderer's own checks in the exit message), and nothing is written."""
    path, _ = run
    (tmp_path / "bad.npz").write_text("not an npz")
    argv = [a.format(run=path, tmp=tmp_path) for a in args]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert message in str(exc.value.code) + capsys.readouterr().err
    assert not any(p.name.startswith("x.") or p.name.startswith(".tmp_") for p in tmp_path.iterdir())


def test_a_run_with_other_step_records_loads_but_one_without_its_contact_log_does_not(run, tmp_path):
    """A replay needs t, q, box_pose and the contact log, not this version's per-step records."""
    path, traj = run
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files if k != "fp_iter"}
    np.savez(tmp_path / "other.npz", **arrays)
    other = scene.load_run(str(tmp_path / "other.npz"))
    np.testing.assert_array_equal(other.q, traj.q)
    np.testing.assert_array_equal(scene.contact_arrows(other, 50)["forces"], scene.contact_arrows(traj, 50)["forces"])
    del arrays["contact_force"]
    np.savez(tmp_path / "nolog.npz", **arrays)
    with pytest.raises(scene.RunError, match="no array 'contact_force'"):
        scene.load_run(str(tmp_path / "nolog.npz"))


def test_render_command_prints_one_json_line(run, gl, tmp_path, capsys):
    path, _ = run
    out = tmp_path / "still.png"
    assert main(["render", path, "--out", str(out), "--at", "0.2", "--width", str(W), "--height", str(H),
                 "--quiet"]) == 0
    captured = capsys.readouterr()
    record = json.loads(captured.out)
    assert record["renderer"] == "mujoco" and record["out"] == str(out) and record["bytes"] == out.stat().st_size
    assert f"MUJOCO_GL={gl['gl']}" in captured.err
    from PIL import Image

    assert Image.open(io.BytesIO(out.read_bytes())).size == (W, H)
