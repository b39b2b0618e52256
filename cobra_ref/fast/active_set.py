"""Certified solves of a box-constrained QP: a guess of the active set, and a KKT proof.

For performance, in the least-action iterates of [COBRA] eq. (6)
(:func:`cobra_ref.least_action.solve_least_action`): each is a box QP, one iterate differs little
from the last, and its active set (the contacts released, the friction at its bound, the servo
rows that saturate) seldom changes from one iterate, or one step, to the next::

    min_x 1/2 x^T H x + c^T x    s.t.  lo <= x <= hi          (H positive definite)

With the variables W held at a bound, the others solve H_FF x_F = -(c_F + H_FW x_W) (one
Cholesky solve), and since H > 0 the minimiser is unique: the answer is *certified* only if

    lo_i - tol <= x_i <= hi_i + tol        on every free variable          (primal feasible)
    r_i >= -tol where held at lo,  r_i <= tol where held at hi              (dual feasible)
    |r_i| <= eps_abs + eps_rel * scale     on every free variable          (stationarity)

with r = H x + c and tol = eps_abs + eps_rel * scale, OSQP's own termination test, so an
accepted answer is as accurate as OSQP's (``box_certificate``). Otherwise OSQP solves it.
Variables with lo_i = hi_i (a contact whose friction bound is zero) are always held, their
multiplier may take either sign.

The guess is improved by the primal-dual active-set iteration of Hintermueller, Ito & Kunisch
(SIAM J. Optim. 13, 2002), with d = diag(H)::

    held at lo:  x_i - r_i / d_i <= lo_i,     held at hi:  x_i - r_i / d_i >= hi_i

repeated until the held set stops changing (at most ``ROUNDS`` times), then certified (a given
guess is certified at once, and the rounds only start if it fails). Full
rounds can cycle (H is not an M-matrix); then up to ``SINGLE_FLIPS`` more rounds change only
the worst violation beyond its certificate tolerance.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy import linalg

ROUNDS = 8  # primal-dual active-set rounds before giving up (and asking OSQP)
SINGLE_FLIPS = 16  # then rounds that change only the worst violation (full rounds can cycle)
_posv = linalg.get_lapack_funcs("posv", (np.zeros(1),))


class BoxQP(NamedTuple):
    """min 1/2 x^T H x + c^T x s.t. lo <= x <= hi (H positive definite)."""

    H: np.ndarray  # (n, n)
    c: np.ndarray  # (n,)
    lo: np.ndarray  # (n,) lower bounds (-inf: none)
    hi: np.ndarray  # (n,) upper bounds (inf: none)


def held_at_bounds(x, lo, hi, y=None):
    """(at_lo, at_hi): the variables an iterate x holds at their bounds.

    The first guess of ``solve_box``: a variable within 1e-12 (relative) of a bound, or,
    with OSQP's duals y, one whose multiplier points at the bound.
    """
    tol = 1e-12 * max(float(np.abs(x).max(initial=0.0)), 1e-300)
    at_hi = x >= hi - tol
    at_lo = (x <= lo + tol) & ~at_hi
    if y is not None:
        at_hi |= y > 0
        at_lo = (at_lo | (y < 0)) & ~at_hi
    # only finite bounds can hold a variable
    return at_lo & np.isfinite(lo), at_hi & np.isfinite(hi)


def solve_box(qp: BoxQP, x0, eps: tuple, rounds: int = ROUNDS, guess=None):
    """The box QP ``qp`` by primal-dual active-set rounds from x0.

    Returns (x, at_lo, at_hi, r) certified by the KKT conditions at OSQP's tolerances
    ``eps`` = (eps_abs, eps_rel),
    with at_lo/at_hi the masks of the variables held at lo/hi and r = H x + c; or None.
    ``guess``: (at_lo, at_hi) to start from instead of the rule applied to x0.
    """
    H, c, lo, hi = qp
    d = H.diagonal()
    fixed = lo == hi
    x, before = x0, None
    r = None if guess is not None else H @ x + c  # the guess needs no residual
    for k in range(rounds + SINGLE_FLIPS + 1):
        if k == 0 and guess is not None:
            at_lo, at_hi = guess
            at_hi = at_hi & ~fixed
            at_lo = (at_lo | fixed) & ~at_hi
        elif k <= rounds:
            trial = x - r / d
            at_hi = (trial >= hi) & ~fixed
            at_lo = ((trial <= lo) | fixed) & ~at_hi
        else:
            # the full rounds cycle (H is not an M-matrix): change only the worst violation, a
            # free variable beyond a bound (scaled by d to gradient units) or a held one whose
            # multiplier has the wrong sign
            at_lo, at_hi = before[0].copy(), before[1].copy()
            free = ~(at_lo | at_hi)
            # each violation in units of its own certificate tolerance (box_certificate)
            tol_p, tol_d = _box_tolerances(x, r, free, eps)
            violation = np.concatenate([np.where(free, lo - x, 0.0) / tol_p, np.where(free, x - hi, 0.0) / tol_p,
                                        -r * (at_lo & ~fixed) / tol_d, r * at_hi / tol_d])
            worst = int(np.argmax(violation))
            if violation[worst] > 1.0:
                i, kind = worst % len(x), worst // len(x)
                at_lo[i], at_hi[i] = (kind == 0), (kind == 1)  # kinds 2, 3: release the variable
        if before is not None and (at_lo == before[0]).all() and (at_hi == before[1]).all():
            break
        before = at_lo, at_hi
        x = np.where(at_hi, hi, lo)
        free = ~(at_lo | at_hi)
        F = free.nonzero()[0]  # the free variables' indices (take copies rows faster than a mask)
        if len(F):
            x[F] = 0.0
            # H_FF x_F = -(c_F + H_FW x_W): LAPACK's Cholesky solve (posv)
            H_F = H.take(F, 0)
            _, x_F, info = _posv(H_F.take(F, 1), -(c.take(F) + H_F @ x), lower=True)
            if info != 0:
                return None
            x[F] = x_F
        r = H @ x + c
        # a guessed set is most often right: its solution is certified at once
        if k == 0 and guess is not None and _certified(qp, x, at_lo, at_hi, eps, r, fixed, free):
            return x, at_lo, at_hi, r
    else:
        return None  # the held set still changes: leave it to OSQP
    if not _certified(qp, x, at_lo, at_hi, eps, r, fixed, free):
        return None
    return x, at_lo, at_hi, r


def box_certificate(qp: BoxQP, x, at_lo, at_hi, eps: tuple, r=None) -> bool:
    """True if x, with the variables in at_lo/at_hi held at lo/hi, is the minimiser of the box QP
    ``qp``: the checks of the module docstring at the tolerances ``eps`` = (eps_abs, eps_rel).

    Primal feasibility, the multipliers' signs (r = H x + c >= 0 where held at lo, <= 0
    where held at hi, either where lo = hi) and stationarity (r = 0 where free), each within
    OSQP's tolerance eps_abs + eps_rel * scale.
    """
    r = qp.H @ x + qp.c if r is None else r
    return _certified(qp, x, at_lo, at_hi, eps, r, qp.lo == qp.hi, ~(at_lo | at_hi))


def _certified(qp: BoxQP, x, at_lo, at_hi, eps: tuple, r, fixed, free) -> bool:
    """``box_certificate`` with r = H x + c, the fixed (lo = hi) and the free variables given."""
    _, c, lo, hi = qp
    eps_abs, eps_rel = eps
    abs_g = np.abs(r)
    # OSQP's tolerances (_box_tolerances): |r| times the held mask is |r times that mask|
    tol_p = eps_abs + eps_rel * float(np.abs(x).max())
    tol_d = eps_abs + eps_rel * float((abs_g * ~free).max())
    # held variables sit on a bound, so the largest violation over all variables is the free ones'
    if max(float((lo - x).max()), float((x - hi).max())) > tol_p:
        return False
    sign = at_hi.astype(float) - (at_lo & ~fixed)
    if float((r * sign).max()) > tol_d:
        return False
    scale = max(float(np.abs(r - c).max()), float(np.abs(c).max()))
    return bool(np.isfinite(x).all() and float((abs_g * free).max()) <= eps_abs + eps_rel * scale)


def _box_tolerances(x, r, free, eps: tuple) -> tuple[float, float]:
    """OSQP's tolerances eps_abs + eps_rel * scale for the bounds (scale max |x|) and for the
    multipliers (scale max |r| over the held variables)."""
    eps_abs, eps_rel = eps
    return (eps_abs + eps_rel * float(np.abs(x).max()), eps_abs + eps_rel * float(np.abs(r * ~free).max()))
