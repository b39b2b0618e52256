"""MuJoCo rollouts of the exported model as worked examples (compared in bands, not equality).

The box at rest must stay at rest, the kinematic servo must follow the reference, and a C roll
must push the box in MuJoCo; ``compare`` then reports how it agrees with our simulator.
"""

import importlib
import inspect
import sys

import numpy as np
import pytest

import cobra_ref as cr
from cobra_ref.reproduce import mujoco_check as mr
from cobra_ref.gaits import gait
from cobra_ref.simulate import simulate
from cobra_ref.start import placed_state

mujoco = pytest.importorskip("mujoco")


def _hold(q_ref0):
    """A reference that holds the shape q_ref0: no actuation change."""
    zero = np.zeros_like(q_ref0)
    return lambda t: (q_ref0, zero, zero)


@pytest.mark.parametrize("mode", mr.MODES)
def test_box_resting_beside_a_still_robot_stays_put_in_mujoco(cobra, mode):
    """Gravity only, robot holding its start shape: the box (0.5 kg on mu = 1) has no horizontal
    load, so it must not slide; MuJoCo's soft contact lets it sink by a_u (1 - d) tau_c^2 ~ 1e-5 m
    ([MJ] "Reference": r = a_u (1 - d) timeconst^2 dampratio^2, a_u = g, d >= 0.9, tau_c = 4 ms)."""
    reference = gait("C")
    q0 = placed_state(cobra, reference)
    res = mr.rollout(cobra, _hold(reference(0.0)[0]), q0, 1.0, mode=mode)
    box = cobra.boxes[0]
    np.testing.assert_array_equal(res.qpos[0], q0, err_msg="the initial state goes into MuJoCo unchanged")
    assert np.linalg.norm(res.box_displacement) < 1e-3, res.box_displacement
    sink = box.half[2] - res.box_pose[-1, 2]
    assert 0.0 <= sink < 1e-4, f"box sinks {sink} m"
    np.testing.assert_allclose(np.abs(res.box_pose[-1, 3:] @ q0[cobra.q_idx[box.body]][3:]), 1.0, atol=1e-6,
                               err_msg="box orientation changed")
    assert res.n_warnings == 0


@pytest.mark.parametrize("name", ["C", "sidewinding"])
def test_kinematic_mode_joint_angles_equal_the_reference(cobra, name):
    """The equality-row servo tracks theta_ref to within 1e-4 rad at every step, contacts
    included (measured ~1.3e-5). Without its velocity shift it would lag by 2 tau_c theta_dot_ref
    ~ 6e-3 rad (module docstring), so this tolerance tests the shift too."""
    reference = gait(name)
    q0 = placed_state(cobra, reference)
    res = mr.rollout(cobra, reference, q0, 1.5, mode="kinematic")
    hinges = [cobra.q_idx[i].start for i, jt in enumerate(cobra.joint_type) if jt != "free"]
    q_ref = np.array([reference(t)[0] for t in res.t])
    np.testing.assert_allclose(res.qpos[:, hinges], q_ref, atol=1e-4, rtol=0,
                               err_msg=f"{name}: joints leave the reference")
    assert res.max_tracking_error < 1e-4
    np.testing.assert_allclose(res.t[-1], 1.5, atol=1e-12)
    assert res.qpos.shape == (1501, cobra.nq) and res.box_pose.shape == (1501, 7)


def test_j_mirror_pushes_the_box_along_the_mirror_image_of_j(cobra):
    """Symmetry: J-mirror is J reflected in the robot's vertical plane y = 0 (gaits docstring), and
    so is its start state (robot on the x axis, box on the reflected concave side). The laws of
    motion and the ground are invariant under the reflection, so the box's path must be J's with
    y -> -y. MuJoCo keeps this to 1e-11 m over 2 s of pushing; asserted to 1e-6 m."""
    paths = {}
    for name in ("J", "J-mirror"):
        reference = gait(name)
        q0 = placed_state(cobra, reference)
        paths[name] = mr.rollout(cobra, reference, q0, 2.0).box_pose[:, :2]
    assert np.linalg.norm(paths["J"][-1] - paths["J"][0]) > mr.MIN_DISPLACEMENT, "J does not push the box"
    np.testing.assert_allclose(paths["J-mirror"], paths["J"] * [1.0, -1.0], atol=1e-6, rtol=0,
                               err_msg="J-mirror's box path is not J's reflected in y = 0")


def test_compare_worked_examples():
    """Hand-solvable: 30 deg apart and twice as far holds; 60 deg apart or 4x as far does not;
    both below the 5 mm floor agree; one below it does not."""
    c = np.cos(np.radians(30)), np.sin(np.radians(30))
    r = mr.compare((0.1, 0.0), (0.2 * c[0], 0.2 * c[1]))
    assert r["angle_deg"] == pytest.approx(30.0) and r["ratio"] == pytest.approx(2.0) and r["holds"]
    assert not mr.compare((0.1, 0.0), (0.05, 0.05 * np.sqrt(3)))["holds"]  # 60 deg
    assert not mr.compare((0.1, 0.0), (0.4, 0.0))["holds"]  # ratio 4
    assert not mr.compare((0.1, 0.0), (0.03, 0.0))["holds"]  # ratio 0.3 < 1/3
    assert mr.compare((0.001, 0.0), (0.0, -0.002))["holds"]
    r = mr.compare((0.1, 0.0), (0.0, 0.0))
    assert not r["holds"] and np.isnan(r["angle_deg"]) and r["ratio"] == 0.0


@pytest.fixture(scope="module")
def c_roll_2s():
    """Our simulator and MuJoCo (kinematic servo), the same 2 s of C rolling from the same state."""
    model = cr.cobra_model()
    reference = gait("C")
    q0 = placed_state(model, reference)
    ours = simulate(model, reference, 2.0, q0=q0)
    return ours, mr.rollout(model, reference, q0, 2.0, mode="kinematic")


def test_c_rolling_moves_the_box_in_mujoco_and_compare_reports(c_roll_2s):
    """The C roll reaches the box within 2 s in both simulators and pushes it along the ground.

    Asserted: both move the box more than the 5 mm floor; in MuJoCo it stays on the ground, with
    sub-mm penetration; the two push directions agree within the 45 deg band, because the
    direction is set by geometry both share (box on the concave side, the same roll). The
    magnitude ratio (the contact-law-sensitive part, ``compare`` Notes) is printed, not asserted."""
    ours, mj = c_roll_2s
    d_ours = ours.box_pose[-1, :2] - ours.box_pose[0, :2]
    report = mr.compare(d_ours, mj.box_displacement)
    print(f"\nC rolling, 2 s: ours {np.round(d_ours, 4)} m, MuJoCo {np.round(mj.box_displacement, 4)} m; "
          f"angle {report['angle_deg']:.1f} deg, ratio {report['ratio']:.2f}, holds {report['holds']} "
          f"({report['reason']}); MuJoCo max penetration {mj.max_penetration * 1000:.2f} mm, "
          f"{mj.mean_contacts:.1f} contacts per step, {mj.wall_time:.2f} s wall")
    assert not ours.error
    assert np.linalg.norm(mj.box_displacement) > mr.MIN_DISPLACEMENT
    assert abs(mj.box_pose[-1, 2] - mj.box_pose[0, 2]) < 2e-3, "the box left the ground"
    assert 0.0 < mj.max_penetration < 1e-3
    assert np.linalg.norm(d_ours) > mr.MIN_DISPLACEMENT
    assert report["angle_deg"] <= mr.MAX_ANGLE_DEG, report["reason"]
    assert np.isfinite(report["ratio"])
    assert set(report) >= {"angle_deg", "ratio", "holds", "band"}


def test_missing_mujoco_raises_a_clear_error(cobra, monkeypatch):
    """mujoco is optional: without it the rollout says what to install, and available() is False."""
    monkeypatch.setitem(sys.modules, "mujoco", None)  # makes `import mujoco` raise ImportError
    assert not mr.mujoco_available()
    with pytest.raises(mr.MujocoUnavailable, match="pip install mujoco"):
        mr.rollout(cobra, gait("C"), cr.neutral_q(cobra), 0.01)
    with pytest.raises(mr.MujocoUnavailable):
        mr.cross_check(["C"], 0.01)


def test_bad_mode_and_mismatched_layout_are_refused(cobra, cobra_robot):
    with pytest.raises(ValueError, match="mode"):
        mr.servo_mjcf(cobra, 1e-3, mode="torque")
    m = mujoco.MjModel.from_xml_string(cr.to_mjcf(cobra_robot))
    with pytest.raises(mr.MujocoRolloutError, match="nq"):
        mr._check_layout(cobra, m)


def test_public_functions_name_what_they_implement():
    """Every public function names what it implements, as tests/test_docstrings_cite.py checks."""
    module = importlib.import_module("cobra_ref.reproduce.mujoco_check")
    for fname, obj in vars(module).items():
        if fname.startswith("_") or not inspect.isfunction(obj) or obj.__module__ != module.__name__:
            continue
        doc = inspect.getdoc(obj) or ""
        assert "Implements:" in doc or "Helper:" in doc, f"mujoco_rollout.{fname}"
