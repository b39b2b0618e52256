"""Forward kinematics, body and point Jacobians, and configuration integration.

Implements: [RBDA] ch. 4 (forward kinematics of a tree) and the body Jacobian of a tree
(columns ^iX_j S_j over the ancestors j of body i, spatial_v2 ``bodyJac``); MuJoCo's
``mj_integratePos``.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .joints import jcalc
from .model import Model, ModelError
from .quaternion import quat_exp, quat_mul
from .spatial import inv_X, plux, skew


class Kinematics(NamedTuple):
    """Per-body results of forward kinematics (lists indexed by body)."""

    X_up: list  # ^iX_lambda(i), (6, 6)
    X_0: list  # ^iX_0 (world -> body i coordinates), (6, 6)
    R: list  # orientation of body i in world (body -> world rotation), (3, 3)
    o: list  # position of body i's origin in world, (3,)
    S: list  # motion subspace of joint i in body coordinates, (6, n_i)
    c_J: list  # velocity-product term of joint i, (6,)
    v: list  # spatial velocity of body i in body coordinates, (6,) (zeros if qd is None)


def forward_kinematics(model: Model, q, qd=None) -> Kinematics:
    """Poses, transforms and velocities of every body.

    Implements: [RBDA] Table 5.1 (the velocity pass of RNEA)::

        X_up[i] = X_J(q_i) X_tree[i]
        X_0[i]  = X_up[i] X_0[parent]
        v[i]    = X_up[i] v[parent] + S_i qd_i
        R[i]    = R[parent] R_tree[i] R_J(q_i),  o[i] = o[parent] + R[parent] p_tree[i]
    """
    q = model.check_q(q)
    qd = np.zeros(model.nv) if qd is None else model.check_qd(qd)
    X_up, X_0, R, o, S, c_J, v = ([] for _ in range(7))
    for i in range(model.nb):
        q_i, qd_i = q[model.q_idx[i]], qd[model.v_idx[i]]
        X_J, S_i, c_i = jcalc(model.joint_type[i], q_i, qd_i)
        X_up.append(X_J @ model.X_tree[i])
        parent = model.parent[i]
        # poses from 3x3 rotations (better rounding than 6x6 products); E = R_J^T is X_J's block
        R_p, o_p = (np.eye(3), np.zeros(3)) if parent < 0 else (R[parent], o[parent])
        R.append(R_p @ model.tree_rot[i] @ X_J[:3, :3].T)
        if model.joint_type[i] == "free":
            o.append(o_p + R_p @ (model.tree_pos[i] + model.tree_rot[i] @ q_i[:3]))
        else:
            o.append(o_p + R_p @ model.tree_pos[i])
        X_0.append(plux(R[i].T, o[i]))
        v_p = np.zeros(6) if parent < 0 else v[parent]
        v.append(X_up[i] @ v_p + S_i @ qd_i)
        S.append(S_i)
        c_J.append(c_i)
    return Kinematics(X_up, X_0, R, o, S, c_J, v)


def ancestors(model: Model, i: int) -> list[int]:
    """Bodies on the path from body i to the root, i first (the support of body i).

    The support kappa(i) of [RBDA] sec. 4.1.
    """
    out = []
    while i >= 0:
        out.append(i)
        i = model.parent[i]
    return out


def body_jacobian(model: Model, q, body, kin: Kinematics | None = None) -> np.ndarray:
    """Body Jacobian J_b (6, nv): spatial velocity of ``body`` in its own coordinates = J_b @ qd.

    Implements: ``J_b[:, j] = ^bX_j S_j`` for every ancestor j of b
    (spatial_v2 ``bodyJac``), zero elsewhere.
    """
    b = model.body_index(body)
    kin = kin or forward_kinematics(model, q)
    J = np.zeros((6, model.nv))
    for j in ancestors(model, b):
        # ^bX_j = ^bX_0 (^jX_0)^-1
        J[:, model.v_idx[j]] = kin.X_0[b] @ inv_X(kin.X_0[j]) @ kin.S[j]
    return J


def point_jacobian(model: Model, q, body, point, kin: Kinematics | None = None) -> np.ndarray:
    """Point Jacobian (3, nv): world velocity of a point fixed in ``body`` = J_p @ qd.

    ``point`` is given in ``body``'s coordinates. Implements::

        v_point = R_b (v_b + w_b x p) = R_b (J_b[3:] - [p]x J_b[:3]) qd
    """
    b = model.body_index(body)
    point = np.asarray(point, dtype=float)
    if point.shape != (3,) or not np.all(np.isfinite(point)):
        raise ModelError(f"point must be a finite 3-vector in body coordinates, got {point!r}")
    kin = kin or forward_kinematics(model, q)
    J_b = body_jacobian(model, q, b, kin)
    return kin.R[b] @ (J_b[3:] - skew(point) @ J_b[:3])


def integrate(model: Model, q, qd, dt: float) -> np.ndarray:
    """Configuration after moving with constant generalized velocity qd for time dt.

    Implements: MuJoCo's ``mj_integratePos``: for a free joint
    p <- p + dt v_world and quat <- quat * exp(dt w_body) (body-frame angular velocity
    multiplies on the right), renormalized; for a revolute joint theta <- theta + dt thetad.
    """
    q = model.check_q(q).copy()
    qd = model.check_qd(qd)
    if not np.isfinite(dt):
        raise ModelError(f"dt must be finite, got {dt}")
    for i, jt in enumerate(model.joint_type):
        iq, iv = model.q_idx[i], model.v_idx[i]
        if jt == "free":
            q_i, qd_i = q[iq], qd[iv]
            quat = quat_mul(q_i[3:], quat_exp(dt * qd_i[3:]))
            q[iq] = np.concatenate([q_i[:3] + dt * qd_i[:3], quat / np.linalg.norm(quat)])
        else:
            q[iq] = q[iq] + dt * qd[iv]
    return q
