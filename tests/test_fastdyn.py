"""The world-frame fast path gives the same numbers as the readable recursion (the reference)."""

import numpy as np
import pytest

import cobra_ref as cr
from cobra_ref.fast.chain import ChainModel
from cobra_ref.model import ModelError


@pytest.fixture(scope="module")
def fast(cobra):
    return ChainModel(cobra)


def test_fast_mass_matrix_bias_and_poses_equal_the_reference(cobra, fast, rng):
    """M = crba, h = bias_force, R and p = forward_kinematics, at 10 random states, to 1e-12."""
    for _ in range(10):
        q, qd = cr.random_state(cobra, rng)
        terms = fast.terms(q, qd)
        kin = cr.forward_kinematics(cobra, q, qd)
        np.testing.assert_allclose(terms.M, cr.crba(cobra, q), atol=1e-12)
        h = cr.bias_force(cobra, q, qd)
        np.testing.assert_allclose(terms.h, h, atol=1e-12 * max(1.0, np.abs(h).max()))
        np.testing.assert_allclose(terms.R, np.array(kin.R), atol=1e-14)
        np.testing.assert_allclose(terms.o, np.array(kin.o), atol=1e-14)


def test_fast_point_jacobian_equals_the_reference(cobra, fast, rng):
    q, qd = cr.random_state(cobra, rng)
    terms = fast.terms(q, qd)
    kin = cr.forward_kinematics(cobra, q)
    for body in range(cobra.nb):
        point = rng.normal(size=3) * 0.05
        x = kin.o[body] + kin.R[body] @ point
        np.testing.assert_allclose(fast.point_jacobian(terms, body, x), cr.point_jacobian(cobra, q, body, point),
                                   atol=1e-13, err_msg=f"body {body}")


def test_fast_body_velocities_are_the_reference_velocities_in_world_coordinates(cobra, fast, rng):
    """V_i (world, at the world origin) = ^0X_i v_i = inv(X_0[i]) v_i."""
    q, qd = cr.random_state(cobra, rng)
    terms = fast.terms(q, qd)
    kin = cr.forward_kinematics(cobra, q, qd)
    for i in range(cobra.nb):
        np.testing.assert_allclose(terms.V[i], np.linalg.solve(kin.X_0[i], kin.v[i]), atol=1e-12)


def test_fast_path_refuses_a_branching_tree(cobra):
    import dataclasses

    parents = list(cobra.parent)
    parents[5] = 2
    with pytest.raises(ModelError, match="fastdyn needs chains"):
        ChainModel(dataclasses.replace(cobra, parent=tuple(parents)))
