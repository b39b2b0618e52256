"""The contacts of the scene and their Jacobian J_c, in batches: the fast wing's contact search.

Helper (performance): the same contacts, in the same order and with the same frames, as
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


def find_contacts(model, terms: ChainTerms, margin: float) -> Contacts:
    """Every candidate contact with gap g < margin, in the order of :func:`cobra_ref.contact.find_contacts`.

    Helper: the batched form of the reference contact search (the gap functions of
    :mod:`cobra_ref.gaps` row by row).
    """
    sph = model.spheres
    centers = terms.o[sph.body] + np.einsum("sij,sj->si", terms.R[sph.body], sph.center)
    # robot spheres on the ground: g = c_z - r, n = e_z (gaps.sphere_plane_gap)
    s = np.flatnonzero(centers[:, 2] - sph.radius < margin)
    counts = [len(s)]
    body_A, feature, g = [sph.body[s]], [s], [centers[s, 2] - sph.radius[s]]
    n = [_e_z_rows(len(s))]
    point_A, point_B = [centers[s] - sph.radius[s, None] * gapfn.e_z], [centers[s] * [1.0, 1.0, 0.0]]
    box_bodies = []
    for box in model.boxes:
        R_b, p_b = terms.R[box.body], terms.o[box.body]
        # robot spheres on the box (gaps.sphere_box_gap), after a cheap test: the distance to
        # the box is at least the largest excess of the centre over a half extent
        c_b = (centers - p_b) @ R_b
        near = np.flatnonzero(np.max(np.abs(c_b) - box.half, axis=1) - sph.radius < margin)
        if len(near):
            g_b, n_b, a_b, b_b = gapfn.sphere_box_gaps(centers[near], sph.radius[near], R_b, p_b, box.half)
            k = g_b < margin
            near, g_b, n_b, a_b, b_b = near[k], g_b[k], n_b[k], a_b[k], b_b[k]
        else:
            g_b, n_b, a_b, b_b = np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3))
        counts.append(len(near))
        box_bodies.append(box.body)
        body_A.append(sph.body[near]), feature.append(near), g.append(g_b), n.append(n_b)
        point_A.append(a_b), point_B.append(b_b)
        # box corners on the ground: g = x_z (gaps.box_corner_plane_gaps)
        corners = p_b + (gapfn.CORNER_SIGNS * box.half) @ R_b.T  # gaps.box_corners, unchecked
        k = np.flatnonzero(corners[:, 2] < margin)
        counts.append(len(k))
        body_A.append(np.full(len(k), box.body)), feature.append(k), g.append(corners[k, 2])
        n.append(_e_z_rows(len(k)))
        point_A.append(corners[k]), point_B.append(corners[k] * [1.0, 1.0, 0.0])
    kind = np.repeat([ROBOT_GROUND] + [ROBOT_BOX, BOX_GROUND] * len(model.boxes), counts)
    body_B = np.repeat([-1] + [b for body in box_bodies for b in (body, -1)], counts)
    body_A, feature = np.concatenate(body_A).astype(int), np.concatenate(feature).astype(int)
    g, n, point_A, point_B = (np.concatenate(x) for x in (g, n, point_A, point_B))
    # the ground's frame is the same for every contact: [e_z, e_x, e_y] (gaps.contact_frame); the box's are computed
    frames = np.broadcast_to(GROUND_FRAME, (len(g), 3, 3)).copy()
    on_box = kind == ROBOT_BOX
    if on_box.any():
        frames[on_box] = gapfn.contact_frames(n[on_box])
    return Contacts(kind, body_A, body_B, feature, g.astype(float), frames, point_A, point_B)


GROUND_FRAME = gapfn.contact_frame(gapfn.e_z)


_E_Z_ROWS = np.tile(gapfn.e_z, (64, 1))


def _e_z_rows(k: int) -> np.ndarray:
    """k rows of the ground normal e_z (a view of a constant for k <= 64: read, never written)."""
    return _E_Z_ROWS[:k] if k <= len(_E_Z_ROWS) else np.tile(gapfn.e_z, (k, 1))


def contact_jacobian(chain: ChainModel, terms: ChainTerms, contacts: Contacts) -> np.ndarray:
    """Stacked relative contact Jacobian J_c (3m, nv), rows [n, t1, t2]^T (J_A - J_B) per contact.

    Helper: the batched form of :func:`cobra_ref.contact.contact_jacobian`: every body point's
    Jacobian is J(x) = S_lin - x × S_ang over the dofs that move the body
    (``ChainModel.point_jacobian``), here for all contacts at once.
    """
    J_rel = _point_jacobians(chain, terms, contacts.body_A, contacts.point_A)
    on_body = contacts.body_B >= 0
    if on_body.any():
        J_rel[on_body] -= _point_jacobians(chain, terms, contacts.body_B[on_body], contacts.point_B[on_body])
    # rows n^T J, t1^T J, t2^T J of each contact
    return (contacts.frame.transpose(0, 2, 1) @ J_rel).reshape(3 * contacts.m, chain.model.nv)


def _point_jacobians(chain: ChainModel, terms: ChainTerms, body: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(k, 3, nv) world Jacobians of the body-fixed points at world positions x (k, 3):
    S_lin - [x]x S_ang on the dofs that move each body."""
    return (terms.S[3:] - skew_rows(x) @ terms.S[:3]) * chain.moves[body][:, None, :]
