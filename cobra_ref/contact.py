"""Contact candidates of the COBRA + box scene and their stacked Jacobian J_c.

Implements: [COBRA] eq. (3)-(4): for each contact i between body A and body B (the ground or
the box), the gap g_i(q) of :mod:`cobra_ref.gaps` and its rate

    g'_i = n_i . (v_A(point_A) - v_B(point_B)) = W_i^T u,    W_i^T = n_i^T (J_A - J_B)

which is *relative*: when B is the moving box, dg/dt depends on the box's motion too
(the paper's dg/dt != 0 for a moving object). Stacking [n, t1, t2]^T (J_A - J_B) for every
contact gives J_c with g' = J_c u (eq. (4)); rows are ordered contact by contact.

Contact kinds (``KINDS``): robot sphere on the ground, robot sphere on the box, box corner on
the ground. Body A is the robot link (or the box, for box-ground); the normal points from B to
A, so a positive normal impulse pushes A away from B. A candidate enters the contact problem
when its gap is below ``margin`` (speculative contacts: the QP then forbids closing more than
the gap within one step, so fast approach cannot tunnel).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from . import gaps as gapfn
from .fastdyn import ChainModel, ChainTerms

KINDS = ("robot-ground", "robot-box", "box-ground")
ROBOT_GROUND, ROBOT_BOX, BOX_GROUND = 0, 1, 2


class Contacts(NamedTuple):
    """Candidate contacts (struct of arrays, m entries)."""

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
        """Identity of each contact across steps (for warm starts and logs)."""
        return list(zip(self.kind.tolist(), self.body_A.tolist(), self.feature.tolist()))


def find_contacts(model, terms: ChainTerms, margin: float, t_hint: dict | None = None) -> Contacts:
    """All candidate contacts with gap < margin, in a fixed order (ground, box, box corners).

    Implements: the active set of [COBRA] eq. (2): contacts whose gap g_i is (nearly) closed.

    ``t_hint`` maps a contact key to a tangent direction (the previous sliding direction), so
    that t1 follows the slip and the friction pyramid is exact along it.
    """
    t_hint = t_hint or {}
    rows = []
    sph = model.spheres
    centers = terms.p[sph.body] + np.einsum("sij,sj->si", terms.R[sph.body], sph.center)
    for s in np.flatnonzero(centers[:, 2] - sph.radius < margin):
        key = (ROBOT_GROUND, int(sph.body[s]), int(s))
        rows.append((key, -1, gapfn.sphere_plane_gap(centers[s], sph.radius[s], t_hint.get(key))))
    for box in model.boxes:
        R_b, p_b = terms.R[box.body], terms.p[box.body]
        # cheap bounding-sphere test first: |c - p_box| - r < margin + half-diagonal
        near = np.linalg.norm(centers - p_b, axis=1) - sph.radius < margin + np.linalg.norm(box.half)
        for s in np.flatnonzero(near):
            key = (ROBOT_BOX, int(sph.body[s]), int(s))
            gap = gapfn.sphere_box_gap(centers[s], sph.radius[s], R_b, p_b, box.half, t_hint.get(key))
            if gap.g < margin:
                rows.append((key, box.body, gap))
        for k, gap in enumerate(gapfn.box_corner_plane_gaps(R_b, p_b, box.half)):
            key = (BOX_GROUND, box.body, k)
            if gap.g < margin:
                if key in t_hint:
                    gap = gap._replace(frame=gapfn.contact_frame(gap.n, t_hint[key]))
                rows.append((key, -1, gap))
    return _stack(rows)


def _stack(rows) -> Contacts:
    if not rows:
        z = np.zeros(0)
        return Contacts(z.astype(int), z.astype(int), z.astype(int), z.astype(int), z, np.zeros((0, 3, 3)),
                        np.zeros((0, 3)), np.zeros((0, 3)))
    return Contacts(
        kind=np.array([r[0][0] for r in rows], dtype=int),
        body_A=np.array([r[0][1] for r in rows], dtype=int),
        body_B=np.array([r[1] for r in rows], dtype=int),
        feature=np.array([r[0][2] for r in rows], dtype=int),
        g=np.array([r[2].g for r in rows]),
        frame=np.array([r[2].frame for r in rows]),
        point_A=np.array([r[2].point_A for r in rows]),
        point_B=np.array([r[2].point_B for r in rows]),
    )


def contact_jacobian(chain: ChainModel, terms: ChainTerms, contacts: Contacts) -> np.ndarray:
    """Stacked relative contact Jacobian J_c (3m, nv): rows [n, t1, t2]^T (J_A - J_B) per contact.

    Implements: [COBRA] eq. (3)-(4), g' = J_c u, with W_i^T = n_i^T (J_A - J_B) the gap's
    gradient (checked against finite differences of the gap functions in the tests).
    """
    J = np.zeros((3 * contacts.m, chain.model.nv))
    for k in range(contacts.m):
        J_rel = chain.point_jacobian(terms, contacts.body_A[k], contacts.point_A[k])
        if contacts.body_B[k] >= 0:
            J_rel = J_rel - chain.point_jacobian(terms, contacts.body_B[k], contacts.point_B[k])
        J[3 * k:3 * k + 3] = contacts.frame[k].T @ J_rel
    return J
