"""The least-action contact problem of one time step, solved with OSQP.

Implements: [COBRA] eq. (5)-(6) for impulses p = f dt over one step, with the normal-cone
law of eq. (2) at the velocity level::

    G = J_c M^-1 J_c^T                          # eq. (5): Delassus matrix
    c = J_c u_free + [g_stab / dt ; 0 ; 0]      # eq. (5): free contact velocity (+ gap term)
    min_p  1/2 p^T G p + p^T c                  # eq. (6): least action
    s.t.   p_N >= 0,  |d_k . p_T| <= mu p_N    # F_i: friction pyramid, K facets

Its KKT conditions, with w = G p + c the contact velocity after the step, are eq. (2):
0 <= p_N  _|_  w_N >= 0 (no approach where a force pushes, no pull) and, for the tangential
impulse, w_T = 0 while p_T is inside the pyramid (stick) or p_T on its boundary opposing w_T
(slip). ``kkt_residuals`` measures all of them.

Note (friction): by default (``friction="fixed-point"``) the friction bound uses pbar_N, a
guess of the normal impulses, and the QP is re-solved until p_N stops changing (a De Saxce /
"staggered projections" fixed point): at convergence the bound is mu p_N, exact Coulomb
friction on the pyramid with 0 <= p_N _|_ w_N >= 0. The update of pbar_N (K = 4 facets) is a
Newton step: on the active set of the last iterate (released contacts, sliding components
held at +-mu pbar_N) the fixed point is one linear system (``coulomb_fixed_point``), so when
that set is right the next iterate has converged; the first pbar_N is that system solved on
the warm start's (the previous step's) active set. Right after a Newton step that did not
contract (its set was wrong), the plain update pbar_N = p_N is taken instead, relaxed by 1/2
from the first plain one that does not contract (two-cycles); a Newton guess whose sum exceeds
NEWTON_MAX_GROWTH times the last p_N's is not taken (a wrong active set). Measured on the
built-in rolling push (10 s, 87 % of the steps touching the box): 1.04 iterates per rolling
step, 1.22 per pushing step, 99.2 % of the pushing steps converged (the plain update alone
converged on none of the pushing steps of a 2 s run within 10 iterates); every one of 60
random cold-started 5-contact problems converges within 8 iterates on the default path (the
plain update needed 10-50, and 8 of the 60 not even then). If it
has not converged after ``fp_max`` iterates (50; the stepper uses ``StepSettings.fp_max`` =
10 because it warm-starts) -- robot, box and ground jam, and redundant contacts (4 box
corners, 13 spheres on a 6-DoF robot base) leave the split of p_N between them nearly
undetermined, so the active set cycles -- the iterate whose friction leaves its own pyramid
least is kept (often one whose bound mu pbar_N was below mu p_N, so nothing is clipped; the
smallest change |p_N - pbar_N| breaks ties), its friction clipped into the pyramid of its own
p_N, and ``QPInfo.status`` says so: the step then
obeys the cone exactly but only approximately the stick/slip condition
(``stick_slip_residual`` reports by how much), and the velocities stay consistent with the
impulses actually applied. OSQP failing on a later iterate's bounds ends the fixed point the
same way (measured: three 10 s figure runs stopped at such a failure before the growth limit
above); failing on the first, Newton-guessed bounds restarts it from the plain guess.
``friction="convex"`` puts mu p_N inside the constraints: the paper's eq. (6) with f in F
literally, one convex QP, always solvable, but it is the Anitescu relaxation: its KKT
conditions give w_N = mu |w_T| for a sliding contact, and a fast slide is converted into a
jump (a ball sliding at 1 m/s on mu = 1 leaves the ground at 0.5 m/s in one step). Use it to
study that artefact, not for box pushing.

Note (pyramid): K facets (K even, default 4, option 8) make a regular K-gon circumscribing the
circle |p_T| <= mu p_N, rows |d_k . p_T| <= mu p_N with d_k at angles 2 pi k / K,
k < K/2. The contact frame's t1 follows the previous sliding direction, so the pyramid is
exact along the slip (the largest error is sec(pi/K) - 1 across it: 41 % for K = 4, 8 % for
K = 8, in the direction of a sideways slip only).

Note (regularization): G is singular whenever contacts are redundant (13 spheres on one plane
acting on a robot whose shape is prescribed have rank <= 6). We add eps I with
eps = reg * mean(diag G) (reg = 1e-6 by default: with 1e-8, cond(G + eps I) reaches 1e9 and
OSQP's ADMM stalls at "solved inaccurate" on robot-box steps), which picks the least-norm impulses among
equally valid ones, like a tiny uniform compliance; the velocity error it causes is about
reg * |w| and is reported through the KKT residuals.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import osqp
from scipy import sparse
from scipy.linalg import get_lapack_funcs

from .active_set import box_form, certified_solve, held_variables


class ContactSolveError(RuntimeError):
    """OSQP did not solve the contact problem (the message names the status)."""


class QPInfo(NamedTuple):
    status: str  # "solved", "solved inaccurate" (OSQP), or "solved (fixed point not converged; ...)"
    iterations: int  # OSQP ADMM iterations summed over the fixed-point iterates
    fp_iterations: int  # friction fixed-point iterates
    complementarity: float  # max_i |p_N,i w_N,i|  [N s * m/s]
    cone_residual: float  # max facet violation / max p_N (relative)
    stick_slip_residual: float  # max |w_T| at strictly-inside (sticking) contacts [m/s]
    cond_G: float  # condition number of G + eps I
    osqp_solves: int = 1  # OSQP solves (the other fixed-point iterates were certified re-solves)


# the fast path's loose OSQP solve (ContactQP docstring): its answer is only a guess of the
# active set, which active_set.certified_solve then certifies at the tight tolerance
LOOSE_EPS = 1e-5
LOOSE_MAX_ITER = 200
NEWTON_MAX_GROWTH = 3.0  # a Newton guess of the normal impulses may at most triple their sum


def facet_directions(n_facets: int) -> np.ndarray:
    """(K/2, 2) unit facet normals d_k in the (t1, t2) plane, angles 2 pi k / K.

    Helper: the facets of the friction pyramid that linearizes F_i of [COBRA] eq. (2).
    """
    if n_facets < 4 or n_facets % 2:
        raise ValueError(f"n_facets must be an even number >= 4, got {n_facets}")
    angles = 2 * np.pi * np.arange(n_facets // 2) / n_facets
    D = np.stack([np.cos(angles), np.sin(angles)], axis=1)
    D[np.abs(D) < 1e-15] = 0.0  # cos(pi/2) = 6e-17 in floating point: exactly 0, so K = 4 rows are unit rows
    return D


def _constraint_matrix(m: int, D: np.ndarray, mu=None) -> sparse.csc_matrix:
    """Rows: p_N,i for every contact, then one row per contact and facet pair.

    ``mu`` given, (m,) (convex cone): rows mu_i p_N - d.p_T and mu_i p_N + d.p_T (both >= 0).
    ``mu`` None (fixed point): rows d.p_T, bounded by +-mu pbar_N through l and u.
    """
    rows, cols, vals = list(range(m)), [3 * i for i in range(m)], [1.0] * m
    r = m
    for i in range(m):
        for d in D:
            for sign in ((-1.0, 1.0) if mu is not None else (1.0,)):
                rows += [r, r]
                cols += [3 * i + 1, 3 * i + 2]
                vals += [sign * d[0], sign * d[1]]
                if mu is not None:
                    rows.append(r)
                    cols.append(3 * i)
                    vals.append(mu[i])
                r += 1
    return sparse.csc_matrix((vals, (rows, cols)), shape=(r, 3 * m))


def _upper_pattern(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Row and column of every upper-triangle entry of an n x n matrix, in CSC (column) order."""
    iu = np.triu_indices(n)
    order = np.lexsort((iu[0], iu[1]))  # column-major for CSC
    return iu[0][order], iu[1][order]


def _upper_dense_csc(A: np.ndarray) -> sparse.csc_matrix:
    """Upper triangle of a dense matrix with every entry stored (fixed sparsity for updates)."""
    n = len(A)
    rows, cols = _upper_pattern(n)
    indptr = np.concatenate([[0], np.cumsum(np.arange(1, n + 1))])
    return sparse.csc_matrix((A[rows, cols], rows, indptr), shape=(n, n))


class ContactQP:
    """OSQP least-action solver with warm starts; reuses its factorization pattern when m repeats.

    Implements: [COBRA] eq. (6) (see the module docstring for the formulation and notes).

    ``fp_path``: how the friction fixed point's iterates after the first are solved.
    ``"osqp"`` (the reference): OSQP for every iterate. ``"active-set"`` (default, faster): the
    first iterate of every call is solved by OSQP; each later one is first re-solved on the
    previous iterate's active set and accepted only with a KKT certificate at OSQP's own
    tolerances (:mod:`cobra_ref.active_set`), else OSQP solves it. Both return the same QP
    minimisers to those tolerances (tests/test_contact_qp.py).

    ``osqp``: ``"every-step"`` (default, the design: OSQP solves every step's contact problem)
    or ``"fallback"`` (with the active-set path: the first iterate, too, is tried on the
    previous step's active set first, so OSQP runs only when no certified answer is found;
    the fastest, and as accurate, but most steps then never call OSQP).
    """

    def __init__(self, mu: float, n_facets: int = 4, reg: float = 1e-6, eps: float = 1e-7,
                 friction: str = "fixed-point", fp_tol: float = 1e-8, fp_max: int = 50,
                 max_iter: int = 20000, fp_path: str = "active-set", osqp: str = "every-step"):
        if not (np.isfinite(mu) and mu >= 0):
            raise ValueError(f"mu must be finite and >= 0, got {mu}")
        if friction not in ("convex", "fixed-point"):
            raise ValueError(f"friction must be 'convex' or 'fixed-point', got {friction!r}")
        if fp_path not in ("active-set", "osqp"):
            raise ValueError(f"fp_path must be 'active-set' or 'osqp', got {fp_path!r}")
        if osqp not in ("every-step", "fallback"):
            raise ValueError(f"osqp must be 'every-step' or 'fallback', got {osqp!r}")
        self.osqp_every_step = osqp == "every-step" or fp_path == "osqp"
        self.mu, self.D, self.reg, self.friction = mu, facet_directions(n_facets), reg, friction
        self.eps, self.fp_tol, self.fp_max, self.max_iter = eps, fp_tol, fp_max, max_iter
        self.fp_path = fp_path
        # OSQP's constraint rows (and duals) per contact: p_N, then the facets (twice for the cone)
        self.rows_per_contact = 1 + (1 if friction == "fixed-point" else 2) * len(self.D)
        self._solvers: dict = {}
        self._upper: dict = {}  # m -> CSC order of the upper triangle of P (3m x 3m)
        self._A_dense: dict = {}  # m -> the fixed-point form's constraint matrix, dense
        self._box: dict = {}  # m -> its active_set.BoxForm (K = 4), or None
        self.y = np.zeros(0)  # OSQP-convention duals of the last solve (see duals_per_contact)

    def solve(self, G: np.ndarray, c: np.ndarray, p_warm: np.ndarray | None = None, mu=None,
              y_warm: np.ndarray | None = None, G_factor: np.ndarray | None = None):
        """Impulses p (3m,) ordered [p_N, p_t1, p_t2] per contact, and a QPInfo.

        ``mu``: a friction coefficient per contact (m,), or None for the solver's ``mu``.
        ``p_warm``, ``y_warm``: where OSQP starts, primal and dual (the previous step's
        values contact by contact; ``duals_per_contact`` lays the duals out per contact).
        ``G_factor``: B with G = B B^T (3m x r), if the caller has it: cond(G) then costs an
        r x r eigenvalue problem instead of a 3m x 3m one.
        """
        m = len(c) // 3
        if m == 0:
            self.y = np.zeros(0)
            return np.zeros(0), QPInfo("solved", 0, 0, 0.0, 0.0, 0.0, 1.0, 0)
        mu = np.full(m, self.mu) if mu is None else np.broadcast_to(np.asarray(mu, dtype=float), (m,))
        if not (mu.min() >= 0.0 and np.isfinite(mu.max())):  # NaN fails the first test
            raise ValueError(f"friction coefficients must be finite and >= 0, got {mu}")
        # eq. (6) with a small uniform regularization eps I (module docstring)
        eps_I = self.reg * max(G.trace() / (3 * m), 1e-300)
        P = G.copy()
        P.flat[::3 * m + 1] += eps_I
        p0 = np.zeros(3 * m) if p_warm is None else np.asarray(p_warm, dtype=float).copy()
        n_rows = m * self.rows_per_contact
        y0 = np.zeros(n_rows) if y_warm is None else np.asarray(y_warm, dtype=float)
        status, iters, fp, solves = "solved", 0, 1, 1
        if self.friction == "fixed-point":
            p, iters, fp, solves, ok, inaccurate = self._fixed_point(P, c, p0, y0, mu)
            if not ok:
                status = "solved (fixed point not converged; friction clipped)"
                p = self._clip_friction(p, mu)
        else:
            solver = self._solver(m, P, c, convex=mu)
            solver.warm_start(x=p0, y=y0)
            p, _, iters, inaccurate = self._run(solver, m, np.zeros(n_rows), np.full(n_rows, np.inf))
        if inaccurate and status == "solved":
            status = "solved inaccurate"
        cond_G = _cond(P) if G_factor is None else _cond_factored(G_factor, eps_I)
        info = QPInfo(status, iters, fp, *kkt_residuals(G, c, p, mu, self.D), cond_G=cond_G, osqp_solves=solves)
        return p, info

    @staticmethod
    def duals_per_contact(y: np.ndarray, m: int) -> np.ndarray:
        """OSQP's duals as (m, 1 + rows per contact): each contact's p_N row, then its facet
        rows (``_constraint_matrix`` orders both blocks contact by contact)."""
        return np.concatenate([y[:m, None], y[m:].reshape(m, -1)], axis=1)

    @staticmethod
    def duals_stacked(Y: np.ndarray) -> np.ndarray:
        """The inverse of ``duals_per_contact``: OSQP's dual vector from its (m, k) rows."""
        return np.concatenate([Y[:, 0], Y[:, 1:].ravel()])

    def _solver(self, m, P, c, convex=None, loose=False):
        """An OSQP instance for m contacts: set up once per (m, kind), then only updated.

        ``convex``: None for the fixed-point form, else the (m,) friction coefficients that
        enter the convex cone's constraint matrix. ``loose``: the fast path's first guess
        (tolerance ``LOOSE_EPS``, no polishing, at most ``LOOSE_MAX_ITER`` iterations).
        """
        key = (m, None if convex is None else tuple(convex), loose)
        if key not in self._solvers:
            A = _constraint_matrix(m, self.D, convex)
            solver = osqp.OSQP()
            eps = LOOSE_EPS if loose else self.eps
            solver.setup(P=_upper_dense_csc(P), q=c, A=A, l=np.zeros(A.shape[0]),
                         u=np.full(A.shape[0], np.inf), eps_abs=eps, eps_rel=eps,
                         polishing=not loose, verbose=False, warm_starting=True, polish_refine_iter=5,
                         max_iter=LOOSE_MAX_ITER if loose else self.max_iter)
            if len(self._solvers) > 64:
                self._solvers.clear()
            self._solvers[key] = solver
            self._upper[m] = _upper_pattern(3 * m)
        else:
            rows, cols = self._upper[m]
            self._solvers[key].update(Px=P[rows, cols], q=c)
        return self._solvers[key]

    def _run(self, solver, m, l, u):
        """One OSQP solve from the solver's current iterate (polished when it can be); a failed
        one is retried cold, tighter. Returns (x, y, ADMM iterations, inaccurate)."""
        solver.update(l=l, u=u)
        res = solver.solve(raise_error=False)
        iters = res.info.iter
        if res.info.status != "solved":
            solver.update_settings(eps_abs=self.eps * 1e-2, eps_rel=self.eps * 1e-2)
            solver.warm_start(x=np.zeros(3 * m), y=np.zeros(len(l)))
            res = solver.solve(raise_error=False)
            iters += res.info.iter
            solver.update_settings(eps_abs=self.eps, eps_rel=self.eps)
        if res.info.status not in ("solved", "solved inaccurate"):
            raise ContactSolveError(f"OSQP status '{res.info.status}' after {res.info.iter} iterations "
                                    f"(m = {m} contacts)")
        self.y = res.y
        return res.x, res.y, iters, res.info.status != "solved"

    def _fixed_point(self, P, c, p, y, mu):
        """Friction bounded by mu pbar_N of the previous iterate, until p_N stops changing.

        OSQP starts from (p, y), then from each iterate. With ``fp_path="active-set"`` each
        iterate is first re-solved on the previous iterate's active set (not the first), then
        by a loose OSQP solve whose active set is re-solved and certified, and only then by the
        reference tight OSQP solve (class docstring).
        Returns (p, ADMM iterations, iterates, OSQP solves, converged, inaccurate)."""
        m = len(c) // 3
        fast = self.fp_path == "active-set"
        # the OSQP solvers are set up or updated only when they are needed
        solver = None if fast else self._solver(m, P, c)
        loose = self._solver(m, P, c, loose=True) if fast and self.osqp_every_step else None
        A, box = self._dense_constraints(m)
        p0, y0 = p, y
        pbar_N = np.maximum(p[0::3], 0.0)
        if box is not None and pbar_N.any():
            # the first guess: the fixed point on the active set of the warm start (the previous
            # step's), so that an unchanged active set converges at the first iterate
            held = held_variables(box, p, y, *self._bounds(pbar_N, mu))
            guess = _newton_update(P, c, mu, *held, pbar_N)
            pbar_N, newton_start = (pbar_N, False) if guess is None else (guess, True)
        else:
            newton_start = False
        total, solves, inaccurate, damped, last_change = 0, 0, False, False, np.inf
        # kept if no fixed point is reached: the iterate whose friction leaves its own pyramid
        # least (relative to max p_N; then the smallest change), so clipping it changes least
        best = ((np.inf, np.inf), p)
        last_update = "none"
        for fp in range(1, self.fp_max + 1):
            l, u = self._bounds(pbar_N, mu)
            # the first iterate goes to OSQP unless osqp="fallback" (class docstring)
            certified = (certified_solve(P, c, A, l, u, p, y, self.eps, self.eps, box)
                         if fast and (fp > 1 or not self.osqp_every_step) else None)
            if fast and certified is None:
                loose = loose or self._solver(m, P, c, loose=True)
                loose.warm_start(x=p, y=y)
                loose.update(l=l, u=u)
                res = loose.solve(raise_error=False)
                total, solves = total + res.info.iter, solves + 1
                if res.info.status in ("solved", "solved inaccurate"):
                    p, y = res.x, res.y
                    certified = certified_solve(P, c, A, l, u, p, y, self.eps, self.eps, box)
            if certified is None:
                solver = solver or self._solver(m, P, c)
                solver.warm_start(x=p, y=y)
                try:
                    p, y, it, bad = self._run(solver, m, l, u)
                except ContactSolveError:
                    if best[0][0] < np.inf:
                        break  # OSQP failed on a later iterate's bounds: keep the best iterate so far
                    if not newton_start:
                        raise  # no iterate to fall back on
                    # the first guess came from the warm start's active set: start plainly instead
                    pbar_N, newton_start = np.maximum(p0[0::3], 0.0), False
                    p, y = p0, y0
                    continue
                total, solves, inaccurate = total + it, solves + 1, inaccurate or bad
                held = None if box is None else held_variables(box, p, y, l, u)
            else:
                p, y, *held = certified
                self.y = y
            p_N = np.maximum(p[0::3], 0.0)
            change = np.abs(p_N - pbar_N).max()
            if change <= self.fp_tol * max(p_N.max(), 1e-12):
                return p, total, fp, solves, True, inaccurate
            rank = (self._cone_excess(p, mu), change)
            if rank < best[0]:
                best = (rank, p)
            # the Newton update (the fixed point on this iterate's active set, K = 4), except
            # right after a Newton update that did not contract (its active set was wrong);
            # then the plain update p_N, relaxed by 1/2 from the first plain one that does not
            # contract (two-cycles)
            stalled = change > 0.9 * last_change
            damped = damped or (stalled and last_update == "plain")
            newton = None if (stalled and last_update == "newton") or box is None else _newton_update(P, c, mu, *held, p_N)
            if newton is not None:
                pbar_N, last_update = newton, "newton"
            else:
                pbar_N, last_update = (0.5 * (pbar_N + p_N) if damped else p_N), "plain"
            last_change = change
        return best[1], total, fp, solves, False, inaccurate

    def _bounds(self, pbar_N, mu):
        """OSQP's l and u of the fixed-point form: p_N >= 0, |d_k . p_T| <= mu pbar_N."""
        m = len(pbar_N)
        bound = np.repeat(mu * pbar_N, len(self.D))
        return np.concatenate([np.zeros(m), -bound]), np.concatenate([np.full(m, np.inf), bound])

    def _dense_constraints(self, m):
        """The fixed-point form's constraint matrix (dense) and its active_set.BoxForm (or None)."""
        if m not in self._A_dense:
            self._A_dense[m] = _constraint_matrix(m, self.D).toarray()
            self._box[m] = box_form(self._A_dense[m])
        return self._A_dense[m], self._box[m]

    def _cone_excess(self, p, mu) -> float:
        """max_i (max_k |d_k . p_T,i| - mu_i p_N,i)_+ / max p_N: how far friction leaves its pyramid."""
        p3 = p.reshape(-1, 3)
        p_N = np.maximum(p3[:, 0], 0.0)
        excess = np.abs(p3[:, 1:] @ self.D.T).max(axis=1) - mu * p_N
        return max(0.0, float(excess.max())) / max(float(p_N.max()), 1e-12)

    def _clip_friction(self, p, mu):
        """Scale each p_T into the pyramid of its own p_N: max_k |d_k . p_T| <= mu p_N."""
        p = p.copy()
        p_N = np.maximum(p[0::3], 0.0)
        p_T = np.stack([p[1::3], p[2::3]], axis=1)
        worst = np.max(np.abs(p_T @ self.D.T), axis=1)
        scale = np.where(worst > mu * p_N, mu * p_N / np.maximum(worst, 1e-300), 1.0)
        p[0::3], p[1::3], p[2::3] = p_N, p_T[:, 0] * scale, p_T[:, 1] * scale
        return p


def _newton_update(P, c, mu, at_lo, at_hi, p_N):
    """The next pbar_N: the normal impulses of ``coulomb_fixed_point`` on the active set
    (at_lo, at_hi) of the last iterate (K = 4), clipped at 0; None if the solve fails or if
    their sum exceeds NEWTON_MAX_GROWTH times that of the last iterate's p_N (a wrong active
    set: measured, up to 800 times, and such bounds can stall OSQP)."""
    try:
        guess = np.maximum(coulomb_fixed_point(P, c, mu, at_lo, at_hi)[0::3], 0.0)
    except np.linalg.LinAlgError:
        return None
    if not (np.isfinite(guess).all() and guess.sum() <= NEWTON_MAX_GROWTH * p_N.sum()):
        return None
    return guess


def coulomb_fixed_point(P: np.ndarray, c: np.ndarray, mu: np.ndarray, at_lo: np.ndarray,
                        at_hi: np.ndarray) -> np.ndarray:
    """The impulses p whose QP with friction bound mu p_N has the given active set (K = 4 facets).

    Implements: the friction fixed point of [COBRA] eq. (6) (module docstring, note friction),
    solved on a known active set instead of iterated: with p_N in the bounds themselves, the
    KKT conditions of eq. (6) on that set are one square linear system,

        (P p + c)_j = 0                   for every free component j
        p_N,i = 0                         for a released contact (p_N held at 0)
        p_t,i -/+ mu_i p_N,i = 0          for a tangential component held at +-mu_i pbar_N,i

    so when the set is right, the next iterate reproduces these p_N and the fixed point has
    converged. ``at_lo``/``at_hi``: (3m,) masks of components held at their lower/upper bound.
    """
    held = np.flatnonzero(at_lo | at_hi)
    K, rhs = P.copy(), -c.copy()
    K[held], rhs[held] = 0.0, 0.0
    K[held, held] = 1.0
    tangential = held[held % 3 != 0]
    K[tangential, tangential - tangential % 3] = np.where(at_hi[tangential], -1.0, 1.0) * mu[tangential // 3]
    _, _, p, info = _gesv(K, rhs)  # LAPACK's LU solve
    if info != 0:
        raise np.linalg.LinAlgError(f"the fixed-point system is singular (info {info})")
    return p


_gesv = get_lapack_funcs("gesv", (np.zeros(1),))


def kkt_residuals(G: np.ndarray, c: np.ndarray, p: np.ndarray, mu, D: np.ndarray):
    """Complementarity, cone and stick residuals of p for the velocity-level eq. (2).

    Implements: the optimality (KKT) conditions of [COBRA] eq. (6) = eq. (2) at velocity level.

    w = G p + c. Returns (max |p_N w_N|, relative cone violation, max |w_T| among contacts
    whose tangential impulse is strictly inside the pyramid). ``mu``: scalar or one per contact.
    "Strictly inside" means inside by more than 1e-6 mu max p_N, the same scale as the cone
    residual: a contact carrying a tiny load and sliding at its bound is not counted as sticking.
    """
    if len(p) == 0:
        return 0.0, 0.0, 0.0
    p3, w3 = p.reshape(-1, 3), (G @ p + c).reshape(-1, 3)
    p_N = p3[:, 0]
    comp = float(np.abs(p_N * w3[:, 0]).max())
    facet = np.abs(p3[:, 1:] @ D.T)  # (m, K/2)
    scale = max(float(p_N.max()), 1e-12)
    mu = np.broadcast_to(np.asarray(mu, dtype=float), p_N.shape)
    bound = (mu * p_N)[:, None]
    cone = max(0.0, float((facet - bound).max())) / scale
    inside = (facet < bound - 1e-6 * scale * mu[:, None]).all(axis=1) & (p_N > 1e-9 * scale)
    w_T = w3[inside, 1:]
    stick = float(np.sqrt((w_T * w_T).sum(axis=1).max())) if len(w_T) else 0.0
    return comp, cone, stick


def _cond(P: np.ndarray) -> float:
    eig = np.linalg.eigvalsh(P)
    return float(eig[-1] / eig[0]) if eig[0] > 0 else np.inf


def _cond_factored(B: np.ndarray, eps: float) -> float:
    """cond(B B^T + eps I) from the smaller Gram matrix of B (n x r).

    The nonzero eigenvalues of B B^T are those of B^T B; if n > r, B B^T also has the
    eigenvalue 0, so the smallest eigenvalue of B B^T + eps I is eps.
    """
    n, r = B.shape
    lam = np.linalg.eigvalsh(B.T @ B if r <= n else B @ B.T)
    lam_min = 0.0 if n > r else max(lam[0], 0.0)
    return float((lam[-1] + eps) / (lam_min + eps))
