"""Worked identities of [COBRA] eq. (1), M qdd + h = tau + sum J^T f, at random states.

Every test uses COBRA with the box (nv = 23) or the smallest toy that shows the fact.
"""

import dataclasses

import numpy as np
import pytest

import cobra_ref as cr
from cobra_ref.kinematics import forward_kinematics

N_STATES = 5


def test_mass_matrix_is_symmetric_positive_definite(cobra, rng):
    """M(q) = M(q)^T > 0: kinetic energy is a positive definite quadratic form in qd."""
    for _ in range(N_STATES):
        q, _ = cr.random_state(cobra, rng)
        M = cr.crba(cobra, q)
        np.testing.assert_allclose(M, M.T, atol=1e-15)
        assert np.linalg.eigvalsh(M).min() > 0


def test_mass_matrix_columns_are_rnea_with_unit_accelerations(cobra, rng):
    """M[:, k] = rnea(q, qd, e_k) - rnea(q, qd, 0)   ([RBDA] ch. 6).

    Inverse dynamics is affine in the acceleration, so differences of rnea() along unit
    accelerations recover crba() column by column, velocity terms cancelling exactly.
    """
    q, qd = cr.random_state(cobra, rng)
    M = cr.crba(cobra, q)
    h = cr.rnea(cobra, q, qd, np.zeros(cobra.nv))
    for k in range(cobra.nv):
        e_k = np.eye(cobra.nv)[k]
        np.testing.assert_allclose(cr.rnea(cobra, q, qd, e_k) - h, M[:, k], atol=1e-12, err_msg=f"column {k}")


def test_rnea_is_mass_matrix_times_acceleration_plus_bias(cobra, rng):
    """rnea(q, qd, qdd) = M qdd + h with h = bias_force(q, qd) = rnea(q, qd, 0)."""
    for _ in range(N_STATES):
        q, qd = cr.random_state(cobra, rng)
        qdd = rng.normal(size=cobra.nv)
        lhs = cr.crba(cobra, q) @ qdd + cr.bias_force(cobra, q, qd)
        np.testing.assert_allclose(cr.rnea(cobra, q, qd, qdd), lhs, atol=1e-11)


def test_forward_dynamics_inverts_inverse_dynamics(cobra, rng):
    """rnea(q, qd, forward_dynamics(q, qd, tau)) = tau."""
    q, qd = cr.random_state(cobra, rng)
    tau = rng.normal(size=cobra.nv)
    qdd = cr.forward_dynamics(cobra, q, qd, tau)
    np.testing.assert_allclose(cr.rnea(cobra, q, qd, qdd), tau, atol=1e-10)


def test_kinetic_energy_is_sum_of_body_kinetic_energies(cobra, rng):
    """1/2 qd^T M qd = sum_i 1/2 v_i^T I_i v_i ([RBDA] eq. 2.67)."""
    for _ in range(N_STATES):
        q, qd = cr.random_state(cobra, rng)
        T_M = 0.5 * qd @ cr.crba(cobra, q) @ qd
        np.testing.assert_allclose(T_M, cr.body_kinetic_energies(cobra, q, qd).sum(), rtol=1e-13)


def test_gravity_force_is_the_gradient_of_potential_energy(cobra, rng):
    """h(q, 0) = dV/dq along each velocity direction: V(q (+) eps e_k) - V(q (-) eps e_k) / 2 eps.

    With qd = 0 the bias force holds only gravity, g(q) = dV/dq (Lagrange's equations).
    """
    q, _ = cr.random_state(cobra, rng)
    g = cr.bias_force(cobra, q, np.zeros(cobra.nv))
    eps = 1e-6
    for k in range(cobra.nv):
        e_k = np.eye(cobra.nv)[k]
        dV = (cr.potential_energy(cobra, cr.integrate(cobra, q, e_k, eps))
              - cr.potential_energy(cobra, cr.integrate(cobra, q, e_k, -eps))) / (2 * eps)
        np.testing.assert_allclose(g[k], dV, atol=1e-7, err_msg=f"dof {k}")


def _finite_difference_velocity(model, q, qd, body, point, eps=1e-6):
    """World velocity of a body point by central differences of forward kinematics along qd."""
    def world_point(qq):
        kin = forward_kinematics(model, qq)
        return kin.o[body] + kin.R[body] @ point
    return (world_point(cr.integrate(model, q, qd, eps)) - world_point(cr.integrate(model, q, qd, -eps))) / (2 * eps)


def test_point_jacobian_matches_finite_differences_of_kinematics(cobra, rng):
    """J_p qd = d/dt (world position of the point), checked by central differences (eps = 1e-6)."""
    for body in [0, 6, 11, 12]:
        q, qd = cr.random_state(cobra, rng)
        point = rng.normal(size=3) * 0.05
        J = cr.point_jacobian(cobra, q, body, point)
        np.testing.assert_allclose(J @ qd, _finite_difference_velocity(cobra, q, qd, body, point),
                                   atol=1e-7, err_msg=f"body {body}")


def test_body_jacobian_angular_rows_match_finite_differences_of_orientation(cobra, rng):
    """R^T dR/dt = [w_body]x: the angular rows of J_b times qd, from central differences."""
    q, qd = cr.random_state(cobra, rng)
    eps = 1e-6
    for body in [0, 5, 11]:
        R_plus = forward_kinematics(cobra, cr.integrate(cobra, q, qd, eps)).R[body]
        R_minus = forward_kinematics(cobra, cr.integrate(cobra, q, qd, -eps)).R[body]
        R = forward_kinematics(cobra, q).R[body]
        W = R.T @ (R_plus - R_minus) / (2 * eps)
        w_fd = np.array([W[2, 1], W[0, 2], W[1, 0]])
        np.testing.assert_allclose(cr.body_jacobian(cobra, q, body)[:3] @ qd, w_fd, atol=1e-7)


def _rk4_step(model, q, qd, dt):
    """Classical RK4 on (q, qd) with positions advanced by integrate() (a Lie-group variant)."""
    tau = np.zeros(model.nv)
    k1v, k1a = qd, cr.forward_dynamics(model, q, qd, tau)
    q2, v2 = cr.integrate(model, q, k1v, dt / 2), qd + dt / 2 * k1a
    k2v, k2a = v2, cr.forward_dynamics(model, q2, v2, tau)
    q3, v3 = cr.integrate(model, q, k2v, dt / 2), qd + dt / 2 * k2a
    k3v, k3a = v3, cr.forward_dynamics(model, q3, v3, tau)
    q4, v4 = cr.integrate(model, q, k3v, dt), qd + dt * k3a
    k4v, k4a = v4, cr.forward_dynamics(model, q4, v4, tau)
    q_next = cr.integrate(model, q, (k1v + 2 * k2v + 2 * k3v + k4v) / 6, dt)
    return q_next, qd + dt / 6 * (k1a + 2 * k2a + 2 * k3a + k4a)


@pytest.mark.slow
def test_free_floating_snake_conserves_momentum_without_gravity(cobra_robot, rng):
    """No gravity, no contact, no torque: total spatial momentum is constant (Newton-Euler).

    The snake tumbles freely for 0.2 s; d/dt (sum X_0^T I v) = sum of external forces = 0.
    Energy is conserved as well. RK4 at dt = 2 ms keeps both to ~1e-8 relative.
    """
    model = dataclasses.replace(cobra_robot, gravity=np.zeros(3))
    q, qd = cr.random_state(model, rng, scale=0.5)
    h0 = cr.spatial_momentum(model, q, qd)
    T0 = cr.kinetic_energy(model, q, qd)
    for _ in range(100):
        q, qd = _rk4_step(model, q, qd, 2e-3)
    np.testing.assert_allclose(cr.spatial_momentum(model, q, qd), h0, atol=1e-7 * np.abs(h0).max())
    np.testing.assert_allclose(cr.kinetic_energy(model, q, qd), T0, rtol=1e-7)


def test_horizontal_link_gravity_torque_by_hand():
    """A link held horizontal needs tau = m g l/2 about its pitch joint.

    chain(2): link 0 yaws (Rz) at the origin, link 1 pitches (Ry) at x = -l. With q = 0 both
    links lie along -x. Gravity acts on link 1 at its centre, r = (-l/2, 0, 0) from the pitch
    joint: r x F = (-l/2, 0, 0) x (0, 0, -m g) = (0, -m g l/2, 0). At rest M qdd + h = tau
    with qdd = 0, so the holding torque is h_1 = -(r x F)_y = +m g l/2 = 1.5 * 9.81 * 0.2 N m.
    The yaw axis is vertical, so gravity has no moment about it: h_0 = 0.
    """
    model = cr.chain(2, link_length=0.4, link_mass=1.5)
    h = cr.bias_force(model, np.zeros(2), np.zeros(2))
    np.testing.assert_allclose(h[1], 1.5 * 9.81 * 0.4 / 2, rtol=1e-14)
    np.testing.assert_allclose(h[0], 0.0, atol=1e-14)
