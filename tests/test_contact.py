"""Contact candidates and the stacked relative Jacobian J_c ([COBRA] eq. (3)-(4)).

The reference (cobra_ref/contact.py) calls the one-contact gap functions of cobra_ref/gaps.py;
the fast wing (cobra_ref/fast/contacts.py) computes the same arrays in batches. These tests
check the two equal, contact by contact, and check J_c against finite differences of the gaps:
W_i^T = dg_i/dq along every velocity direction.
"""

import numpy as np
import pytest

from cobra_ref import contact as reference
from cobra_ref.contact import BOX_GROUND, ROBOT_BOX, ROBOT_GROUND
from cobra_ref.fast import contacts as fast
from cobra_ref.fast.chain import ChainModel
from cobra_ref.fast.gaps import contact_frames, sphere_box_gaps
from cobra_ref.gaps import (
    box_corner_plane_gaps,
    contact_frame,
    sphere_box_gap,
    sphere_plane_gap,
)
from cobra_ref.kinematics import integrate
from cobra_ref.quaternion import quat_to_rot
from cobra_ref.gaits import RollingGait
from cobra_ref.robots import cobra_model
from cobra_ref.start import BoxPlacement, placed_state


def _rotation(rng):
    q = rng.normal(size=4)
    return quat_to_rot(q / np.linalg.norm(q))


def test_batched_contact_frames_equal_contact_frame_row_by_row(rng):
    """Random normals (some near +-e_x, where the default seed switches to e_y), with a hint,
    without one (NaN row), and with a hint parallel to n (ignored)."""
    n = rng.normal(size=(40, 3))
    n[:5] = [[1, 0, 0], [-1, 0, 0], [0.95, 0.1, 0], [0, 0, 1], [0, 0, -1]]
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    hints = rng.normal(size=(40, 3))
    hints[::3] = np.nan
    hints[1::7] = 2.5 * n[1::7]
    batched = contact_frames(n, hints)
    for k in range(len(n)):
        expected = contact_frame(n[k], None if np.isnan(hints[k, 0]) else hints[k])
        np.testing.assert_allclose(batched[k], expected, atol=1e-14)


def test_batched_sphere_box_gaps_equal_sphere_box_gap_inside_and_outside(rng):
    R, p, half = _rotation(rng), rng.normal(size=3), np.array([0.3, 0.2, 0.1])
    # centres around the box: half of them inside it (negative gaps), some past edges and corners
    c_b = rng.uniform(-1.6, 1.6, size=(60, 3)) * half
    centers = p + c_b @ R.T
    radii = rng.uniform(0.01, 0.08, size=60)
    g, n, point_A, point_B = sphere_box_gaps(centers, radii, R, p, half)
    assert (g < 0).any() and (g > 0).any()
    for k in range(60):
        ref = sphere_box_gap(centers[k], radii[k], R, p, half)
        np.testing.assert_allclose([g[k]], [ref.g], atol=1e-14)
        np.testing.assert_allclose(n[k], ref.n, atol=1e-14)
        np.testing.assert_allclose(point_A[k], ref.point_A, atol=1e-14)
        np.testing.assert_allclose(point_B[k], ref.point_B, atol=1e-14)


@pytest.fixture
def scene(rng):
    """COBRA in its rolling start shape on the ground, the box 4 mm from a link sphere and turned,
    every joint nudged: contacts of all three kinds within a 1 cm margin."""
    model = cobra_model()
    q, qd = placed_state(model, RollingGait(), BoxPlacement(offset=(0.12, 0.0))), np.zeros(model.nv)
    q[7:18] += rng.normal(scale=0.02, size=11)
    chain = ChainModel(model)
    terms = chain.terms(q, qd)
    sph = model.spheres
    centers = terms.o[sph.body] + np.einsum("sij,sj->si", terms.R[sph.body], sph.center)
    # put the box 4 mm beyond the sphere of L5 (body 5), along +x, at ground level, turned 0.2 rad
    s5 = int(np.flatnonzero(sph.body == 5)[0])
    iq = model.q_idx[model.boxes[0].body]
    half = model.boxes[0].half
    q[iq.start:iq.start + 3] = centers[s5] + [sph.radius[s5] + 0.004 + half[0] / np.cos(0.0), 0.0, 0.0]
    q[iq.start + 2] = half[2] - 0.0005
    q[iq.start + 3:iq.start + 7] = [np.cos(0.1), 0.0, 0.0, np.sin(0.1)]
    qd = rng.normal(scale=0.3, size=model.nv)
    return model, chain, q, qd


def _reference_gaps(model, chain, q):
    """Every sphere-ground, sphere-box and corner-ground gap by the one-contact functions, by key."""
    terms = chain.terms(q, np.zeros(model.nv))
    sph, box = model.spheres, model.boxes[0]
    centers = terms.o[sph.body] + np.einsum("sij,sj->si", terms.R[sph.body], sph.center)
    R_b, p_b = terms.R[box.body], terms.o[box.body]
    out = {}
    for s in range(len(sph.radius)):
        out[(ROBOT_GROUND, int(sph.body[s]), s)] = sphere_plane_gap(centers[s], sph.radius[s])
        out[(ROBOT_BOX, int(sph.body[s]), s)] = sphere_box_gap(centers[s], sph.radius[s], R_b, p_b, box.half)
    for k, gap in enumerate(box_corner_plane_gaps(R_b, p_b, box.half)):
        out[(BOX_GROUND, box.body, k)] = gap
    return out


def test_find_contacts_equals_the_one_contact_gap_functions(scene):
    """The reference and the batched search find the same contacts, in the same order, with the
    gaps, frames and witness points of the one-contact functions."""
    model, chain, q, qd = scene
    contacts = reference.find_contacts(model, q, margin=0.01)
    batched = fast.find_contacts(model, chain.terms(q, qd), margin=0.01)
    for a, b in zip(contacts, batched):
        np.testing.assert_allclose(a, b, atol=1e-14)
    assert set(contacts.kind.tolist()) == {ROBOT_GROUND, ROBOT_BOX, BOX_GROUND}
    ref = _reference_gaps(model, chain, q)
    for i, key in enumerate(contacts.keys()):
        np.testing.assert_allclose(contacts.g[i], ref[key].g, atol=1e-14)
        np.testing.assert_allclose(contacts.frame[i], ref[key].frame, atol=1e-14)
        np.testing.assert_allclose(contacts.point_A[i], ref[key].point_A, atol=1e-14)
        np.testing.assert_allclose(contacts.point_B[i], ref[key].point_B, atol=1e-14)
    # and nothing within the margin is missed
    assert sorted(contacts.keys()) == sorted(k for k, gap in ref.items() if gap.g < 0.01)


def test_normal_rows_of_J_c_are_the_gap_gradients_by_central_differences(scene):
    """W_i^T e_k = (g_i(q (+) h e_k) - g_i(q (-) h e_k)) / 2h for every velocity direction k,
    including the box's: the robot-box rows are relative (eq. (3): the gap moves with the box)."""
    model, chain, q, qd = scene
    contacts = reference.find_contacts(model, q, margin=0.01)
    J = reference.contact_jacobian(model, q, contacts)
    h = 1e-6
    W_fd = np.zeros((contacts.m, model.nv))
    for k in range(model.nv):
        e = np.zeros(model.nv)
        e[k] = 1.0
        plus = _reference_gaps(model, chain, integrate(model, q, e, h))
        minus = _reference_gaps(model, chain, integrate(model, q, e, -h))
        W_fd[:, k] = [(plus[key].g - minus[key].g) / (2 * h) for key in contacts.keys()]
    np.testing.assert_allclose(J[0::3], W_fd, atol=1e-7)
    # the robot-box rows involve both bodies: nonzero in the robot's and in the box's columns
    box_cols = model.v_idx[model.boxes[0].body]
    rb = np.flatnonzero(contacts.kind == ROBOT_BOX)
    assert len(rb) and np.all(np.abs(J[3 * rb][:, box_cols]).max(axis=1) > 0.1)


def test_the_batched_J_c_equals_the_reference(scene):
    """The fast wing's J_c (S_lin - [x]x S_ang over the dofs that move each body, all contacts at
    once) equals the reference's [n t1 t2]^T (J_A - J_B) built from kinematics.point_jacobian."""
    model, chain, q, qd = scene
    terms = chain.terms(q, qd)
    contacts = fast.find_contacts(model, terms, margin=0.01)
    np.testing.assert_allclose(fast.contact_jacobian(chain, terms, contacts),
                               reference.contact_jacobian(model, q, contacts), atol=1e-13)
