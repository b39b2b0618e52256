"""Certified active-set solves of the contact QP: a guess of the active set, and a KKT proof.

Helper (performance) for the friction fixed point of [COBRA] eq. (6) in
:mod:`cobra_ref.contact_qp`: its iterates are one QP whose friction bounds move a little from
one iterate to the next, and whose active set (the contacts that are released, the ones that
slide) seldom changes from one iterate, or one step, to the next. The QP, in OSQP's form::

    min_x 1/2 x^T P x + q^T x    s.t.  l <= A x <= u          (P positive definite)

With W the rows guessed to sit at a bound, v_W that bound (l or u), the equality-constrained
problem is one linear (KKT) system::

    [ P    A_W^T ] [ x   ]   [ -q  ]
    [ A_W  0     ] [ y_W ] = [ v_W ],      y = 0 on the rows not in W

and OSQP's optimality conditions P x + q + A^T y = 0, y_i > 0 only at u_i, y_i < 0 only at
l_i, l <= A x <= u, are then sufficient for the minimiser (P > 0: the QP is strictly convex,
its minimiser unique). So the answer is *certified*: it is returned only if

    l_i - tol <= (A x)_i <= u_i + tol      on every row not in W        (primal feasible)
    y_i >= -tol at an upper bound,  y_i <= tol at a lower bound          (dual feasible)
    |P x + q + A^T y| <= eps_abs + eps_rel * max(|P x|, |A^T y|, |q|)   (stationarity)

with tol = eps_abs + eps_rel * scale, OSQP's own termination test, so an accepted answer is as
accurate as OSQP's. Otherwise the caller asks OSQP. Rows with l_i = u_i (a contact whose
friction bound is zero) are always in W and their y may take either sign.

With K = 4 facets every row of A bounds one impulse component (A is a permutation), so
the QP is box-constrained, lo <= x <= hi, and the guess is improved by the primal-dual
active-set iteration of Hintermueller, Ito & Kunisch (SIAM J. Optim. 13, 2002), with
g = P x + q and d = diag(P)::

    held at lo:  x_i - g_i / d_i <= lo_i,     held at hi:  x_i - g_i / d_i >= hi_i
    x_W = bound,  P_FF x_F = -(q_F + P_FW x_W)           (Cholesky on the free variables)

repeated until the held set stops changing (at most ``ROUNDS`` times), then certified. Full
rounds can cycle (P is not an M-matrix); then up to ``SINGLE_FLIPS`` more rounds change only
the worst violation beyond its certificate tolerance (measured on the box-pushing steps whose
friction fixed point had not converged: OSQP solves per step 8.6 -> 1.5, converged 9 -> 28 of
60). For other A (K = 8) the one guess from the starting iterate is solved and certified.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from scipy import linalg


class WorkingSet(NamedTuple):
    """Which rows are held at a bound: at_lower (l_i) or at_upper (u_i), as boolean masks."""

    at_lower: np.ndarray
    at_upper: np.ndarray


def working_set(Ax: np.ndarray, y: np.ndarray, l: np.ndarray, u: np.ndarray) -> WorkingSet:
    """The rows an iterate (A x, y) points at, by OSQP's polishing rule; rows with l = u included.

    Helper: row i is held at l_i if (A x)_i - l_i < -y_i and at u_i if u_i - (A x)_i < y_i
    (closer to the bound than its multiplier is large; a violated row counts as held).
    """
    fixed = l == u
    at_upper = u - Ax < y
    return WorkingSet((Ax - l < -y) & ~at_upper | (fixed & ~at_upper), at_upper)


ROUNDS = 8  # primal-dual active-set rounds before giving up (and asking OSQP); 3 or 5 left more to OSQP
SINGLE_FLIPS = 16  # then rounds that change only the worst violation (rounds cycle where P is not an M-matrix)
_posv = linalg.get_lapack_funcs("posv", (np.zeros(1),))


class BoxForm(NamedTuple):
    """A constraint matrix that is a permutation: row r is the unit row of variable col[r]."""

    col: np.ndarray


def box_form(A: np.ndarray) -> BoxForm | None:
    """The BoxForm of A, or None if some row of A is not one entry 1 on a column of its own.

    Helper: recognizes the K = 4 friction pyramid's constraint matrix (rows p_N, t1 . p_T,
    t2 . p_T) as bounds on the variables.
    """
    nonzero = A != 0
    if A.shape[0] != A.shape[1] or not np.all(nonzero.sum(axis=1) == 1):
        return None
    col = np.argmax(nonzero, axis=1)
    if len(np.unique(col)) != len(col) or not np.all(A[np.arange(len(col)), col] == 1.0):
        return None
    return BoxForm(col)


def certified_solve(P, q, A, l, u, x0, y0, eps_abs: float, eps_rel: float, box: BoxForm | None = None):
    """(x, y, at_lo, at_hi) of the QP, certified (module docstring), from the iterate (x0, y0); or None.

    Helper: the certified solve of the friction fixed point's QPs ([COBRA] eq. (6)).

    The first guess of the active set is the one (x0, y0) points at (``working_set``).
    ``box``: ``box_form(A)`` if A is a permutation; then the active-set rounds run, and
    at_lo/at_hi are the (n,) masks of the variables held at their lower/upper bound. For other
    A the first guess is the only one, and at_lo/at_hi are None.
    """
    if box is None:
        solved = solve_on_working_set(P, q, A, l, u, working_set(A @ x0, y0, l, u), eps_abs, eps_rel)
        return None if solved is None else (*solved, None, None)
    # the bounds per variable: l_r <= x_c <= u_r
    lo, hi = np.empty(len(q)), np.empty(len(q))
    lo[box.col], hi[box.col] = l, u
    solved = solve_box(P, q, lo, hi, x0, eps_abs, eps_rel, guess=held_variables(box, x0, y0, l, u))
    if solved is None:
        return None
    x, at_lo, at_hi, g = solved
    # OSQP's duals: g_c + y_r = 0 on held rows, 0 on free ones
    y = np.where((at_lo | at_hi)[box.col], -g[box.col], 0.0)
    return x, y, at_lo, at_hi


def held_variables(box: BoxForm, x, y, l, u):
    """(at_lo, at_hi): the variables that the iterate (x, y) holds at their lower/upper bound.

    Helper: ``working_set`` on the rows, mapped to the variables they bound.
    """
    ws = working_set(x[box.col], y, l, u)
    at_lo, at_hi = np.empty(len(x), dtype=bool), np.empty(len(x), dtype=bool)
    at_lo[box.col], at_hi[box.col] = ws.at_lower, ws.at_upper
    return at_lo, at_hi


def solve_box(P, q, lo, hi, x0, eps_abs: float, eps_rel: float, rounds: int = ROUNDS, guess=None):
    """min 1/2 x^T P x + q^T x s.t. lo <= x <= hi by primal-dual active-set rounds from x0.

    Helper: returns (x, at_lo, at_hi, g) certified by the KKT conditions at OSQP's tolerances,
    with at_lo/at_hi the masks of the variables held at lo/hi and g = P x + q; or None.
    ``guess``: (at_lo, at_hi) to start from instead of the rule applied to x0.
    """
    d = P.diagonal()
    fixed = lo == hi
    x, before = x0, None
    for r in range(rounds + SINGLE_FLIPS + 1):
        g = P @ x + q if (r or guess is None) else None  # the guess needs no gradient
        if r == 0 and guess is not None:
            at_lo, at_hi = guess
            at_hi = at_hi & ~fixed
            at_lo = (at_lo | fixed) & ~at_hi
        elif r <= rounds:
            trial = x - g / d
            at_hi = (trial >= hi) & ~fixed
            at_lo = ((trial <= lo) | fixed) & ~at_hi
        else:
            # the full rounds cycle (P is not an M-matrix): change only the worst violation, a
            # free variable beyond a bound (scaled by d to gradient units) or a held one whose
            # multiplier has the wrong sign
            at_lo, at_hi = before[0].copy(), before[1].copy()
            free = ~(at_lo | at_hi)
            # each violation in units of its own certificate tolerance (box_certificate)
            tol_p, tol_d = _box_tolerances(x, g, free, eps_abs, eps_rel)
            violation = np.concatenate([np.where(free, lo - x, 0.0) / tol_p, np.where(free, x - hi, 0.0) / tol_p,
                                        -g * (at_lo & ~fixed) / tol_d, g * at_hi / tol_d])
            worst = int(np.argmax(violation))
            if violation[worst] > 1.0:
                i, kind = worst % len(x), worst // len(x)
                at_lo[i], at_hi[i] = (kind == 0), (kind == 1)  # kinds 2, 3: release the variable
        if before is not None and (at_lo == before[0]).all() and (at_hi == before[1]).all():
            break
        before = at_lo, at_hi
        x = np.where(at_hi, hi, lo)
        free = ~(at_lo | at_hi)
        if free.any():
            x[free] = 0.0
            # P_FF x_F = -(q_F + P_FW x_W): LAPACK's Cholesky solve (posv)
            P_F = P[free]
            _, x_F, info = _posv(P_F[:, free], -(q[free] + P_F @ x), lower=True)
            if info != 0:
                return None
            x[free] = x_F
    else:
        return None  # the held set still changes: leave it to OSQP
    if not box_certificate(P, q, lo, hi, x, at_lo, at_hi, eps_abs, eps_rel, g):
        return None
    return x, at_lo, at_hi, g


def box_certificate(P, q, lo, hi, x, at_lo, at_hi, eps_abs: float, eps_rel: float, g=None) -> bool:
    """True if x, with the variables in at_lo/at_hi held at lo/hi, is the minimiser of
    1/2 x^T P x + q^T x over lo <= x <= hi: the checks of the module docstring for the box form.

    Helper: primal feasibility, the multipliers' signs (g = P x + q >= 0 where held at lo, <= 0
    where held at hi, either where lo = hi) and stationarity (g = 0 where free), each within
    OSQP's tolerance eps_abs + eps_rel * scale.
    """
    g = P @ x + q if g is None else g
    fixed = lo == hi
    free = ~(at_lo | at_hi)
    abs_g = np.abs(g)
    tol_p, tol_d = _box_tolerances(x, g, free, eps_abs, eps_rel)
    # held variables sit on a bound, so the largest violation over all variables is the free ones'
    if max(float((lo - x).max()), float((x - hi).max())) > tol_p:
        return False
    sign = at_hi.astype(float) - (at_lo & ~fixed)
    if float((g * sign).max()) > tol_d:
        return False
    scale = max(float(np.abs(g - q).max()), float(np.abs(q).max()))
    return bool(np.isfinite(x).all() and float((abs_g * free).max()) <= eps_abs + eps_rel * scale)


def _box_tolerances(x, g, free, eps_abs: float, eps_rel: float) -> tuple[float, float]:
    """OSQP's tolerances eps_abs + eps_rel * scale for the bounds (scale max |x|) and for the
    multipliers (scale max |g| over the held variables)."""
    return (eps_abs + eps_rel * float(np.abs(x).max()), eps_abs + eps_rel * float(np.abs(g * ~free).max()))


def solve_on_working_set(P: np.ndarray, q: np.ndarray, A: np.ndarray, l: np.ndarray, u: np.ndarray,
                         ws: WorkingSet, eps_abs: float, eps_rel: float):
    """(x, y) of the QP if the working set ``ws`` is its active set (certified), else None.

    Helper: the KKT solve (LU, one step of iterative refinement: the system is ill-conditioned
    when contacts are redundant) and the checks of the module docstring.
    """
    W = ws.at_lower | ws.at_upper
    n, rows = len(q), np.flatnonzero(W)
    A_W = A[rows]
    K = np.zeros((n + len(rows), n + len(rows)))
    K[:n, :n] = P
    K[:n, n:] = A_W.T
    K[n:, :n] = A_W
    rhs = np.concatenate([-q, np.where(ws.at_upper, u, l)[rows]])
    try:
        lu = linalg.lu_factor(K, check_finite=False)
        sol = linalg.lu_solve(lu, rhs, check_finite=False)
        sol += linalg.lu_solve(lu, rhs - K @ sol, check_finite=False)
    except (np.linalg.LinAlgError, ValueError):
        return None
    x = sol[:n]
    y = np.zeros(len(l))
    y[rows] = sol[n:]
    Ax = A @ x
    finite = np.isfinite(u)
    tol_primal = eps_abs + eps_rel * float(np.max(np.abs(Ax), initial=0.0))
    tol_dual = eps_abs + eps_rel * float(np.max(np.abs(y), initial=0.0))
    free = ~W
    if np.any(Ax[free] < l[free] - tol_primal) or np.any((Ax > u + tol_primal)[free & finite]):
        return None
    fixed = l == u
    if np.any(y[ws.at_upper & ~fixed] < -tol_dual) or np.any(y[ws.at_lower & ~fixed] > tol_dual):
        return None
    # stationarity, measured, not assumed from the linear solve
    Px, ATy = P @ x, A.T @ y
    scale = max(float(np.max(np.abs(Px))), float(np.max(np.abs(ATy))), float(np.max(np.abs(q))))
    if not (np.all(np.isfinite(x)) and np.max(np.abs(Px + q + ATy)) <= eps_abs + eps_rel * scale):
        return None
    return x, y
