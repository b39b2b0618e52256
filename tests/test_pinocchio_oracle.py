"""Pinocchio as an independent oracle for COBRA's kinematics and [COBRA] eq. (1).

The Pinocchio model is built *programmatically* from the cobra_ref Model's own numbers
(joint placements, masses, COMs, rotational inertias, gravity), not parsed from MJCF, so the
only things shared by the two sides are the physical parameters. Everything else - the
recursions, the spatial algebra, the joint models - is Pinocchio's C++ against our Python.

The one thing that needs care is the free joint of the head, whose coordinates differ:

===========  =========================================  ================================
coordinate   cobra_ref / MuJoCo                         Pinocchio ``JointModelFreeFlyer``
===========  =========================================  ================================
q (7)        [x, y, z, qw, qx, qy, qz] (scalar first)   [x, y, z, qx, qy, qz, qw]
qd / v (6)   [v_world (3), w_body (3)]                  [R^T v_world (3), w_body (3)]
qdd / a (6)  d/dt qd                                    d/dt v (extra term, see below)
===========  =========================================  ================================

Both velocities describe the same motion, so they are related by a configuration-dependent
linear map ``v_pin = T(q) qd``; see :func:`to_pinocchio_state` for the derivation and the
maps back (``tau_ours = T^T tau_pin``, ``M_ours = T^T M_pin T``).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import pytest

pin = pytest.importorskip("pinocchio")

import cobra_ref as cr  # noqa: E402
from cobra_ref.quaternion import quat_to_rot  # noqa: E402
from cobra_ref.spatial import swap_lin_ang  # noqa: E402

N_STATES = 25
RTOL = 1e-9  # relative to the largest entry of the expected array


# --------------------------------------------------------------------------------------------
# Building the oracle
# --------------------------------------------------------------------------------------------

_PIN_JOINT = {"free": pin.JointModelFreeFlyer, "Rx": pin.JointModelRX, "Ry": pin.JointModelRY,
              "Rz": pin.JointModelRZ}


def pinocchio_model_from_cobra(model: cr.Model) -> "pin.Model":
    """Pinocchio model with the same tree, placements, inertias and gravity as ``model``.

    Body ``i`` of cobra_ref is Pinocchio joint ``i + 1`` (Pinocchio's joint 0 is the universe).
    ``tree_rot[i]`` is the orientation of joint ``i``'s frame in the parent frame and
    ``tree_pos[i]`` its origin (cobra_ref.model), which is exactly Pinocchio's joint placement
    ``SE3(rotation, translation)``. Body frames are the joints' successor frames on both sides,
    so each body's inertia is appended at the identity placement.
    """
    pm = pin.Model()
    pm.name = model.name
    for i in range(model.nb):
        placement = pin.SE3(np.asarray(model.tree_rot[i], dtype=float),
                            np.asarray(model.tree_pos[i], dtype=float))
        jid = pm.addJoint(model.parent[i] + 1, _PIN_JOINT[model.joint_type[i]](), placement,
                          model.joint_names[i])
        assert jid == i + 1
        pm.appendBodyToJoint(jid, pin.Inertia(model.mass[i], np.asarray(model.com[i], dtype=float),
                                              np.asarray(model.I_com[i], dtype=float)), pin.SE3.Identity())
    pm.gravity = pin.Motion(np.asarray(model.gravity, dtype=float), np.zeros(3))  # linear, angular
    return pm


# --------------------------------------------------------------------------------------------
# The coordinate change (the helper under test)
# --------------------------------------------------------------------------------------------

class PinocchioState(NamedTuple):
    """A cobra_ref state expressed in Pinocchio's coordinates, with the maps back."""

    q: np.ndarray  # (nq,) Pinocchio configuration
    v: np.ndarray  # (nv,) Pinocchio velocity, v = T qd
    a: np.ndarray  # (nv,) Pinocchio acceleration, a = T qdd + Tdot qd
    T: np.ndarray  # (nv, nv) velocity map, v = T qd

    def force_to_ours(self, tau_pin: np.ndarray) -> np.ndarray:
        """Generalized force in cobra_ref coordinates: tau_ours = T^T tau_pin."""
        return self.T.T @ tau_pin

    def mass_matrix_to_ours(self, M_pin: np.ndarray) -> np.ndarray:
        """Mass matrix in cobra_ref coordinates: M_ours = T^T M_pin T."""
        return self.T.T @ M_pin @ self.T


def to_pinocchio_state(model: cr.Model, q, qd, qdd=None) -> PinocchioState:
    """Convert (q, qd, qdd) from cobra_ref's (MuJoCo's) free-joint convention to Pinocchio's.

    Worked derivation, per free joint with orientation R = R(quat) (body -> parent frame):

    * Configuration: only the quaternion's storage order differs,
      ``[x, y, z, qw, qx, qy, qz] -> [x, y, z, qx, qy, qz, qw]``.
    * Velocity: MuJoCo stores the origin's velocity in WORLD coordinates, Pinocchio in the
      LOCAL (body) frame, so ``v_pin_lin = R^T v_world``; the angular velocity is in the body
      frame on both sides. Hence ``v_pin = T qd`` with ``T = blockdiag(R^T, I_3, I_(nv-6))``.
    * Acceleration: Pinocchio's ``a`` is the time derivative of its own ``v``, and ``T``
      depends on q. Differentiating ``v_pin_lin = R^T v_world`` with ``Rdot = R [w_body]x``,
      i.e. ``d/dt R^T = -[w_body]x R^T``::

          a_pin_lin = R^T a_world + (d/dt R^T) v_world = R^T a_world - w_body x (R^T v_world)

      The extra term is the rate at which the world-fixed vector v_world *appears* to rotate
      when seen from the turning body axes: even with a_world = 0 (a head coasting in a straight
      line while spinning) the body-frame components of its velocity change. So
      ``a_pin = T qdd + Tdot qd``, not ``T qdd``. (cobra_ref carries the same term as the free
      joint's ``c_J``, see cobra_ref.joints.jcalc.)
    * Forces (back): power is coordinate-free, ``tau_ours . qd = tau_pin . v_pin =
      tau_pin . (T qd)`` for every qd, so ``tau_ours = T^T tau_pin``.
    * Mass matrix (back): kinetic energy is coordinate-free, ``1/2 qd^T M_ours qd =
      1/2 (T qd)^T M_pin (T qd)``, so ``M_ours = T^T M_pin T``.
    * Bias (back): ``h_ours = rnea_ours(q, qd, 0) = T^T rnea_pin(q, v, Tdot qd)``, i.e.
      ``h_ours = T^T (nle_pin + M_pin Tdot qd)`` - Pinocchio's ``nle`` alone is not h_ours.

    Revolute joints have identical coordinates on both sides (T = 1).
    """
    q = model.check_q(q)
    qd = model.check_qd(qd)
    qdd = np.zeros(model.nv) if qdd is None else model.check_qd(qdd, "qdd")
    q_pin, v_pin, a_pin, T = q.copy(), qd.copy(), qdd.copy(), np.eye(model.nv)
    for i, jt in enumerate(model.joint_type):
        if jt != "free":
            continue
        iq, iv = model.q_idx[i], model.v_idx[i]
        pos, quat_wxyz = q[iq][:3], q[iq][3:]
        v_world, w_body = qd[iv][:3], qd[iv][3:]
        a_world, wdot_body = qdd[iv][:3], qdd[iv][3:]
        R = quat_to_rot(quat_wxyz)
        q_pin[iq] = np.concatenate([pos, quat_wxyz[1:], quat_wxyz[:1]])
        v_lin = R.T @ v_world
        v_pin[iv] = np.concatenate([v_lin, w_body])
        a_pin[iv] = np.concatenate([R.T @ a_world - np.cross(w_body, v_lin), wdot_body])
        T[iv.start:iv.start + 3, iv.start:iv.start + 3] = R.T
    return PinocchioState(q_pin, v_pin, a_pin, T)


def assert_close_relative(actual, expected, rtol=RTOL, err_msg=""):
    """|actual - expected| <= rtol * max|expected| entrywise (relative to the largest entry)."""
    expected = np.asarray(expected)
    scale = float(np.max(np.abs(expected)))
    np.testing.assert_allclose(actual, expected, rtol=0, atol=rtol * scale, err_msg=err_msg)


@pytest.fixture(scope="module")
def pin_robot():
    """(cobra_ref model, Pinocchio model, Pinocchio data) for COBRA alone (nq = 18, nv = 17)."""
    model = cr.cobra_model(with_box=False)
    pm = pinocchio_model_from_cobra(model)
    return model, pm, pm.createData()


# --------------------------------------------------------------------------------------------
# The oracle itself is what we think it is
# --------------------------------------------------------------------------------------------

def test_pinocchio_model_built_from_cobra_has_the_same_dimensions_mass_and_gravity(pin_robot):
    """Sanity of the construction: 12 bodies, nq = 18, nv = 17, same total mass and gravity."""
    model, pm, _ = pin_robot
    assert (model.nb, model.nq, model.nv) == (12, 18, 17)
    assert (pm.njoints - 1, pm.nq, pm.nv) == (model.nb, model.nq, model.nv)
    np.testing.assert_allclose(sum(Y.mass for Y in pm.inertias), sum(model.mass), rtol=1e-15)
    np.testing.assert_array_equal(pm.gravity.linear, model.gravity)


def test_body_poses_match_pinocchio_forward_kinematics_at_random_states(pin_robot, rng):
    """oMi (Pinocchio) == (R[i], p[i]) (cobra_ref) for all 12 bodies ([RBDA] ch. 4).

    Also checks the quaternion reordering: Pinocchio reads [qx, qy, qz, qw] and must produce
    the same head orientation as cobra_ref's [qw, qx, qy, qz].
    """
    model, pm, data = pin_robot
    for k in range(N_STATES):
        q, qd = cr.random_state(model, rng)
        pin.forwardKinematics(pm, data, to_pinocchio_state(model, q, qd).q)
        kin = cr.forward_kinematics(model, q)
        for i in range(model.nb):
            oMi = data.oMi[i + 1]
            np.testing.assert_allclose(oMi.rotation, kin.R[i], atol=1e-12,
                                       err_msg=f"R of body {model.body_names[i]} at state {k}")
            np.testing.assert_allclose(oMi.translation, kin.o[i], atol=1e-12,
                                       err_msg=f"p of body {model.body_names[i]} at state {k}")


def test_velocity_map_gives_pinocchio_the_same_body_velocities(pin_robot, rng):
    """v_pin = T qd describes the same motion: every body's spatial velocity agrees.

    Pinocchio's data.v[i] is body i's spatial velocity in its local frame, linear first;
    cobra_ref's kin.v[i] is the same vector angular first ([RBDA] sec. 2.9), so they differ
    by swap_lin_ang only. For the head this reads [R^T v_world; w_body] on both sides.
    """
    model, pm, data = pin_robot
    for k in range(N_STATES):
        q, qd = cr.random_state(model, rng)
        st = to_pinocchio_state(model, q, qd)
        pin.forwardKinematics(pm, data, st.q, st.v)
        kin = cr.forward_kinematics(model, q, qd)
        for i in range(model.nb):
            np.testing.assert_allclose(data.v[i + 1].vector, swap_lin_ang(kin.v[i]), atol=1e-12,
                                       err_msg=f"velocity of body {model.body_names[i]} at state {k}")


def test_acceleration_map_is_the_time_derivative_of_the_velocity_map(pin_robot, rng, dt=1e-5):
    """a_pin = d/dt (T(q) qd) = T qdd + Tdot qd, checked by central differences in time.

    Move along the path with constant cobra_ref acceleration qdd through (q, qd) at t = 0:
    qd(t) = qd + t qdd and q(t) = integrate(q, qd + t/2 qdd, t), which is exact for the
    position (p + t v_world + t^2/2 a_world) and correct to O(t^3), an odd error, for the
    orientation. Then (v_pin(dt) - v_pin(-dt)) / (2 dt) = a_pin + O(dt^2). The naive guess
    T qdd misses - w_body x (R^T v_world) and fails the same check by O(|w| |v|).
    """
    model, _, _ = pin_robot
    for k in range(N_STATES):
        q, qd = cr.random_state(model, rng)
        qdd = rng.normal(size=model.nv)

        def v_pin_at(t):
            q_t = cr.integrate(model, q, qd + 0.5 * t * qdd, t)
            return to_pinocchio_state(model, q_t, qd + t * qdd).v

        fd = (v_pin_at(dt) - v_pin_at(-dt)) / (2 * dt)
        st = to_pinocchio_state(model, q, qd, qdd)
        np.testing.assert_allclose(st.a, fd, atol=1e-7, err_msg=f"a_pin vs finite differences at state {k}")
        # the naive error is the vector w_body x (R^T v_world), whose largest entry is >= |.|/sqrt(3)
        extra = np.linalg.norm(np.cross(qd[3:6], st.v[:3]))
        if extra > 1e-3:
            assert np.max(np.abs(st.T @ qdd - fd)) > 0.5 * extra, f"naive T qdd passed at state {k}"


# --------------------------------------------------------------------------------------------
# [COBRA] eq. (1) against Pinocchio
# --------------------------------------------------------------------------------------------

def test_mass_matrix_matches_pinocchio_crba_at_random_states(pin_robot, rng):
    """M_ours(q) = T^T M_pin(q) T   ([RBDA] Table 6.2 on both sides).

    Kinetic energy 1/2 qd^T M qd does not depend on the coordinates, and v_pin = T qd, so the
    two mass matrices are congruent. pinocchio.crba fills only the upper triangle; the lower
    one is its transpose.
    """
    model, pm, data = pin_robot
    for k in range(N_STATES):
        q, qd = cr.random_state(model, rng)
        st = to_pinocchio_state(model, q, qd)
        M_pin = pin.crba(pm, data, st.q).copy()
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        assert_close_relative(cr.crba(model, q), st.mass_matrix_to_ours(M_pin),
                              err_msg=f"mass matrix at state {k}")


def test_rnea_matches_pinocchio_rnea_with_random_accelerations(pin_robot, rng):
    """tau_ours = M qdd + h = T^T rnea_pin(q_pin, T qd, T qdd + Tdot qd)   ([RBDA] Table 5.1).

    Power tau . qd is coordinate-free, hence tau_ours = T^T tau_pin; the acceleration passed
    to Pinocchio must include the -w_body x (R^T v_world) term of to_pinocchio_state.
    """
    model, pm, data = pin_robot
    for k in range(N_STATES):
        q, qd = cr.random_state(model, rng)
        qdd = rng.normal(size=model.nv)
        st = to_pinocchio_state(model, q, qd, qdd)
        tau_pin = pin.rnea(pm, data, st.q, st.v, st.a).copy()
        assert_close_relative(cr.rnea(model, q, qd, qdd), st.force_to_ours(tau_pin),
                              err_msg=f"rnea at state {k}")


def test_bias_force_matches_pinocchio_nle_plus_the_free_joint_velocity_term(pin_robot, rng):
    """h_ours = T^T (nle_pin + M_pin Tdot qd)   (MuJoCo's qfrc_bias vs Pinocchio's nle).

    qdd = 0 in our coordinates is not a = 0 in Pinocchio's: it is a = Tdot qd, whose head part
    is -w_body x (R^T v_world). Pinocchio's nle(q, v) = rnea_pin(q, v, 0), so the bias picks up
    M_pin Tdot qd; with it the two agree, without it they differ whenever the head spins while
    it translates.
    """
    model, pm, data = pin_robot
    for k in range(N_STATES):
        q, qd = cr.random_state(model, rng)
        st = to_pinocchio_state(model, q, qd)  # qdd = 0: st.a = Tdot qd
        nle = pin.nle(pm, data, st.q, st.v).copy()
        M_pin = pin.crba(pm, data, st.q).copy()
        M_pin = np.triu(M_pin) + np.triu(M_pin, 1).T
        h = cr.bias_force(model, q, qd)
        assert_close_relative(h, st.force_to_ours(nle + M_pin @ st.a), err_msg=f"bias at state {k}")
        naive_error = np.max(np.abs(h - st.force_to_ours(nle)))
        assert naive_error > 1e-3 * np.max(np.abs(h)), f"nle alone matched at state {k}"
