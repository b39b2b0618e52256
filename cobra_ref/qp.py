"""The box-constrained QP of one least-action iterate, solved by OSQP.

The one place where OSQP's own names appear. OSQP solves

    min_x 1/2 x^T P x + q^T x    s.t.  l <= A x <= u

and reads only the upper triangle of P. The least-action iterates of :mod:`cobra_ref.least_action`
are box QPs, lo <= x <= hi, so here P = H (the problem's Hessian), q = c, A = identity,
l = lo, u = hi. OSQP's duals y are the bound multipliers: y_i < 0 at an active lower bound,
y_i > 0 at an active upper bound, so that H x + c + y = 0 at the solution.

Settings: eps_abs = eps_rel = ``EPS`` = 1e-7 with solution polishing, so an answer with a
correct active set is exact to rounding (OSQP's polish re-solves the KKT system of the active
set); at most ``MAX_ITER`` ADMM iterations.

OSQP catches Ctrl-C itself: while it solves, its own SIGINT handler stands in for Python's and the
solve returns with the status "interrupted". ``osqp_solve`` passes such a Ctrl-C on to Python's
handler, so that it stops a run wherever it arrives.
"""

from __future__ import annotations

import signal
from typing import NamedTuple

import numpy as np
import osqp
from scipy import sparse

EPS = 1e-7
MAX_ITER = 20000
INTERRUPTED = "interrupted"  # the status of a solve that OSQP's SIGINT handler stopped


class ContactSolveError(RuntimeError):
    """OSQP did not solve a contact problem (the message names its status)."""


class BoxQPSolution(NamedTuple):
    """What a box-QP solve returns."""

    x: np.ndarray  # the minimiser
    y: np.ndarray  # bound multipliers (OSQP's sign convention, module docstring)
    iterations: int  # ADMM iterations
    status: str  # "solved" or "solved inaccurate"
    solves: int = 1  # OSQP solves it took (the fast wing certifies some answers without OSQP: 0)


def solve_box_qp(H: np.ndarray, c: np.ndarray, lo: np.ndarray, hi: np.ndarray, x0=None, y0=None) -> BoxQPSolution:
    """min 1/2 x^T H x + c^T x  s.t.  lo <= x <= hi, by OSQP (module docstring); H positive definite.

    One least-action iterate of [COBRA] eq. (6). Raises ``ContactSolveError`` when OSQP returns
    neither "solved" nor "solved inaccurate".
    """
    n = len(c)
    solver = osqp.OSQP()
    solver.setup(P=sparse.triu(H, format="csc"), q=c, A=sparse.identity(n, format="csc"), l=lo, u=hi,
                 eps_abs=EPS, eps_rel=EPS, polishing=True, polish_refine_iter=5, max_iter=MAX_ITER,
                 verbose=False)
    res = osqp_solve(solver, x0, np.zeros(n) if y0 is None else y0)
    if res.info.status not in ("solved", "solved inaccurate"):
        raise ContactSolveError(f"OSQP status '{res.info.status}' after {res.info.iter} iterations ({n} rows)")
    return BoxQPSolution(res.x, res.y, res.info.iter, res.info.status)


def osqp_solve(solver: osqp.OSQP, x0=None, y0=None):
    """``solver``'s answer, warm-started at (x0, y0) unless x0 is None; a Ctrl-C that OSQP caught
    during the solve is raised again here, so Python's SIGINT handler sees it (a
    ``KeyboardInterrupt`` by default). Where SIGINT is ignored (a pool worker, which its main
    process then ends), the solve starts again from (x0, y0), with any step size rho that OSQP
    adapted before the interrupt."""
    while True:
        if x0 is not None:
            solver.warm_start(x=x0, y=y0)
        res = solver.solve(raise_error=False)
        if res.info.status != INTERRUPTED:
            return res
        signal.raise_signal(signal.SIGINT)
