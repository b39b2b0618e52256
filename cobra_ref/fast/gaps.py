"""The gap functions of :mod:`cobra_ref.gaps` in batches, for the fast contact search.

For performance: the same formulas as :func:`cobra_ref.gaps.contact_frame` and
:func:`cobra_ref.gaps.sphere_box_gap`, row by row over arrays, without input checks (the
simulator's inputs are checked once, by the Model); ``tests/test_contact.py`` checks them
equal to the readable functions.
"""

from __future__ import annotations

import numpy as np

from ..gaps import e_x, e_y
from ..spatial import cross_rows


def contact_frames(n: np.ndarray, t_hint: np.ndarray | None = None) -> np.ndarray:
    """(k, 3, 3) frames [n, t1, t2] for unit normals n (k, 3); rows of t_hint that are NaN mean none.

    The row-wise form of :func:`cobra_ref.gaps.contact_frame` (same rules, same results).
    """
    a = np.where(np.abs(n[:, :1]) > 0.9, e_y, e_x)  # default tangent seed
    hint = np.zeros_like(n) if t_hint is None else np.where(np.isnan(t_hint), 0.0, t_hint)
    t_perp = hint - (hint * n).sum(axis=1)[:, None] * n
    # |t_perp| > 1e-9 |t_hint|, squared
    use_hint = (t_perp * t_perp).sum(axis=1) > 1e-18 * (hint * hint).sum(axis=1)
    seed = a - (a * n).sum(axis=1)[:, None] * n
    t1 = np.where(use_hint[:, None], t_perp, seed)
    t1 /= np.sqrt((t1 * t1).sum(axis=1))[:, None]
    frames = np.empty((len(n), 3, 3))
    frames[:, :, 0], frames[:, :, 1], frames[:, :, 2] = n, t1, cross_rows(n, t1)
    return frames


def sphere_box_gaps(centers: np.ndarray, radii: np.ndarray, R_box: np.ndarray, p_box: np.ndarray,
                    half: np.ndarray):
    """Row-wise :func:`cobra_ref.gaps.sphere_box_gap` for k spheres against one box: (g, n, point_A, point_B).

    The same formulas as :func:`cobra_ref.gaps.sphere_box_gap`, without input checks.
    """
    c_b = (centers - p_box) @ R_box
    outside = np.any(np.abs(c_b) > half, axis=1)
    # outside: closest point of the box
    q_out = np.clip(c_b, -half, half)
    diff = c_b - q_out
    d = np.linalg.norm(diff, axis=1)
    n_out = diff / np.where(d > 0, d, 1.0)[:, None]
    # inside: the least-deep face
    depth = half - np.abs(c_b)
    k = np.argmin(depth, axis=1)
    rows = np.arange(len(c_b))
    s = np.where(c_b[rows, k] >= 0.0, 1.0, -1.0)
    n_in = np.zeros_like(c_b)
    n_in[rows, k] = s
    q_in = c_b.copy()
    q_in[rows, k] = s * half[k]
    n_b = np.where(outside[:, None], n_out, n_in)
    q_b = np.where(outside[:, None], q_out, q_in)
    g = np.where(outside, d - radii, -depth[rows, k] - radii)
    n = n_b @ R_box.T
    return g, n, centers - radii[:, None] * n, p_box + q_b @ R_box.T
