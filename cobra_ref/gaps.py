"""Explicit gap functions g_i of [COBRA] for spheres, boxes and the ground plane z = 0.

Implements: [COBRA] eq. (2)-(3) (the gap function g_i that the normal-cone inclusion and the
geometric constraint g_i(q, t) = 0 are written in).

Note: the paper never writes its gap functions out; the geometry here is ours. Conventions:

* every coordinate is in the WORLD frame; the ground is the plane z = 0 with normal e_z;
* a contact is between body A and body B; ``g > 0`` separated, ``g = 0`` touching, ``g < 0``
  penetration [m]; ``n`` is the unit normal pointing from B to A, so ``dg/dp_A = n`` when A
  translates by p_A, and ``point_A - point_B = g n`` for the witness points;
* ``frame`` = [n, t1, t2] (columns) splits a contact force as f_ext,i = [f_N,i, f_T,i]
  ([COBRA], text after eq. (3)).
"""

from __future__ import annotations

import itertools
from typing import NamedTuple

import numpy as np

e_x, e_y, e_z = np.eye(3)


class Gap(NamedTuple):
    """One contact's gap g_i, its normal and witness points (all world coordinates)."""

    g: float  # signed gap: > 0 separated, 0 touching, < 0 penetration [m]
    n: np.ndarray  # (3,) unit contact normal pointing from body B to body A
    point_A: np.ndarray  # (3,) witness point on A's surface (the deepest/closest point of A)
    point_B: np.ndarray  # (3,) witness point on B's surface
    frame: np.ndarray  # (3, 3) orthonormal right-handed contact frame, columns [n, t1, t2]


def _vec3(x, name: str) -> np.ndarray:
    """X as a finite float (3,) array, else ValueError naming ``name``."""
    x = np.asarray(x, dtype=float)
    if x.shape != (3,) or not np.all(np.isfinite(x)):
        raise ValueError(f"{name} must be a finite (3,) vector, got {x!r}")
    return x


def _check_radius(radius) -> float:
    """The sphere radius as a float, required finite and > 0."""
    r = float(radius)
    if not (np.isfinite(r) and r > 0.0):
        raise ValueError(f"radius must be finite and > 0, got {radius!r}")
    return r


def _check_box(R_box, p_box, half) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Validate a box pose (R_box a rotation within 1e-9, p_box) and positive half extents."""
    R = np.asarray(R_box, dtype=float)
    if R.shape != (3, 3) or not np.all(np.isfinite(R)):
        raise ValueError(f"R_box must be a finite 3x3 matrix, got shape {R.shape}")
    if np.max(np.abs(R.T @ R - np.eye(3))) > 1e-9 or np.linalg.det(R) < 0.0:
        raise ValueError("R_box must be a rotation: R^T R = 1 within 1e-9 and det R = +1")
    h = np.asarray(half, dtype=float)
    if h.shape != (3,) or not np.all(np.isfinite(h)) or not np.all(h > 0.0):
        raise ValueError(f"half must be 3 positive finite half extents, got {half!r}")
    return R, _vec3(p_box, "p_box"), h


def contact_frame(n, t_hint=None) -> np.ndarray:
    """Right-handed orthonormal contact frame C = [n, t1, t2] (columns), t2 = n x t1.

    Implements: [COBRA] f_ext,i = [f_N,i, f_T,i] (text after eq. (3)): n carries f_N and the
    tangent plane span(t1, t2) carries f_T.

    Notes
    -----
    ::

        t_perp = t_hint - (t_hint . n) n           # used if |t_perp| > 1e-9 |t_hint|
        else   t_perp = e_x - (e_x . n) n          # deterministic default ...
               (e_y instead of e_x if |n . e_x| > 0.9, i.e. n within ~26 deg of +-e_x)
        t1 = t_perp / |t_perp|,   t2 = n x t1

    ``n`` is normalised first; for the ground normal n = e_z the default is [e_z, e_x, e_y].
    """
    n = _vec3(n, "n")
    if np.linalg.norm(n) == 0.0:
        raise ValueError("n must be a nonzero vector")
    n = n / np.linalg.norm(n)
    t_perp = None
    if t_hint is not None:
        t_hint = _vec3(t_hint, "t_hint")
        t_perp = t_hint - (t_hint @ n) * n
        if np.linalg.norm(t_perp) <= 1e-9 * np.linalg.norm(t_hint):
            t_perp = None
    if t_perp is None:
        a = e_y if abs(n @ e_x) > 0.9 else e_x
        t_perp = a - (a @ n) * n
    t1 = t_perp / np.linalg.norm(t_perp)
    return np.column_stack([n, t1, np.cross(n, t1)])


def sphere_plane_gap(center, radius, t_hint=None) -> Gap:
    """Gap between a sphere (A) and the ground plane z = 0 (B).

    Implements: [COBRA] eq. (2)-(3) (gap function g_i, sphere-ground)::

        n = e_z,   g = c_z - r,   point_A = c - r n,   point_B = (c_x, c_y, 0)
    """
    c, r = _vec3(center, "center"), _check_radius(radius)
    point_B = np.array([c[0], c[1], 0.0])
    return Gap(float(c[2] - r), e_z.copy(), c - r * e_z, point_B, contact_frame(e_z, t_hint))


def sphere_box_gap(center, radius, R_box, p_box, half, t_hint=None) -> Gap:
    """Gap between a sphere (A) and a box (B): signed distance box -> centre, minus r.

    Implements: [COBRA] eq. (2)-(3) (gap function g_i, sphere-box).

    Notes
    -----
    ``R_box`` rotates box to world coordinates, ``p_box`` is the box centre, ``half`` = h its
    half extents. In box coordinates c_b = R^T (c - p)::

        outside (some |c_b,k| > h_k):  q_b = clip(c_b, -h, h),  d = |c_b - q_b| > 0
                                       n_b = (c_b - q_b) / d,   g = d - r
                                       (faces, edges and corners alike)
        inside (all |c_b,k| <= h_k):   k* = argmin_k (h_k - |c_b,k|)     (least-deep face)
                                       s = sign(c_b,k*) (+1 if 0),  n_b = s e_k*
                                       g = -(h_k* - |c_b,k*|) - r,  q_b = c_b, q_b,k* = s h_k*
        n = R n_b,   point_B = p + R q_b,   point_A = c - r n       (so point_A - point_B = g n)

    Both branches give dg/dc = n and dg/dp_box = -n.
    """
    c, r = _vec3(center, "center"), _check_radius(radius)
    R, p, h = _check_box(R_box, p_box, half)
    c_b = R.T @ (c - p)
    if np.any(np.abs(c_b) > h):
        # closest point of the box to the centre, and the distance to it
        q_b = np.clip(c_b, -h, h)
        d = np.linalg.norm(c_b - q_b)
        n_b, g = (c_b - q_b) / d, d - r
    else:
        # the face the centre is least deep under
        depth = h - np.abs(c_b)
        k = int(np.argmin(depth))
        s = 1.0 if c_b[k] >= 0.0 else -1.0
        n_b, g = s * np.eye(3)[k], -depth[k] - r
        q_b = c_b.copy()
        q_b[k] = s * h[k]
    n = R @ n_b
    return Gap(float(g), n, c - r * n, p + R @ q_b, contact_frame(n, t_hint))


# the sign pattern of corner k in box coordinates, k = 0 .. 7 (box_corners)
CORNER_SIGNS = np.array(list(itertools.product((-1.0, 1.0), repeat=3)))


def box_corners(R_box, p_box, half) -> np.ndarray:
    """The 8 world corners of a box, (8, 3), corner k = p + R (s_k * half).

    The signs s_k run over itertools.product((-1, 1), repeat=3), so corner 0 is (-,-,-), corner 1 is
    (-,-,+), ..., corner 7 is (+,+,+) in box coordinates.
    """
    R, p, h = _check_box(R_box, p_box, half)
    return p + (CORNER_SIGNS * h) @ R.T


def box_corner_plane_gaps(R_box, p_box, half, t_hint=None) -> list[Gap]:
    """Gaps between the 8 box corners (A, points) and the ground z = 0 (B), in box_corners order.

    Implements: [COBRA] eq. (2)-(3) (gap function g_i, box-ground at the corners)::

        n = e_z,   g_k = x_k,z,   point_A = x_k,   point_B = (x_k,x, x_k,y, 0)
    """
    C = contact_frame(e_z, t_hint)
    return [
        Gap(float(x[2]), e_z.copy(), x.copy(), np.array([x[0], x[1], 0.0]), C.copy())
        for x in box_corners(R_box, p_box, half)
    ]
