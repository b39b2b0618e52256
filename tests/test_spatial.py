"""Spatial algebra identities ([RBDA] ch. 2), each checked on random vectors."""

import numpy as np

from cobra_ref.quaternion import quat_exp, quat_mul, quat_to_rot, rot_to_quat
from cobra_ref.spatial import crf, crm, cross_rows, force_X, inv_X, mcI, plux, rotx, roty, rotz, skew, swap_lin_ang, xlt


def _random_X(rng):
    return plux(quat_to_rot(_unit(rng)), rng.normal(size=3))


def _unit(rng):
    q = rng.normal(size=4)
    return q / np.linalg.norm(q)


def test_skew_is_the_cross_product(rng):
    """skew(w) u = w x u, and skew(w) is antisymmetric."""
    w, u = rng.normal(size=(2, 3))
    np.testing.assert_allclose(skew(w) @ u, np.cross(w, u), atol=1e-15)
    np.testing.assert_allclose(skew(w), -skew(w).T, atol=0)


def test_force_cross_product_is_minus_transpose_of_motion_cross_product(rng):
    """crf(v) = -crm(v)^T ([RBDA] eq. 2.32), and v x v = 0 for motion vectors."""
    v = rng.normal(size=6)
    np.testing.assert_allclose(crf(v), -crm(v).T, atol=0)
    np.testing.assert_allclose(crm(v) @ v, np.zeros(6), atol=1e-15)


def test_cross_product_is_a_derivation_of_transforms(rng):
    """X (v x m) = (X v) x (X m): crm commutes with a change of coordinates ([RBDA] sec. 2.9)."""
    X = _random_X(rng)
    v, m = rng.normal(size=(2, 6))
    np.testing.assert_allclose(X @ crm(v) @ m, crm(X @ v) @ (X @ m), atol=1e-12)


def test_inverse_transform_without_matrix_inverse(rng):
    """inv_X(X) = X^-1 computed as plux(E^T, -E r) ([RBDA] eq. 2.26)."""
    X = _random_X(rng)
    np.testing.assert_allclose(inv_X(X), np.linalg.inv(X), atol=1e-12)
    np.testing.assert_allclose(inv_X(X) @ X, np.eye(6), atol=1e-12)


def test_force_transform_preserves_power(rng):
    """(X m) . (X^* f) = m . f: power is invariant under a change of coordinates."""
    X = _random_X(rng)
    m, f = rng.normal(size=(2, 6))
    np.testing.assert_allclose((X @ m) @ (force_X(X) @ f), m @ f, atol=1e-12)


def test_elementary_rotations_compose_like_plux(rng):
    """rotz(a) is plux(E, 0) with E the coordinate rotation about z; xlt(r) is plux(1, r)."""
    a = rng.uniform(-3, 3)
    c, s = np.cos(a), np.sin(a)
    np.testing.assert_allclose(rotz(a)[:3, :3], [[c, s, 0], [-s, c, 0], [0, 0, 1]], atol=1e-15)
    np.testing.assert_allclose(rotx(a)[:3, :3], [[1, 0, 0], [0, c, s], [0, -s, c]], atol=1e-15)
    np.testing.assert_allclose(roty(a)[:3, :3], [[c, 0, -s], [0, 1, 0], [s, 0, c]], atol=1e-15)
    r = rng.normal(size=3)
    np.testing.assert_allclose(xlt(r), plux(np.eye(3), r), atol=0)


def test_spatial_inertia_gives_rigid_body_kinetic_energy(rng):
    """1/2 v^T I v = 1/2 m |v_c|^2 + 1/2 w^T I_c w, with v_c = v_O + w x c ([RBDA] eq. 2.63)."""
    m, c = 0.7, rng.normal(size=3)
    A = rng.normal(size=(3, 3))
    I_c = A @ A.T + np.eye(3)
    v = rng.normal(size=6)
    w, v_O = v[:3], v[3:]
    v_c = v_O + np.cross(w, c)
    expected = 0.5 * m * v_c @ v_c + 0.5 * w @ I_c @ w
    np.testing.assert_allclose(0.5 * v @ mcI(m, c, I_c) @ v, expected, rtol=1e-13)


def test_swap_lin_ang_is_an_involution(rng):
    v = rng.normal(size=6)
    np.testing.assert_allclose(swap_lin_ang(swap_lin_ang(v)), v, atol=0)
    np.testing.assert_allclose(swap_lin_ang(v)[:3], v[3:], atol=0)


def test_quaternion_matrix_round_trip_and_product(rng):
    """R(a * b) = R(a) R(b); rot_to_quat inverts quat_to_rot up to sign; exp of a rotvec."""
    a, b = _unit(rng), _unit(rng)
    np.testing.assert_allclose(quat_to_rot(quat_mul(a, b)), quat_to_rot(a) @ quat_to_rot(b), atol=1e-14)
    q = rot_to_quat(quat_to_rot(a))
    np.testing.assert_allclose(q, a if a[0] >= 0 else -a, atol=1e-14)
    # rotation by pi/2 about z maps x to y
    np.testing.assert_allclose(quat_to_rot(quat_exp(np.array([0, 0, np.pi / 2]))) @ [1, 0, 0], [0, 1, 0], atol=1e-15)


def test_cross_rows_equals_numpy_cross_with_broadcasting(rng):
    a, b = rng.normal(size=(4, 1, 3)), rng.normal(size=(1, 5, 3))
    np.testing.assert_allclose(cross_rows(a, b), np.cross(a, b), atol=1e-15)
