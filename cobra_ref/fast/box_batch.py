"""The certified box solves of K members at once: held sets, active-set rounds and certificates, batched.

For performance: the first iterate of every member's friction loop is a box QP (one per member,
concatenated as ``members.MemberRows`` says)::

    min_x 1/2 x^T H x + c^T x    s.t.  lo <= x <= hi

solved by :func:`cobra_ref.fast.active_set.solve_box` from a guessed held set. Here its full
primal-dual rounds run for every member together: each round's held sets, the comparison with the
last round's, and the certificate are one NumPy call for all members (per-member maxima as segment
maxima); the Cholesky solve on each member's free variables and its product H x stay per member,
the same LAPACK and BLAS calls on the same arrays. A member that the full rounds leave uncertified
(a refused certificate, a failed Cholesky, a set still changing after ``active_set.ROUNDS``) is
reported so, and its caller solves it alone (``solve_box``'s single flips, then OSQP). Tested equal
to ``solve_box`` member by member.
"""

from __future__ import annotations

import numpy as np

from ..qp import EPS
from .active_set import ROUNDS, _posv
from .members import MemberRows, segment_max


def held(R: MemberRows, x, lo, hi, y=None, has_y=None):
    """``active_set.held_at_bounds`` of every member (its own tolerance); y: OSQP's duals where
    ``has_y`` (the rows of the members whose OSQP answer guesses the set)."""
    tol = 1e-12 * np.maximum(segment_max(np.abs(x), R.of_row, R.K), 1e-300)[R.of_row]
    at_hi = x >= hi - tol
    at_lo = (x <= lo + tol) & ~at_hi
    if y is not None:
        at_hi |= has_y & (y > 0)
        at_lo = (at_lo | (has_y & (y < 0))) & ~at_hi
    return at_lo & np.isfinite(lo), at_hi & np.isfinite(hi)


def solve_boxes(R: MemberRows, Hs, c, box, guess):
    """(x, certified (K,)): ``active_set.solve_box(BoxQP(Hs[k], c_k, lo_k, hi_k), x0, (EPS, EPS),
    guess=guess_k)`` of every member k, up to its full rounds (module docstring); box = (lo, hi),
    guess = (at_lo, at_hi), all concatenated. Where ``certified`` is False, x is not an answer."""
    (lo, hi), fixed = box, box[0] == box[1]
    d = np.concatenate([H.diagonal() for H in Hs])
    at_hi = guess[1] & ~fixed
    at_lo = (guess[0] | fixed) & ~at_hi
    going = np.ones(R.K, dtype=bool)  # the members in their rounds
    x, going = _solved_on(R, Hs, c, box, (at_lo, at_hi), going)
    r = _residual(R, Hs, x, c, going)
    certified = going & certificates(R, x, (at_lo, at_hi, fixed, ~(at_lo | at_hi)), r, c, box)
    going &= ~certified
    for _ in range(ROUNDS):
        if not going.any():
            break
        # the primal-dual round: held where x - r / diag(H) leaves the box
        trial = x - r / d
        new_hi = (trial >= hi) & ~fixed
        new_lo = ((trial <= lo) | fixed) & ~new_hi
        changed = np.zeros(R.K, dtype=bool)
        np.logical_or.at(changed, R.of_row, (new_lo != at_lo) | (new_hi != at_hi))
        # a member whose set stays is done: its last answer is certified, or not
        stays = going & ~changed
        if stays.any():
            certified |= stays & certificates(R, x, (at_lo, at_hi, fixed, ~(at_lo | at_hi)), r, c, box)
        going &= changed
        rows = going[R.of_row]
        at_lo, at_hi = np.where(rows, new_lo, at_lo), np.where(rows, new_hi, at_hi)
        x_new, solved = _solved_on(R, Hs, c, box, (at_lo, at_hi), going)
        x, going = np.where(rows, x_new, x), going & solved
        r = np.where(rows, _residual(R, Hs, x, c, going), r)
    return x, certified


def _solved_on(R: MemberRows, Hs, c, box, held_set, members):
    """(x, solved (K,)): each member in ``members`` solved with the variables of ``held_set`` =
    (at_lo, at_hi) held at their bounds: H_FF x_F = -(c_F + H_FW x_W), LAPACK's Cholesky solve
    (posv), as ``active_set.solve_box`` writes it; solved is False where the solve fails."""
    (lo, hi), (at_lo, at_hi) = box, held_set
    x = np.where(at_hi, hi, lo)
    free = ~(at_lo | at_hi)
    solved = members.copy()
    for k in np.flatnonzero(members):
        rows = R.row_slice(k)
        x_k, F = x[rows], free[rows].nonzero()[0]
        if len(F):
            x_k[F] = 0.0
            H_F = Hs[k].take(F, 0)
            _, x_F, info = _posv(H_F.take(F, 1), -(c[rows].take(F) + H_F @ x_k), lower=True)
            solved[k] = info == 0
            x_k[F] = x_F
    return x, solved


def _residual(R: MemberRows, Hs, x, c, members) -> np.ndarray:
    """r = H x + c of each member in ``members`` (zero elsewhere), the single member's product."""
    r = np.zeros(len(x))
    for k in np.flatnonzero(members):
        rows = R.row_slice(k)
        r[rows] = Hs[k] @ x[rows] + c[rows]
    return r


def certificates(R: MemberRows, x, held_set, r, c, box) -> np.ndarray:
    """(K,) ``active_set._certified`` of every member at OSQP's tolerances (EPS, EPS); held_set =
    (at_lo, at_hi, fixed, free), box = (lo, hi)."""
    (at_lo, at_hi, fixed, free), (lo, hi) = held_set, box
    member, K = R.of_row, R.K
    abs_g = np.abs(r)
    tol_p = EPS + EPS * segment_max(np.abs(x), member, K)
    tol_d = EPS + EPS * segment_max(abs_g * ~free, member, K)
    # held variables sit on a bound, so the largest violation over all variables is the free ones'
    primal = ~(segment_max(np.maximum(lo - x, x - hi), member, K) > tol_p)
    sign = at_hi.astype(float) - (at_lo & ~fixed)
    dual = ~(segment_max(r * sign, member, K) > tol_d)
    scale = np.maximum(segment_max(np.abs(r - c), member, K), segment_max(np.abs(c), member, K))
    finite = np.ones(K, dtype=bool)
    np.logical_and.at(finite, member, np.isfinite(x))
    return primal & dual & finite & (segment_max(abs_g * free, member, K) <= EPS + EPS * scale)
