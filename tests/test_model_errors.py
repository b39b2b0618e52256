"""Bad input gets a clear error naming what is wrong (and never a silent wrong answer)."""

import dataclasses

import numpy as np
import pytest

import cobra_ref as cr
from cobra_ref import ModelError


def test_wrong_length_q_is_rejected_with_the_expected_shape(cobra):
    with pytest.raises(ModelError, match=r"q: expected shape \(25,\)"):
        cr.crba(cobra, np.zeros(24))


def test_wrong_length_qd_is_rejected(cobra):
    with pytest.raises(ModelError, match=r"qd: expected shape \(23,\)"):
        cr.bias_force(cobra, cr.neutral_q(cobra), np.zeros(17))


def test_zero_quaternion_is_rejected_naming_the_body(cobra):
    q = cr.neutral_q(cobra)
    q[3:7] = 0.0
    with pytest.raises(ModelError, match="zero quaternion for free body 'head'"):
        cr.forward_kinematics(cobra, q)


def test_non_unit_quaternion_is_rejected_naming_the_body(cobra):
    q = cr.neutral_q(cobra)
    q[cobra.q_idx[12].start + 3] = 2.0
    with pytest.raises(ModelError, match="non-unit quaternion for free body 'box'"):
        cr.crba(cobra, q)


@pytest.mark.parametrize("name", ["q", "qd", "qdd"])
def test_nan_entries_are_rejected_with_their_indices(cobra, name):
    args = {"q": cr.neutral_q(cobra), "qd": np.zeros(cobra.nv), "qdd": np.zeros(cobra.nv)}
    args[name] = args[name].copy()
    args[name][9] = np.nan
    with pytest.raises(ModelError, match=rf"{name}: non-finite entries .* \[9\]"):
        cr.rnea(cobra, args["q"], args["qd"], args["qdd"])


@pytest.mark.parametrize("mass", [0.0, -0.5, np.nan])
def test_non_positive_mass_in_a_custom_model_is_rejected(cobra, mass):
    masses = list(cobra.mass)
    masses[4] = mass
    with pytest.raises(ModelError, match=r"body 4 \('L4'\): mass must be positive"):
        dataclasses.replace(cobra, mass=tuple(masses))


def test_non_positive_definite_inertia_is_rejected(cobra):
    I_com = list(cobra.I_com)
    I_com[2] = np.diag([1e-4, -1e-4, 1e-4])
    with pytest.raises(ModelError, match=r"body 2 \('L2'\): inertia is not positive definite"):
        dataclasses.replace(cobra, I_com=tuple(I_com))


def test_inertia_violating_the_triangle_inequality_is_rejected(cobra):
    I_com = list(cobra.I_com)
    I_com[3] = np.diag([1e-4, 1e-4, 5e-4])  # 1e-4 + 1e-4 < 5e-4: no rigid body has these moments
    with pytest.raises(ModelError, match="triangle inequality"):
        dataclasses.replace(cobra, I_com=tuple(I_com))


def test_unknown_body_name_lists_the_bodies(cobra):
    with pytest.raises(ModelError, match="unknown body 'neck'; bodies are head, L1"):
        cr.point_jacobian(cobra, cr.neutral_q(cobra), "neck", np.zeros(3))


def test_parent_must_precede_child(cobra):
    parents = list(cobra.parent)
    parents[3] = 5
    with pytest.raises(ModelError, match="parent 5 must be -1 or a lower index"):
        dataclasses.replace(cobra, parent=tuple(parents))
