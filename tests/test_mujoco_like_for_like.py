"""MuJoCo and cobra_ref on the same contact law: worked examples of the mapping of assumption A27.

``to_mjcf`` maps our spring-damper (k, c) onto MuJoCo's direct solref with the smallest impedance
d = 1e-4 and MuJoCo's own inverse weight A_hat (``mjcf`` module docstring), so that MuJoCo's normal
force is f = -k r - c v up to 1e-4 of the contact's acceleration over A_hat. Each test below is a
case whose answer is known by hand: a body at rest sinks by its weight over the stiffness, a
sliding box decelerates at mu g, an explicit damper is stable below 2 / rate.
"""

import numpy as np
import pytest

from bodies import BALL_RADIUS, BOX_MASS, BOX_SIDE, GRAVITY, at_height, ball, box, pressed_box_state, run
import cobra_ref as cr
from cobra_ref.gaits import gait
from cobra_ref.mjcf import IMPEDANCE, TIMESTEP, inverse_weights, pair_parameters

mujoco = pytest.importorskip("mujoco", reason="the MuJoCo comparison needs the optional dependency mujoco")


def mj_run(model, q0, qd0, duration, timestep=TIMESTEP):
    """(qpos, qvel) after ``duration`` of ``to_mjcf(model, timestep)`` from (q0, qd0), no actuators."""
    m = mujoco.MjModel.from_xml_string(cr.to_mjcf(model, timestep=timestep))
    d = mujoco.MjData(m)
    d.qpos[:], d.qvel[:] = q0, qd0
    for _ in range(int(round(duration / timestep))):
        mujoco.mj_step(m, d)
    return d.qpos.copy(), d.qvel.copy()


def test_inverse_weights_are_mujocos_body_invweight0(cobra):
    """A_hat, the mass MuJoCo scales a contact's reference acceleration with, is the mean diagonal of
    J M^-1 J^T at a body's centre of mass at qpos0 ([MJ] "Diagonal approximation"); ours, from
    crba and point_jacobian, equals the compiled model's body_invweight0 to 1e-9 (the box: 1 / m)."""
    m = mujoco.MjModel.from_xml_string(cr.to_mjcf(cobra))
    w = inverse_weights(cobra)
    np.testing.assert_allclose(w, m.body_invweight0[1:, 0], rtol=1e-9)
    np.testing.assert_allclose(w[cobra.boxes[0].body], 1.0 / BOX_MASS, rtol=1e-12)


def test_every_pair_has_its_friction_an_elliptic_cone_and_the_constant_impedance(cobra):
    """One <pair> per pair of geoms (MuJoCo would combine two geoms' frictions by their max):
    robot-ground and box-ground mu = 1.0, robot-box mu_rb = 0.5 (A13, A22), condim 3 on the elliptic
    cone, impedance d = 1e-4 at both ends of solimp, and no contact outside the pairs."""
    m = mujoco.MjModel.from_xml_string(cr.to_mjcf(cobra))
    assert m.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert m.npair == len(pair_parameters(cobra)) == 2 * len(cobra.spheres.body) + 1
    assert np.all(m.geom_contype == 0) and np.all(m.geom_conaffinity == 0)
    box_geom = mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_GEOM, f"box_{cobra.boxes[0].body}")
    for k in range(m.npair):
        robot_box = box_geom in (m.pair_geom1[k], m.pair_geom2[k]) and m.pair_geom1[k] != 0
        assert m.pair_friction[k, 0] == m.pair_friction[k, 1] == (cobra.mu_rb if robot_box else cobra.mu)
        assert m.pair_dim[k] == 3
        np.testing.assert_array_equal(m.pair_solimp[k, :2], [IMPEDANCE, IMPEDANCE])


def test_mujocos_normal_force_is_our_spring_damper(cobra, rng):
    """The mapping itself. On a normal row MuJoCo's force obeys R f = a_ref - a_c ([MJ]
    "Parameters"), and our solref makes a_ref / R = -k r - c v exactly: the spring-damper of A12
    (k = 1e6 N/m, c = 1e3 N s/m) for the distance r and normal velocity v that MuJoCo reports
    (checked to 1e-9 on every loaded contact). What is left, f - (-k r - c v) = -a_c / R =
    -d / (1 - d) a_c / A_hat, together with the friction rows' share of the same size (a
    contact's three rows share the cone), is 1e-4 of the contact's acceleration times 1 / A_hat.
    State: the robot's spheres 1.5-5 mm into the ground, the box 2 mm into links 5 and 6 and
    0.2 mm into the ground, random velocities: forces 60-5000 N, accelerations up to 1e4 m/s^2,
    so up to about 1e-4 x 1e4 m/s^2 x 0.5 kg = 0.5 N on the box's 60 N corners: every force within
    1e-2 of the spring-damper's (at rest a_c = 0: the resting case below)."""
    m = mujoco.MjModel.from_xml_string(cr.to_mjcf(cobra))
    d = mujoco.MjData(m)
    q = pressed_box_state(cobra, gait("C"), 0.005)
    q[2] -= 0.005
    q[cobra.q_idx[cobra.boxes[0].body].start + 2] -= 2e-4
    for scale in (0.0, 0.01, 0.1):
        d.qpos[:], d.qvel[:] = q, scale * rng.normal(size=cobra.nv)
        mujoco.mj_forward(m, d)
        rows = d.contact.efc_address[:d.ncon]
        rows = rows[rows >= 0]  # contacts at exactly r = 0 have no row
        assert len(rows) == 17, f"{len(rows)} loaded contacts: 11 spheres, 4 box corners, 2 robot-box expected"
        spring_damper = -cobra.contact_stiffness * d.efc_pos[rows] - cobra.contact_damping * d.efc_vel[rows]
        np.testing.assert_allclose(d.efc_aref[rows] / d.efc_R[rows], spring_damper, rtol=1e-9,
                                   err_msg=f"a_ref / R, velocity scale {scale}")
        print(f"\nvelocity scale {scale}: max relative difference of the force "
              f"{np.max(np.abs(d.efc_force[rows] / spring_damper - 1)):.2e}")
        np.testing.assert_allclose(d.efc_force[rows], spring_damper, rtol=1e-2, err_msg=f"velocity scale {scale}")


@pytest.mark.parametrize("build, height, n_contacts", [(ball, BALL_RADIUS, 1), (box, BOX_SIDE / 2, 4)],
                         ids=["ball, one contact", "box, four corners"])
def test_a_body_resting_on_the_ground_sinks_by_its_weight_over_the_stiffness(build, height, n_contacts):
    """Resting case. At rest each of n contacts carries m g / n, so the spring sags by
    m g / (n k): 9.81 um for the 1 kg ball on one contact, 1.23 um for the 0.5 kg box on its four
    bottom corners. Ours is exact (1e-9); MuJoCo's within 1e-3 (the mapping's remainder vanishes at
    rest, a_c = 0). With the impedance near 1 instead, MuJoCo's spring would carry only 1 - d of the
    load and the sag would be 1e-4 of this (docs/mujoco.md)."""
    model = build()
    sag = model.mass[0] * GRAVITY / (n_contacts * model.contact_stiffness)
    q0, qd0 = at_height(model, height)
    q_ours, _, _ = run(model, q0, qd0, 500)
    q_mj, qd_mj = mj_run(model, q0, qd0, 0.5)
    print(f"\nsag: hand {sag:.6e} m, ours {height - q_ours[2]:.6e} m, MuJoCo {height - q_mj[2]:.6e} m")
    np.testing.assert_allclose(height - q_ours[2], sag, rtol=1e-9, err_msg="ours")
    np.testing.assert_allclose(height - q_mj[2], sag, rtol=1e-3, err_msg="MuJoCo")
    assert np.abs(qd_mj).max() < 1e-9, "MuJoCo's body is not at rest"


@pytest.mark.parametrize("angle", [0.0, 45.0])
def test_a_box_sliding_on_the_ground_decelerates_at_mu_g_in_both(angle, mu=0.5, v0=0.5, T=0.05):
    """Sliding case. Coulomb's circle: four corners slipping at v each oppose it with mu f_N, in
    sum mu m g against the velocity, so the box slows at mu g along its heading, at any heading
    (a pyramid would pull it towards the facets at 45 degrees). From 0.5 m/s over 0.05 s, both
    within 1 % of mu g = 4.905 m/s^2 and 0.5 degree of the heading. mu = 0.5 keeps the cube off
    its tipping limit (mu = 1, where the load's split between the corners is undetermined)."""
    model = box(mu=mu)
    e = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle)), 0.0])
    q0, qd0 = at_height(model, BOX_SIDE / 2 - BOX_MASS * GRAVITY / (4 * model.contact_stiffness), v=v0 * e)
    _, qd_ours, _ = run(model, q0, qd0, int(round(T / 1e-3)))
    _, qd_mj = mj_run(model, q0, qd0, T)
    for who, qd in (("ours", qd_ours), ("MuJoCo", qd_mj)):
        a = (v0 - np.linalg.norm(qd[:2])) / T
        print(f"\n{who}: deceleration {a:.5f} m/s^2 (mu g = {mu * GRAVITY:.5f})")
        np.testing.assert_allclose(a, mu * GRAVITY, rtol=1e-2, err_msg=who)
        assert abs(np.degrees(np.arctan2(qd[1], qd[0])) - angle) < 0.5, f"{who}: heading changed"


def test_the_timestep_resolves_the_explicit_contact_damping():
    """MuJoCo evaluates the contact force at the start of the step (d = 1e-4 leaves nothing implicit),
    so the box's heave, damped by its four corners at the rate 4 c / m = 8000 / s, is an explicit
    damper: stable for dt < 2 m / (4 c) = 0.25 ms. At TIMESTEP = 0.05 ms the resting box comes to
    rest (|qd| < 1e-9 after 0.5 s); at 0.3 ms it never does (|qd| > 1e-3)."""
    model = box()
    q0, qd0 = at_height(model, BOX_SIDE / 2)
    limit = 2 * BOX_MASS / (4 * model.contact_damping)
    assert TIMESTEP < limit < 3e-4
    assert np.abs(mj_run(model, q0, qd0, 0.5)[1]).max() < 1e-9
    assert np.abs(mj_run(model, q0, qd0, 0.5, timestep=3e-4)[1]).max() > 1e-3
