"""MuJoCo as an independent oracle for the exported MJCF ([MJ] mj_fullM, qfrc_bias, mj_jac).

cobra_ref's q and qd use MuJoCo's free-joint convention, so states pass through unchanged and
M, h, Jacobians and poses are compared entry by entry at 20+ random states.
"""

import numpy as np
import pytest

import cobra_ref as cr

mujoco = pytest.importorskip("mujoco")

N_STATES = 25


@pytest.fixture(scope="module")
def mj(cobra):
    model = mujoco.MjModel.from_xml_string(cr.to_mjcf(cobra))
    return model, mujoco.MjData(model)


def _states(model, seed=7):
    rng = np.random.default_rng(seed)
    return [cr.random_state(model, rng) for _ in range(N_STATES)]


def _set(mj, q, qd):
    m, d = mj
    d.qpos[:] = q
    d.qvel[:] = qd
    mujoco.mj_forward(m, d)
    return d


def _rel_err(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


def test_exported_model_has_the_same_sizes_and_joint_order(cobra, mj):
    m, _ = mj
    assert (m.nq, m.nv, m.nbody - 1) == (cobra.nq, cobra.nv, cobra.nb)
    for i, name in enumerate(cobra.joint_names):
        assert mujoco.mj_id2name(m, mujoco.mjtObj.mjOBJ_JOINT, i) == name
        assert m.jnt_qposadr[i] == cobra.q_idx[i].start
        assert m.jnt_dofadr[i] == cobra.v_idx[i].start


def test_mass_matrix_matches_mujoco_full_inertia(cobra, mj):
    """crba(q) = mj_fullM at 25 random states, relative error <= 1e-9 (measured ~1e-15)."""
    m, _ = mj
    for q, qd in _states(cobra):
        d = _set(mj, q, qd)
        M_mj = np.zeros((m.nv, m.nv))
        mujoco.mj_fullM(m, d, M_mj)
        assert _rel_err(cr.crba(cobra, q), M_mj) <= 1e-9


def test_bias_force_matches_mujoco_qfrc_bias(cobra, mj):
    """rnea(q, qd, 0) = qfrc_bias (Coriolis + centrifugal + gravity) at 25 random states."""
    for q, qd in _states(cobra):
        d = _set(mj, q, qd)
        assert _rel_err(cr.bias_force(cobra, q, qd), d.qfrc_bias) <= 1e-9


def test_forward_kinematics_matches_mujoco_body_poses(cobra, mj):
    """World position and orientation of every body agree with xpos / xmat to 1e-12."""
    for q, qd in _states(cobra):
        d = _set(mj, q, qd)
        kin = cr.forward_kinematics(cobra, q)
        for i in range(cobra.nb):
            np.testing.assert_allclose(kin.o[i], d.xpos[i + 1], atol=1e-12)
            np.testing.assert_allclose(kin.R[i], d.xmat[i + 1].reshape(3, 3), atol=1e-12)


def test_point_and_body_jacobians_match_mj_jac(cobra, mj):
    """point_jacobian = jacp and R_b J_b[:3] = jacr (world-frame angular rows), every body."""
    m, _ = mj
    rng = np.random.default_rng(3)
    for q, qd in _states(cobra):
        d = _set(mj, q, qd)
        kin = cr.forward_kinematics(cobra, q)
        for b in range(cobra.nb):
            point = rng.normal(size=3) * 0.05
            jacp, jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
            mujoco.mj_jac(m, d, jacp, jacr, kin.o[b] + kin.R[b] @ point, b + 1)
            scale = max(1.0, np.abs(jacp).max())
            assert np.abs(cr.point_jacobian(cobra, q, b, point, kin) - jacp).max() <= 1e-9 * scale
            assert np.abs(kin.R[b] @ cr.body_jacobian(cobra, q, b, kin)[:3] - jacr).max() <= 1e-9


def test_exported_contact_geoms_match_the_model_spheres(cobra, mj):
    """Every contact sphere (body, centre, radius) and the box appear in the MJCF unchanged."""
    m, _ = mj
    for s, (b, c, r) in enumerate(zip(cobra.spheres.body, cobra.spheres.center, cobra.spheres.radius)):
        k = int(np.sum(cobra.spheres.body[:s] == b))
        gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"sphere_{b}_{k}")
        assert gid >= 0 and m.geom_bodyid[gid] == b + 1
        np.testing.assert_allclose(m.geom_pos[gid], c, atol=1e-15)
        assert m.geom_size[gid][0] == r
    box = cobra.boxes[0]
    gid = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"box_{box.body}")
    np.testing.assert_allclose(m.geom_size[gid], box.half, atol=0)


def test_exported_joint_ranges_and_actuator_force_limits(cobra, mj):
    m, _ = mj
    for i, jt in enumerate(cobra.joint_type):
        if jt != "free":
            np.testing.assert_allclose(m.jnt_range[i], [-cobra.q_limit[i], cobra.q_limit[i]], atol=1e-15)
    assert m.nu == 11
    np.testing.assert_allclose(m.actuator_forcerange, [[-9.2, 9.2]] * 11, atol=0)


def test_exported_contact_pairs_have_the_same_friction_as_the_contact_solve(cobra, mj):
    """Each pair of geoms has its own <pair> (assumption A27), so the contacts MuJoCo finds carry
    exactly the contact solve's coefficients: robot-ground and box-ground 1.0, robot-box 0.5 (A22)."""
    from cobra_ref.gaits import RollingGait
    from bodies import pressed_box_state

    m, d = mj
    q = pressed_box_state(cobra, RollingGait(), 0.03)  # box 30 mm into the middle links
    q[2] -= 0.0015  # robot spheres 0.5 mm into the ground
    d.qpos[:] = q
    d.qvel[:] = 0
    mujoco.mj_forward(m, d)
    box_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"box_{cobra.boxes[0].body}")
    ground = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, "ground")
    seen = set()
    for c in d.contact[:d.ncon]:
        pair = {int(c.geom1), int(c.geom2)}
        kind = ("box-ground" if pair == {box_geom, ground} else "robot-ground" if ground in pair else "robot-box")
        expected = cobra.mu_robot_box if kind == "robot-box" else cobra.mu
        assert c.friction[0] == pytest.approx(expected), kind
        seen.add(kind)
    assert seen == {"robot-ground", "robot-box", "box-ground"}
