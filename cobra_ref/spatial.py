"""6-D spatial vector algebra, written after [RBDA] ch. 2 and spatial_v2.

Conventions (used everywhere in cobra_ref):

* Spatial vectors are **angular-first**: a motion vector is ``[w; v]`` (angular velocity,
  then the linear velocity of the body-fixed point at the frame origin), a force vector is
  ``[n; f]`` (moment about the origin, then force). This is Featherstone's and MuJoCo's order;
  Pinocchio is linear-first, and the only conversion is :func:`swap_lin_ang`.
* ``X_BA`` (or ``X``) is the 6x6 motion transform from A coordinates to B coordinates
  (^B X_A). With ``E`` the 3x3 rotation from A to B coordinates (E = R_AB^T, where R_AB is B's
  orientation seen from A) and ``r`` the position of B's origin in A coordinates::

      X = [ E          0 ]        X^* = X^-T = [ E  -E r x ]
          [ -E r x     E ]                     [ 0   E     ]

* ``crm(v) = v x`` acts on motion vectors, ``crf(v) = v x* = -crm(v)^T`` on force vectors.
"""

from __future__ import annotations

import numpy as np


def skew(w: np.ndarray) -> np.ndarray:
    """3x3 cross-product matrix: skew(w) @ u = w x u.

    Implements: [RBDA] eq. (2.23) (the 3-D "tilde" operator).

    Examples
    --------
    >>> skew(np.array([0.0, 0.0, 1.0])) @ np.array([1.0, 0.0, 0.0])
    array([0., 1., 0.])
    """
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def skew_rows(w: np.ndarray) -> np.ndarray:
    """(..., k, 3, 3) skew matrices [w_i]x of the rows of w (..., k, 3): skew_rows(w)[i] @ v = w_i x v.

    The batched :func:`skew` of the world-frame fast paths.
    """
    out = np.zeros(w.shape + (3,))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def cross_rows(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise cross product a x b of (..., 3) arrays, broadcasting like numpy.

    The batched 3-D cross product of the world-frame fast paths (np.cross is slow for small arrays).
    """
    return np.stack([a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
                     a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
                     a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]], axis=-1)


def crm(v: np.ndarray) -> np.ndarray:
    """Motion cross product matrix: crm(v) @ m = v x m.

    Implements: [RBDA] eq. (2.31)::

        v x = [ w x   0  ]
              [ v x   w x ]
    """
    out = np.zeros((6, 6))
    out[:3, :3] = skew(v[:3])
    out[3:, :3] = skew(v[3:])
    out[3:, 3:] = out[:3, :3]
    return out


def crf(v: np.ndarray) -> np.ndarray:
    """Force cross product matrix: crf(v) @ f = v x* f = -crm(v)^T @ f.

    Implements: [RBDA] eq. (2.32).
    """
    return -crm(v).T


def plux(E: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Motion transform from rotation ``E`` (A->B coordinates) and B's origin ``r`` in A.

    Implements: [RBDA] eq. (2.28): X = [E 0; -E r x  E] (spatial_v2 ``plux``).
    """
    X = np.zeros((6, 6))
    X[:3, :3] = E
    X[3:, 3:] = E
    X[3:, :3] = -E @ skew(r)
    return X


def xlt(r: np.ndarray) -> np.ndarray:
    """Pure translation by ``r`` (B's origin at r in A, axes parallel). [RBDA] eq. (2.27).

    Implements: [RBDA] eq. (2.27).
    """
    return plux(np.eye(3), r)


def _rot_axis(axis: int, theta: float) -> np.ndarray:
    """Coordinate rotation E (A->B) for B rotated by theta about A's axis 0/1/2."""
    c, s = np.cos(theta), np.sin(theta)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    E = np.eye(3)
    E[i, i] = c
    E[j, j] = c
    E[i, j] = s
    E[j, i] = -s
    return E


def rotx(theta: float) -> np.ndarray:
    """Motion transform for a frame rotated by theta about x. [RBDA] eq. (2.30), spatial_v2 rotx.

    Implements: [RBDA] eq. (2.30) (spatial_v2 ``rotx``).
    """
    return plux(_rot_axis(0, theta), np.zeros(3))


def roty(theta: float) -> np.ndarray:
    """Motion transform for a frame rotated by theta about y. [RBDA] eq. (2.30).

    Implements: [RBDA] eq. (2.30) (spatial_v2 ``roty``).
    """
    return plux(_rot_axis(1, theta), np.zeros(3))


def rotz(theta: float) -> np.ndarray:
    """Motion transform for a frame rotated by theta about z. [RBDA] eq. (2.30).

    Implements: [RBDA] eq. (2.30) (spatial_v2 ``rotz``).
    """
    return plux(_rot_axis(2, theta), np.zeros(3))


def inv_X(X: np.ndarray) -> np.ndarray:
    """Inverse of a motion transform without a matrix inverse.

    Implements: [RBDA] eq. (2.26): (^B X_A)^-1 = ^A X_B = plux(E^T, -E r).
    """
    E = X[:3, :3]
    # X[3:, :3] = -E r x  =>  r x = -E^T X[3:, :3]
    r_cross = -E.T @ X[3:, :3]
    r = np.array([r_cross[2, 1], r_cross[0, 2], r_cross[1, 0]])
    return plux(E.T, -E @ r)


def force_X(X: np.ndarray) -> np.ndarray:
    """Force transform X^* = X^-T for the motion transform X. [RBDA] eq. (2.25).

    Implements: [RBDA] eq. (2.25).
    """
    return inv_X(X).T


def mcI(m: float, c: np.ndarray, I_c: np.ndarray) -> np.ndarray:
    """Spatial inertia of a body with mass m, centre of mass c and rotational inertia I_c at c.

    Implements: [RBDA] eq. (2.63)::

        I = [ I_c + m c x c x^T   m c x ]
            [ m c x^T              m 1  ]
    """
    C = skew(c)
    I = np.zeros((6, 6))
    I[:3, :3] = I_c + m * C @ C.T
    I[:3, 3:] = m * C
    I[3:, :3] = m * C.T
    I[3:, 3:] = m * np.eye(3)
    return I


def swap_lin_ang(x: np.ndarray) -> np.ndarray:
    """Swap the two 3-blocks of a spatial vector (or the rows of a 6xN matrix).

    The only conversion between cobra_ref's angular-first vectors and Pinocchio's linear-first ones.
    """
    return np.concatenate([x[3:6], x[0:3]], axis=0)
