"""The box QPs of the least-action loop, solved fast: certified active-set solves, OSQP kept warm.

For performance: ``FastBoxQP`` is a drop-in ``solve_qp`` for
:func:`cobra_ref.least_action.solve_least_action`, which the reference step calls with a fresh
OSQP solve per iterate (:func:`cobra_ref.qp.solve_box_qp`). Both return the minimiser of the
same strictly convex QP to OSQP's tolerance (tests run them side by side):

* the first iterate of every step is solved by OSQP, loosely (``LOOSE_EPS``, no polishing, no
  Ruiz scaling, warm-started from the friction loop's guess): the design asks for an OSQP solve
  every step. It takes one or two ADMM iterations, so the scaling, recomputed at every update of
  the matrix, would cost more than it saves. Its active set is then re-solved exactly and certified (:mod:`cobra_ref.fast.active_set`);
* later iterates are first re-solved on the active set of the iterate they start from, and
  certified;
* where no certificate is found, OSQP solves the QP to ``cobra_ref.qp.EPS`` with polishing.

OSQP instances are set up once per problem size n (dense upper triangle of P, A = identity)
and afterwards only updated (P, q, bounds), so a step costs no OSQP setup.
"""

from __future__ import annotations

import numpy as np
import osqp
from scipy import sparse

from ..qp import EPS, MAX_ITER, BoxQPSolution, ContactSolveError, osqp_solve
from .active_set import BoxQP, held_at_bounds, solve_box

LOOSE_EPS = 1e-5  # the first OSQP solve of a step: only a guess of the active set
LOOSE_MAX_ITER = 200
GUESSES = ("solved", "solved inaccurate", "maximum iterations reached")  # OSQP's statuses whose answer guesses the set


class FastBoxQP:
    """``solve_qp(H, c, lo, hi, x0) -> BoxQPSolution`` with certified solves and warm OSQP (module docstring).

    Call ``new_step()`` before each step's least-action loop: its first QP then goes to OSQP.
    """

    def __init__(self):
        self._solvers: dict = {}
        self._upper: dict = {}
        self.first = True

    def new_step(self) -> None:
        """Mark the next QP as the first of a step (OSQP solves it).

        Called by the fast stepper before each step.
        """
        self.first = True

    def __call__(self, H, c, lo, hi, x0) -> BoxQPSolution:
        first, self.first = self.first, False
        x0 = np.clip(x0, lo, hi)
        solves, iterations, y = 0, 0, None
        if first:
            # OSQP starts from x0 and its duals: minus the residual on the rows x0 holds at a bound
            at_lo, at_hi = held_at_bounds(x0, lo, hi)
            y0 = np.where(at_lo | at_hi, -(H @ x0 + c), 0.0)
            res = self._osqp(H, c, lo, hi, x0, y0, loose=True)
            solves, iterations = 1, res.info.iter
            if res.info.status in GUESSES:
                x0, y = res.x, res.y
        return self.certified(BoxQP(H, c, lo, hi), x0, y, (iterations, solves))

    def certified(self, qp: BoxQP, x0, y, counts: tuple) -> BoxQPSolution:
        """The QP ``qp`` by a certified solve from x0 with the held set guessed from x0 and OSQP's
        duals y (or None), else by OSQP to ``EPS``; ``counts``: the OSQP iterations and solves so far."""
        (H, c, lo, hi), (iterations, solves) = qp, counts
        certified = solve_box(qp, x0, (EPS, EPS), guess=held_at_bounds(x0, lo, hi, y))
        if certified is not None:
            return BoxQPSolution(certified[0], np.zeros(len(c)), iterations, "solved", solves)
        res = self._osqp(H, c, lo, hi, x0, None, loose=False)
        if res.info.status not in ("solved", "solved inaccurate"):
            raise ContactSolveError(f"OSQP status '{res.info.status}' after {res.info.iter} iterations "
                                    f"({len(c)} rows)")
        return BoxQPSolution(res.x, res.y, iterations + res.info.iter, res.info.status, solves + 1)

    def _osqp(self, H, c, lo, hi, x0, y0, loose: bool):
        """One OSQP solve on the cached instance for this size, warm-started at x0 (and y0, if given)."""
        n = len(c)
        key = (n, loose)
        if key not in self._solvers:
            rows, cols = np.triu_indices(n)
            order = np.lexsort((rows, cols))  # column-major, as CSC stores it
            rows, cols = rows[order], cols[order]
            self._upper[n] = rows * n + cols  # their positions in H's (row-major) flat order, for take
            indptr = np.concatenate([[0], np.cumsum(np.arange(1, n + 1))])
            P = sparse.csc_matrix((H.take(self._upper[n]), rows, indptr), shape=(n, n))
            solver = osqp.OSQP()
            eps = LOOSE_EPS if loose else EPS
            solver.setup(P=P, q=c, A=sparse.identity(n, format="csc"), l=lo, u=hi, eps_abs=eps, eps_rel=eps,
                         polishing=not loose, polish_refine_iter=5, verbose=False, warm_starting=True,
                         check_termination=1 if loose else 25, scaling=0 if loose else 10,
                         max_iter=LOOSE_MAX_ITER if loose else MAX_ITER)
            if len(self._solvers) > 64:
                self._solvers.clear()
            self._solvers[key] = solver
        else:
            solver = self._solvers[key]
            solver.update(Px=H.take(self._upper[n]), q=c, l=lo, u=hi)
        return osqp_solve(solver, x0, np.zeros(n) if y0 is None else y0)
