"""Unit quaternions, w-first (``quat_wxyz``), as in MuJoCo and MJCF.

A quaternion ``(w, x, y, z)`` represents the rotation R that maps body coordinates to world
coordinates (MuJoCo's ``xquat``). scipy's ``Rotation.from_quat`` is scalar-LAST unless told
otherwise; cobra_ref never hands a quaternion to scipy.
"""

from __future__ import annotations

import math

import numpy as np


def quat_to_rot(quat_wxyz: np.ndarray) -> np.ndarray:
    """Rotation matrix of a unit quaternion (body -> world).

    Implements: the Euler-Rodrigues formula R = (w^2 - u.u) 1 + 2 u u^T + 2 w [u]x, u = (x, y, z).
    """
    w, x, y, z = np.asarray(quat_wxyz, dtype=float).tolist()  # Python floats: faster scalar arithmetic
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quat_to_rot_rows(quat_wxyz: np.ndarray) -> np.ndarray:
    """(..., 3, 3) rotation matrices of unit quaternions (..., 4): :func:`quat_to_rot` row by row,
    the same arithmetic on arrays (the same numbers, bit for bit)."""
    w, x, y, z = np.moveaxis(np.asarray(quat_wxyz, dtype=float), -1, 0)
    R = np.empty(np.shape(w) + (3, 3))
    R[..., 0, 0], R[..., 0, 1], R[..., 0, 2] = 1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)
    R[..., 1, 0], R[..., 1, 1], R[..., 1, 2] = 2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)
    R[..., 2, 0], R[..., 2, 1], R[..., 2, 2] = 2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)
    return R


def quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product a * b (rotation b first, then a).
    """
    aw, ax, ay, az = np.asarray(a, dtype=float).tolist()
    bw, bx, by, bz = np.asarray(b, dtype=float).tolist()
    # (aw bw - a.b,  aw b + bw a + a x b)
    return np.array([aw * bw - (ax * bx + ay * by + az * bz),
                     aw * bx + bw * ax + (ay * bz - az * by),
                     aw * by + bw * ay + (az * bx - ax * bz),
                     aw * bz + bw * az + (ax * by - ay * bx)])


def quat_exp(rotvec: np.ndarray) -> np.ndarray:
    """Quaternion of the rotation by angle |rotvec| about rotvec/|rotvec| (exponential map).

    Exp(rotvec / 2) as a unit quaternion, as in MuJoCo's ``mju_quatIntegrate``.
    """
    x, y, z = np.asarray(rotvec, dtype=float).tolist()
    angle = math.sqrt(x * x + y * y + z * z)
    if angle < 1e-12:
        # second-order Taylor expansion of (cos(a/2), sin(a/2)/a * rotvec)
        return np.array([1.0 - angle**2 / 8.0, 0.5 * x, 0.5 * y, 0.5 * z])
    k = math.sin(angle / 2) / angle
    return np.array([math.cos(angle / 2), k * x, k * y, k * z])


def rot_to_quat(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w >= 0) of a rotation matrix (Shepperd's method).

    Shepperd's method, the inverse of quat_to_rot up to sign.
    """
    t = np.trace(R)
    if t > 0:
        s = 2.0 * np.sqrt(1.0 + t)
        q = np.array([s / 4, (R[2, 1] - R[1, 2]) / s, (R[0, 2] - R[2, 0]) / s, (R[1, 0] - R[0, 1]) / s])
    else:
        i = int(np.argmax(np.diag(R)))
        j, k = (i + 1) % 3, (i + 2) % 3
        s = 2.0 * np.sqrt(1.0 + R[i, i] - R[j, j] - R[k, k])
        q = np.zeros(4)
        q[0] = (R[k, j] - R[j, k]) / s
        q[1 + i] = s / 4
        q[1 + j] = (R[j, i] + R[i, j]) / s
        q[1 + k] = (R[k, i] + R[i, k]) / s
    q = q / np.linalg.norm(q)
    return q if q[0] >= 0 else -q
