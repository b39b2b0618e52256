"""The contacts of the COBRA + box scene and their stacked relative Jacobian J_c.

Implements: [COBRA] eq. (3)-(4). For each contact i between body A and body B (the ground or
the box), the gap g_i(q) of :mod:`cobra_ref.gaps` and its rate

    g'_i = n_i . (v_A(point_A) - v_B(point_B)) = W_i^T u,    W_i^T = n_i^T (J_A - J_B)

which is *relative*: when B is the moving box, g' depends on the box's motion too (the paper's
dg/dt != 0 for a moving object). Stacking [n, t1, t2]^T (J_A - J_B) for every contact gives
J_c with g' = J_c u (eq. (4)); rows are ordered contact by contact.

Contact kinds (``KINDS``): robot sphere on the ground, robot sphere on the box, box corner on
the ground. Body A is the robot link (or the box, for box-ground); the normal points from B to
A, so a positive normal impulse pushes A away from B. A candidate enters the contact problem
when its gap is below ``margin``: the least-action problem then decides whether it carries a
force (it may close at most its gap within one step, so a fast approach cannot tunnel).

This module is the readable reference: one gap function call and one point Jacobian per
contact. :mod:`cobra_ref.fast.contacts` computes the same arrays in batches (tested equal).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import gaps
from .kinematics import Kinematics, forward_kinematics, point_jacobian
from .model import Model

KINDS = ("robot-ground", "robot-box", "box-ground")
ROBOT_GROUND, ROBOT_BOX, BOX_GROUND = 0, 1, 2


class Contacts(NamedTuple):
    """Candidate contacts as a struct of arrays (m entries)."""

    kind: np.ndarray  # (m,) index into KINDS
    body_A: np.ndarray  # (m,) body of point_A
    body_B: np.ndarray  # (m,) body of point_B, -1 for the ground
    feature: np.ndarray  # (m,) sphere index (robot contacts) or box corner index (box-ground)
    g: np.ndarray  # (m,) signed gaps [m]
    frame: np.ndarray  # (m, 3, 3) columns [n, t1, t2], world
    point_A: np.ndarray  # (m, 3) witness point on A, world
    point_B: np.ndarray  # (m, 3) witness point on B, world

    @property
    def m(self) -> int:
        return len(self.g)

    def keys(self) -> list[tuple[int, int, int]]:
        """Identity of each contact across steps (kind, body A, feature): warm starts and logs."""
        return list(zip(self.kind.tolist(), self.body_A.tolist(), self.feature.tolist()))


def find_contacts(model: Model, q, margin: float, kin: Kinematics | None = None) -> Contacts:
    """Every candidate contact with gap g < margin, in a fixed order: robot spheres on the ground,
    then on each box, then each box's corners on the ground.

    Implements: the contact set of [COBRA] eq. (2)-(3), with the gap functions of
    :mod:`cobra_ref.gaps` (sphere-plane, sphere-box, box corner-plane), one call per pair.
    """
    kin = kin or forward_kinematics(model, q)
    sph = model.spheres
    centers = [kin.o[b] + kin.R[b] @ c for b, c in zip(sph.body, sph.center)]
    found = []  # (kind, body A, body B, feature, Gap)
    for s, (body, center) in enumerate(zip(sph.body, centers)):
        gap = gaps.sphere_plane_gap(center, sph.radius[s])
        if gap.g < margin:
            found.append((ROBOT_GROUND, body, -1, s, gap))
    for box in model.boxes:
        R_b, p_b = kin.R[box.body], kin.o[box.body]
        for s, (body, center) in enumerate(zip(sph.body, centers)):
            gap = gaps.sphere_box_gap(center, sph.radius[s], R_b, p_b, box.half)
            if gap.g < margin:
                found.append((ROBOT_BOX, body, box.body, s, gap))
        for k, gap in enumerate(gaps.box_corner_plane_gaps(R_b, p_b, box.half)):
            if gap.g < margin:
                found.append((BOX_GROUND, box.body, -1, k, gap))
    return _stack(found)


def _stack(found) -> Contacts:
    """Contacts from a list of (kind, body A, body B, feature, Gap)."""
    index = [np.array([f[i] for f in found], dtype=int) for i in range(4)]
    gap_rows = [np.array([getattr(f[4], name) for f in found], dtype=float).reshape((len(found),) + shape)
                for name, shape in (("g", ()), ("frame", (3, 3)), ("point_A", (3,)), ("point_B", (3,)))]
    return Contacts(*index, *gap_rows)


def contact_jacobian(model: Model, q, contacts: Contacts, kin: Kinematics | None = None) -> np.ndarray:
    """Stacked relative contact Jacobian J_c (3m, nv): rows [n, t1, t2]^T (J_A - J_B) per contact.

    Implements: [COBRA] eq. (3)-(4), g' = J_c u, with W_i^T = n_i^T (J_A - J_B) the gap's
    gradient (checked against finite differences of the gap functions in the tests); J_A and
    J_B are the point Jacobians of the witness points (:func:`cobra_ref.kinematics.point_jacobian`).
    """
    kin = kin or forward_kinematics(model, q)
    J = np.zeros((3 * contacts.m, model.nv))
    for i in range(contacts.m):
        J_rel = _world_point_jacobian(model, q, kin, contacts.body_A[i], contacts.point_A[i])
        if contacts.body_B[i] >= 0:
            J_rel = J_rel - _world_point_jacobian(model, q, kin, contacts.body_B[i], contacts.point_B[i])
        # rows n^T J, t1^T J, t2^T J
        J[3 * i:3 * i + 3] = contacts.frame[i].T @ J_rel
    return J


def _world_point_jacobian(model, q, kin, body: int, x_world: np.ndarray) -> np.ndarray:
    """Jacobian (3, nv) of the point of ``body`` that is at world position x_world now."""
    x_body = kin.R[body].T @ (x_world - kin.o[body])
    return point_jacobian(model, q, body, x_body, kin)
