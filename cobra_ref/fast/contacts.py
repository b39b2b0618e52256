"""The contacts of the scene and their Jacobian J_c, in batches: the fast wing's contact search.

The same contacts, in the same order and with the same frames, as
:func:`cobra_ref.contact.find_contacts` and :func:`cobra_ref.contact.contact_jacobian` (tested
equal), computed with batched NumPy from the world-frame chain terms of
:class:`cobra_ref.fast.chain.ChainModel` instead of one gap function call per pair.
"""

from __future__ import annotations

import numpy as np

from .. import gaps as gapfn
from ..contact import BOX_GROUND, ROBOT_BOX, ROBOT_GROUND, Contacts
from ..spatial import skew_rows
from .chain import ChainModel, ChainTerms
from .gaps import contact_frames, sphere_box_gaps


def find_contacts(model, terms: ChainTerms, margin: float) -> Contacts:
    """Every candidate contact with gap g < margin, in the order of :func:`cobra_ref.contact.find_contacts`.

    The batched form of the reference contact search (the gap functions of
    :mod:`cobra_ref.gaps` row by row).
    """
    sph = model.spheres
    centers = terms.o.take(sph.body, axis=0) + np.einsum("sij,sj->si", terms.R.take(sph.body, axis=0), sph.center)
    # robot spheres on the ground: g = c_z - r, n = e_z (gaps.sphere_plane_gap)
    g_ground = centers[:, 2] - sph.radius
    s = (g_ground < margin).nonzero()[0]  # np.flatnonzero
    c_s = centers[s]
    # the contacts in groups, in order: (kind, body_A, body_B, feature, g, point_A, point_B); the
    # normals only matter on the box (the ground's are e_z)
    groups = [(ROBOT_GROUND, sph.body[s], -1, s, g_ground[s], c_s - sph.radius[s, None] * gapfn.e_z, c_s * _XY)]
    box_normals = []
    for box in model.boxes:
        R_b, p_b = terms.R[box.body], terms.o[box.body]
        # robot spheres on the box (gaps.sphere_box_gap), after a cheap test: the distance to
        # the box is at least the largest excess of the centre over a half extent
        c_b = (centers - p_b) @ R_b
        near = ((np.abs(c_b) - box.half).max(axis=1) - sph.radius < margin).nonzero()[0]
        if len(near):
            g_b, n_b, a_b, b_b = sphere_box_gaps(centers[near], sph.radius[near], R_b, p_b, box.half)
            k = g_b < margin
            groups.append((ROBOT_BOX, sph.body[near[k]], box.body, near[k], g_b[k], a_b[k], b_b[k]))
            box_normals.append(n_b[k])
        # box corners on the ground: g = x_z (gaps.box_corner_plane_gaps)
        corners = p_b + (gapfn.CORNER_SIGNS * box.half) @ R_b.T  # gaps.box_corners, unchecked
        k = (corners[:, 2] < margin).nonzero()[0]
        c_k = corners[k]
        groups.append((BOX_GROUND, np.full(len(k), box.body), -1, k, c_k[:, 2], c_k, c_k * _XY))
    # kind and body_B: each group's constants, repeated (rows of one (2, m) array)
    counts = [len(group[4]) for group in groups]
    kind, body_B = np.repeat(np.array([(group[0], group[2]) for group in groups]).T, counts, axis=1)
    body_A, feature = (np.concatenate([group[i] for group in groups]).astype(int, copy=False) for i in (1, 3))
    g, point_A, point_B = (np.concatenate([group[i] for group in groups]) for i in (4, 5, 6))
    # the ground's frame is the same for every contact: [e_z, e_x, e_y] (gaps.contact_frame); the box's are computed
    frames = np.empty((len(g), 3, 3))
    frames[:] = GROUND_FRAME
    if sum(len(n_b) for n_b in box_normals):
        frames[kind == ROBOT_BOX] = contact_frames(np.concatenate(box_normals))
    return Contacts(kind, body_A, body_B, feature, g, frames, point_A, point_B)


GROUND_FRAME = gapfn.contact_frame(gapfn.e_z)
_XY = np.array([1.0, 1.0, 0.0])  # point * _XY: the point's projection on the ground z = 0


def contact_jacobian(chain: ChainModel, terms: ChainTerms, contacts: Contacts) -> np.ndarray:
    """Stacked relative contact Jacobian J_c (3m, nv), rows [n, t1, t2]^T (J_A - J_B) per contact.

    The batched form of :func:`cobra_ref.contact.contact_jacobian`: every body point's
    Jacobian is J(x) = S_lin - x × S_ang over the dofs that move the body
    (``ChainModel.point_jacobian``), here for all contacts at once.
    """
    J_rel = _point_jacobians(chain, terms, contacts.body_A, contacts.point_A)
    on_body = contacts.body_B >= 0
    if on_body.any():
        J_rel[on_body] -= _point_jacobians(chain, terms, contacts.body_B[on_body], contacts.point_B[on_body])
    # rows n^T J, t1^T J, t2^T J of each contact
    return (contacts.frame.transpose(0, 2, 1) @ J_rel).reshape(3 * contacts.m, chain.nv)


def _point_jacobians(chain: ChainModel, terms: ChainTerms, body: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(k, 3, nv) world Jacobians of the body-fixed points at world positions x (k, 3):
    S_lin - [x]x S_ang on the dofs that move each body."""
    return (terms.S[3:] - skew_rows(x) @ terms.S[:3]) * chain.moves.take(body, axis=0)[:, None, :]
