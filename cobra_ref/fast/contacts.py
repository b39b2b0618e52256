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
    :mod:`cobra_ref.gaps` row by row): ``find_contacts_batch`` for one member.
    """
    return find_contacts_batch(model, terms.R[None], terms.o[None], margin)[0]


def find_contacts_batch(model, R: np.ndarray, o: np.ndarray, margin: float) -> list:
    """[Contacts] of K members with body orientations R (K, nb, 3, 3) and origins o (K, nb, 3)
    (``ChainModel.terms`` of a batch): member k's are the ones ``find_contacts`` finds for its own
    terms, bit for bit."""
    sph, K = model.spheres, len(o)
    centers = o.take(sph.body, axis=-2) + np.einsum("...sij,sj->...si", R.take(sph.body, axis=-3), sph.center)
    # robot spheres on the ground: g = c_z - r, n = e_z (gaps.sphere_plane_gap)
    g_ground = centers[..., 2] - sph.radius
    member, s = (g_ground < margin).nonzero()
    c_s = centers[member, s]
    # the contacts in groups, each group in member order: (member, kind, body_A, body_B, feature, g,
    # point_A, point_B, box normals or None); the normals only matter on the box (the ground's are e_z)
    groups = [(member, ROBOT_GROUND, sph.body[s], -1, s, g_ground[member, s], c_s - sph.radius[s, None] * gapfn.e_z,
               c_s * _XY, None)]
    for box in model.boxes:
        R_b, p_b = R[:, box.body], o[:, box.body]
        # robot spheres on the box (gaps.sphere_box_gap), after a cheap test: the distance to
        # the box is at least the largest excess of the centre over a half extent
        c_b = (centers - p_b[:, None, :]) @ R_b
        near_member, near = ((np.abs(c_b) - box.half).max(axis=-1) - sph.radius < margin).nonzero()
        # the members with spheres near the box (np.unique only when there is more than one member)
        near_members = np.unique(near_member).tolist() if K > 1 else ([0] if len(near) else [])
        for k in near_members:
            idx = near[near_member == k] if K > 1 else near
            g_b, n_b, a_b, b_b = sphere_box_gaps(centers[k, idx], sph.radius[idx], R_b[k], p_b[k], box.half)
            on = g_b < margin
            groups.append((np.full(int(on.sum()), k), ROBOT_BOX, sph.body[idx[on]], box.body, idx[on], g_b[on],
                           a_b[on], b_b[on], n_b[on]))
        # box corners on the ground: g = x_z (gaps.box_corner_plane_gaps)
        corners = p_b[:, None, :] + (gapfn.CORNER_SIGNS * box.half) @ np.swapaxes(R_b, -1, -2)  # gaps.box_corners
        corner_member, k = (corners[..., 2] < margin).nonzero()
        c_k = corners[corner_member, k]
        groups.append((corner_member, BOX_GROUND, np.full(len(k), box.body), -1, k, c_k[:, 2], c_k, c_k * _XY, None))
    return _by_member(groups, K)


def _by_member(groups: list, K: int) -> list:
    """[Contacts] of each of K members from ``find_contacts_batch``'s groups: every group's rows,
    member by member, in the groups' order."""
    counts = [len(group[5]) for group in groups]
    member = np.concatenate([group[0] for group in groups])
    kind, body_B = np.repeat(np.array([(group[1], group[3]) for group in groups]).T, counts, axis=1)
    body_A, feature = (np.concatenate([group[i] for group in groups]).astype(int, copy=False) for i in (2, 4))
    g, point_A, point_B = (np.concatenate([group[i] for group in groups]) for i in (5, 6, 7))
    # the ground's frame is the same for every contact: [e_z, e_x, e_y] (gaps.contact_frame); the box's are computed
    frames = np.empty((len(g), 3, 3))
    frames[:] = GROUND_FRAME
    normals = [group[8] for group in groups if group[8] is not None and len(group[8])]
    if normals:
        frames[kind == ROBOT_BOX] = contact_frames(np.concatenate(normals))
    fields = (kind, body_A, body_B, feature, g, frames, point_A, point_B)
    if K == 1:
        return [Contacts(*fields)]
    order = np.argsort(member, kind="stable")
    fields = [a[order] for a in fields]
    ends = np.searchsorted(member[order], np.arange(K + 1)).tolist()
    return [Contacts(*(a[ends[i]:ends[i + 1]] for a in fields)) for i in range(K)]


GROUND_FRAME = gapfn.contact_frame(gapfn.e_z)
_XY = np.array([1.0, 1.0, 0.0])  # point * _XY: the point's projection on the ground z = 0


def contact_jacobian(chain: ChainModel, terms: ChainTerms, contacts: Contacts) -> np.ndarray:
    """Stacked relative contact Jacobian J_c (3m, nv), rows [n, t1, t2]^T (J_A - J_B) per contact.

    The batched form of :func:`cobra_ref.contact.contact_jacobian`: every body point's
    Jacobian is J(x) = S_lin - x × S_ang over the dofs that move the body
    (``ChainModel.point_jacobian``), here for all contacts at once (``contact_jacobian_batch``
    for one member).
    """
    return contact_jacobian_batch(chain, terms.S[None], [contacts])[0]


def contact_jacobian_batch(chain: ChainModel, S_all: np.ndarray, contacts: list) -> list:
    """[J_c] of K members with motion subspaces S_all (K, 6, nv) and ``contacts`` [Contacts]:
    member k's is the one ``contact_jacobian`` gives for its own terms and contacts, bit for bit."""
    m = [c.m for c in contacts]
    names = ("body_A", "point_A", "body_B", "point_B", "frame")
    if len(contacts) == 1:  # one member: its motion subspace for every contact
        S = S_all[0]
        body_A, point_A, body_B, point_B, frame = (getattr(contacts[0], name) for name in names)
    else:  # each contact's member's motion subspace
        S = S_all[np.repeat(np.arange(len(m)), m)]
        body_A, point_A, body_B, point_B, frame = (np.concatenate([getattr(c, name) for c in contacts]) for name in names)
    J_rel = _point_jacobians(chain, S, body_A, point_A)
    on_body = body_B >= 0
    if on_body.any():
        J_rel[on_body] -= _point_jacobians(chain, S if S.ndim == 2 else S[on_body], body_B[on_body], point_B[on_body])
    # rows n^T J, t1^T J, t2^T J of each contact
    J = frame.transpose(0, 2, 1) @ J_rel
    if len(m) == 1:
        return [J.reshape(3 * m[0], chain.nv)]
    ends = np.concatenate([[0], np.cumsum(m)]).tolist()
    return [J[a:b].reshape(3 * (b - a), chain.nv) for a, b in zip(ends[:-1], ends[1:])]


def _point_jacobians(chain: ChainModel, S: np.ndarray, body: np.ndarray, x: np.ndarray) -> np.ndarray:
    """(k, 3, nv) world Jacobians of the body-fixed points at world positions x (k, 3) of bodies
    whose motion subspace is S (6, nv), or whose motion subspaces are S (k, 6, nv):
    S_lin - [x]x S_ang on the dofs that move each body."""
    return (S[..., 3:, :] - skew_rows(x) @ S[..., :3, :]) * chain.moves.take(body, axis=0)[:, None, :]
