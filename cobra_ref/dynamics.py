"""Recursive rigid-body dynamics: RNEA, CRBA, bias forces, forward dynamics, energy, momentum.

Implements: [COBRA] eq. (1), written with the signs of [RBDA]::

    M(q) qdd + h(q, qd) = tau + sum_i J_i^T f_i,      h = C(q, qd) qd + g(q)

Note: the paper writes M u' - h = sum J^T f with h = C u + G + B tau, which puts gravity and
actuation on the wrong side; we implement the standard form above (assumption A24).
Here ``rnea(model, q, qd, qdd) = M qdd + h`` and ``h = rnea(model, q, qd, 0)``.
"""

from __future__ import annotations

import numpy as np

from .kinematics import forward_kinematics
from .model import Model
from .spatial import crf, crm


def rnea(model: Model, q, qd, qdd, f_ext=None) -> np.ndarray:
    """Inverse dynamics tau = M(q) qdd + h(q, qd) - (generalized external forces).

    Implements: [COBRA] eq. (1) solved for tau, by [RBDA] Table 5.1 (recursive Newton-Euler),
    gravity as a fictitious base acceleration a_0 = -g::

        v[i] = X_up[i] v[p] + S_i qd_i
        a[i] = X_up[i] a[p] + S_i qdd_i + c_J[i] + v[i] x v_J
        f[i] = I[i] a[i] + v[i] x* I[i] v[i] - f_ext[i]
        tau_i = S_i^T f[i];   f[p] += X_up[i]^T f[i]

    ``f_ext`` (optional) is a list of spatial forces, one per body, in body coordinates.
    """
    qdd = model.check_qd(qdd, "qdd")
    kin = forward_kinematics(model, q, qd)
    qd = model.check_qd(qd)
    a_0 = np.concatenate([np.zeros(3), -model.gravity])
    a, f = [], []
    for i in range(model.nb):
        parent = model.parent[i]
        v_J = kin.S[i] @ qd[model.v_idx[i]]
        a_p = a_0 if parent < 0 else a[parent]
        a.append(kin.X_up[i] @ a_p + kin.S[i] @ qdd[model.v_idx[i]] + kin.c_J[i] + crm(kin.v[i]) @ v_J)
        f.append(model.I[i] @ a[i] + crf(kin.v[i]) @ model.I[i] @ kin.v[i])
        if f_ext is not None:
            f[i] = f[i] - f_ext[i]
    tau = np.zeros(model.nv)
    for i in reversed(range(model.nb)):
        tau[model.v_idx[i]] = kin.S[i].T @ f[i]
        if model.parent[i] >= 0:
            f[model.parent[i]] = f[model.parent[i]] + kin.X_up[i].T @ f[i]
    return tau


def bias_force(model: Model, q, qd) -> np.ndarray:
    """h(q, qd) = C(q, qd) qd + g(q) = rnea(q, qd, 0): Coriolis, centrifugal and gravity.

    Implements: [COBRA] eq. (1) term h without actuation (MuJoCo's ``qfrc_bias``).
    """
    return rnea(model, q, qd, np.zeros(model.nv))


def crba(model: Model, q) -> np.ndarray:
    """Joint-space inertia matrix M(q), (nv, nv), symmetric positive definite.

    Implements: [COBRA] eq. (1)'s M(q), by [RBDA] Table 6.2 (composite-rigid-body algorithm)::

        I_c[i] = I[i] + sum over children c of X_up[c]^T I_c[c] X_up[c]
        F = I_c[i] S_i;  M[i, i] = S_i^T F
        j = i; while parent(j) >= 0: F = X_up[j]^T F; j = parent(j); M[i, j] = F^T S_j
    """
    kin = forward_kinematics(model, q)
    I_c = [I.copy() for I in model.I]
    for i in reversed(range(model.nb)):
        if model.parent[i] >= 0:
            I_c[model.parent[i]] += kin.X_up[i].T @ I_c[i] @ kin.X_up[i]
    M = np.zeros((model.nv, model.nv))
    for i in range(model.nb):
        vi = model.v_idx[i]
        F = I_c[i] @ kin.S[i]
        M[vi, vi] = kin.S[i].T @ F
        j = i
        while model.parent[j] >= 0:
            F = kin.X_up[j].T @ F
            j = model.parent[j]
            vj = model.v_idx[j]
            M[vi, vj] = F.T @ kin.S[j]
            M[vj, vi] = M[vi, vj].T
    return M


def forward_dynamics(model: Model, q, qd, tau) -> np.ndarray:
    """qdd = M^-1 (tau - h): accelerations without contact, by Cholesky of the CRBA matrix.

    Implements: [COBRA] eq. (1) with f_ext = 0 ([RBDA] sec. 6.1).
    """
    tau = model.check_qd(tau, "tau")
    M = crba(model, q)
    h = bias_force(model, q, qd)
    L = np.linalg.cholesky(M)
    return np.linalg.solve(L.T, np.linalg.solve(L, tau - h))


def body_kinetic_energies(model: Model, q, qd) -> np.ndarray:
    """Kinetic energy of each body, 1/2 v_i^T I_i v_i ([RBDA] eq. (2.67)).

    Implements: [RBDA] eq. (2.67), T_i = 1/2 v_i . I_i v_i.
    """
    kin = forward_kinematics(model, q, qd)
    return np.array([0.5 * v @ I @ v for v, I in zip(kin.v, model.I)])


def kinetic_energy(model: Model, q, qd) -> float:
    """Total kinetic energy T = 1/2 qd^T M qd = sum of the bodies' kinetic energies.

    Implements: [RBDA] eq. (2.67) summed over the bodies.
    """
    return float(body_kinetic_energies(model, q, qd).sum())


def potential_energy(model: Model, q) -> float:
    """Gravitational potential energy V = -sum_i m_i g . c_i (c_i = world COM of body i).

    Implements: the gravity potential whose gradient is g(q) in [COBRA] eq. (1).
    """
    kin = forward_kinematics(model, q)
    return float(-sum(m * model.gravity @ (o + R @ c)
                      for m, c, R, o in zip(model.mass, model.com, kin.R, kin.o)))


def spatial_momentum(model: Model, q, qd) -> np.ndarray:
    """Total spatial momentum about the world origin, world coordinates: sum X_0[i]^T I_i v_i.

    Implements: [RBDA] sec. 2.13 (momentum h = I v, summed in world coordinates).

    ([RBDA] sec. 2.13; ^0X_i^* = (^iX_0)^T maps a body-coordinate force vector to world.)
    """
    kin = forward_kinematics(model, q, qd)
    return sum(X.T @ I @ v for X, I, v in zip(kin.X_0, model.I, kin.v))
