"""``cobra-ref export-mjcf`` writes a file one can open and play: its keyframe ``start`` puts the
robot and the box at rest on the ground, so 1 s of MuJoCo's own stepping from it moves no body by
more than 5 mm (the settled start moves ~0.2 mm: the servo holds the joints, the compliant contact
carries the weight). Without ``--from`` the key is the C gait's settled start; with it, the run's
state at ``--at``.
"""

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.mjcf import KEY, joint_angles
from cobra_ref.robots import cobra_model

mujoco = pytest.importorskip("mujoco")

REST = 5e-3  # [m] the most any body may move in 1 s from the key


def play_from_key(path, seconds=1.0):
    """(MjModel, largest displacement of any body [m], qpos after ``seconds``) from the key."""
    m = mujoco.MjModel.from_xml_path(str(path))
    d = mujoco.MjData(m)
    mujoco.mj_resetDataKeyframe(m, d, mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_KEY, KEY))
    mujoco.mj_forward(m, d)
    x0 = d.xpos.copy()
    for _ in range(int(round(seconds / m.opt.timestep))):
        mujoco.mj_step(m, d)
    assert np.all(np.isfinite(d.qpos)) and np.all(np.isfinite(d.xpos)), "NaN in MuJoCo's state"
    return m, float(np.max(np.linalg.norm(d.xpos - x0, axis=1))), d.qpos.copy()


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    from cobra_ref.gaits import gait
    from cobra_ref.simulate import simulate

    path = tmp_path_factory.mktemp("run") / "run.npz"
    traj = simulate(cobra_model(), gait("C"), 0.2)
    traj.to_npz(str(path))
    return path, traj


def test_the_default_key_is_the_settled_c_start_and_rests(tmp_path):
    from cobra_ref.gaits import gait
    from cobra_ref.start import initial_state

    out = tmp_path / "cobra.xml"
    assert main(["export-mjcf", str(out)]) == 0
    text = out.read_text()
    assert 'builtin="checker"' in text and 'material="floor"' in text and "<light" in text and 'name="box_' in text
    m, moved, _ = play_from_key(out)
    assert (m.nq, m.nu, m.nkey) == (25, 11, 1)
    q0 = initial_state(cobra_model(), gait("C"))[0]
    np.testing.assert_allclose(m.key_qpos[0], q0, rtol=0, atol=1e-15)
    np.testing.assert_allclose(m.key_ctrl[0], q0[7:18], rtol=0, atol=1e-15)  # ctrl = the joint angles
    assert q0[2] > 0.03, "the head rests on the ground, not at the origin inside it"
    assert moved < REST, f"a body moved {moved * 1e3:.2f} mm in 1 s from the key"


@pytest.mark.parametrize("at", [None, 0.2])
def test_the_key_from_a_run_is_its_state_at_the_time_and_rests(run, tmp_path, at):
    path, traj = run
    out = tmp_path / "from.xml"
    assert main(["export-mjcf", str(out), "--from", str(path)] + ([] if at is None else ["--at", str(at)])) == 0
    m, moved, _ = play_from_key(out)
    k = 0 if at is None else len(traj.t) - 1
    np.testing.assert_allclose(m.key_qpos[0], traj.q[k], rtol=0, atol=1e-15)
    np.testing.assert_allclose(traj.q[k][-7:], traj.box_pose[k], rtol=0, atol=1e-15)
    np.testing.assert_allclose(m.key_ctrl[0], joint_angles(cobra_model(), traj.q[k]), rtol=0, atol=1e-15)
    assert moved < REST, f"a body moved {moved * 1e3:.2f} mm in 1 s from the key"


def test_the_robot_alone_takes_the_robot_part_of_the_run(run, tmp_path):
    path, traj = run
    out = tmp_path / "robot.xml"
    assert main(["export-mjcf", str(out), "--no-box", "--from", str(path), "--at", "0.1"]) == 0
    m, moved, _ = play_from_key(out, seconds=0.5)
    assert (m.nq, m.nu) == (18, 11)
    np.testing.assert_allclose(m.key_qpos[0], traj.q[100][:18], rtol=0, atol=1e-15)
    assert moved < REST


@pytest.mark.parametrize("args, message", [
    (["--at", "0.1"], "--at needs --from"),
    (["--from", "{run}", "--at", "5"], "outside the run"),
    (["--from", "{tmp}/missing.npz"], "no such run file"),
])
def test_bad_key_options_say_why_and_write_nothing(run, tmp_path, args, message):
    out = tmp_path / "x.xml"
    argv = ["export-mjcf", str(out)] + [a.format(run=run[0], tmp=tmp_path) for a in args]
    with pytest.raises(SystemExit, match=message):
        main(argv)
    assert not out.exists()
