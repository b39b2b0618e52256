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

Note (friction): by default (``friction="fixed-point"``) the friction bound uses pbar_N, the
normal impulse of the previous iterate, and the QP is re-solved until p_N stops changing (a
De Saxce / "staggered projections" fixed point): at convergence the bound is mu p_N, exact
Coulomb friction on the pyramid with 0 <= p_N _|_ w_N >= 0. Iterates take the full update
while they contract and half of it from the first one that does not (damping against cycling). Starting from the
previous step's p_N (warm start), rolling without the box converges in about 4 iterates; cold
starts (random 5-contact problems) need 10-100. If it has not converged after ``fp_max``
iterates (50; the stepper uses ``StepSettings.fp_max`` = 10 because it warm-starts) -- robot, box and ground jam, and redundant
contacts (4 box corners, 13 spheres on a 6-DoF robot base) leave the split of p_N between
them undetermined, so the friction bounds wander along that null space; more iterates (50,
200, Anderson acceleration) were measured not to fix it -- the last iterate's friction is
clipped into the pyramid of its own p_N and ``QPInfo.status`` says so: the step then obeys
the cone exactly but only approximately the stick/slip condition (``stick_slip_residual``
reports by how much), and the velocities stay consistent with the impulses actually applied.
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


def facet_directions(n_facets: int) -> np.ndarray:
    """(K/2, 2) unit facet normals d_k in the (t1, t2) plane, angles 2 pi k / K.

    Helper: the facets of the friction pyramid that linearizes F_i of [COBRA] eq. (2).
    """
    if n_facets < 4 or n_facets % 2:
        raise ValueError(f"n_facets must be an even number >= 4, got {n_facets}")
    angles = 2 * np.pi * np.arange(n_facets // 2) / n_facets
    return np.stack([np.cos(angles), np.sin(angles)], axis=1)


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


def _upper_dense_csc(A: np.ndarray) -> sparse.csc_matrix:
    """Upper triangle of a dense matrix with every entry stored (fixed sparsity for updates)."""
    n = len(A)
    iu = np.triu_indices(n)
    order = np.lexsort((iu[0], iu[1]))  # column-major for CSC
    rows, cols = iu[0][order], iu[1][order]
    indptr = np.concatenate([[0], np.cumsum(np.arange(1, n + 1))])
    return sparse.csc_matrix((A[rows, cols], rows, indptr), shape=(n, n))


class ContactQP:
    """OSQP least-action solver with warm starts; reuses its factorization pattern when m repeats.

    Implements: [COBRA] eq. (6) (see the module docstring for the formulation and notes).
    """

    def __init__(self, mu: float, n_facets: int = 4, reg: float = 1e-6, eps: float = 1e-7,
                 friction: str = "fixed-point", fp_tol: float = 1e-8, fp_max: int = 50,
                 max_iter: int = 20000):
        if not (np.isfinite(mu) and mu >= 0):
            raise ValueError(f"mu must be finite and >= 0, got {mu}")
        if friction not in ("convex", "fixed-point"):
            raise ValueError(f"friction must be 'convex' or 'fixed-point', got {friction!r}")
        self.mu, self.D, self.reg, self.friction = mu, facet_directions(n_facets), reg, friction
        self.eps, self.fp_tol, self.fp_max, self.max_iter = eps, fp_tol, fp_max, max_iter
        self._solvers: dict = {}

    def solve(self, G: np.ndarray, c: np.ndarray, p_warm: np.ndarray | None = None, mu=None):
        """Impulses p (3m,) ordered [p_N, p_t1, p_t2] per contact, and a QPInfo.

        ``mu``: a friction coefficient per contact (m,), or None for the solver's ``mu``.
        """
        m = len(c) // 3
        if m == 0:
            return np.zeros(0), QPInfo("solved", 0, 0, 0.0, 0.0, 0.0, 1.0)
        mu = np.full(m, self.mu) if mu is None else np.broadcast_to(np.asarray(mu, dtype=float), (m,))
        if not (np.all(np.isfinite(mu)) and np.all(mu >= 0)):
            raise ValueError(f"friction coefficients must be finite and >= 0, got {mu}")
        # eq. (6) with a small uniform regularization eps I (module docstring)
        P = G + self.reg * max(np.mean(np.diag(G)), 1e-300) * np.eye(3 * m)
        p0 = np.zeros(3 * m) if p_warm is None else np.asarray(p_warm, dtype=float).copy()
        status, iters, fp = "solved", 0, 1
        if self.friction == "fixed-point":
            p, iters, fp, ok, inaccurate = self._fixed_point(P, c, p0, mu)
            if not ok:
                status = "solved (fixed point not converged; friction clipped)"
                p = self._clip_friction(p, mu)
        else:
            solver = self._solver(m, P, c, convex=mu)
            n_rows = m * (1 + 2 * len(self.D))
            p, it, inaccurate = self._run(solver, m, p0, np.zeros(n_rows), np.full(n_rows, np.inf))
            iters += it
        if inaccurate and status == "solved":
            status = "solved inaccurate"
        info = QPInfo(status, iters, fp, *kkt_residuals(G, c, p, mu, self.D), cond_G=_cond(P))
        return p, info

    def _solver(self, m, P, c, convex=None):
        """An OSQP instance for m contacts: set up once per (m, kind), then only updated.

        ``convex``: None for the fixed-point form, else the (m,) friction coefficients that
        enter the convex cone's constraint matrix.
        """
        key = (m, None if convex is None else tuple(convex))
        Px = _upper_dense_csc(P)
        if key not in self._solvers:
            A = _constraint_matrix(m, self.D, convex)
            solver = osqp.OSQP()
            solver.setup(P=Px, q=c, A=A, l=np.zeros(A.shape[0]), u=np.full(A.shape[0], np.inf),
                         eps_abs=self.eps, eps_rel=self.eps, polishing=True, verbose=False,
                         max_iter=self.max_iter, warm_starting=True, polish_refine_iter=5)
            if len(self._solvers) > 64:
                self._solvers.clear()
            self._solvers[key] = solver
        else:
            self._solvers[key].update(Px=Px.data, q=c)
        return self._solvers[key]

    def _run(self, solver, m, p0, l, u):
        """One OSQP solve (polished when it can be); a failed one is retried cold, tighter."""
        solver.update(l=l, u=u)
        solver.warm_start(x=p0)
        res = solver.solve(raise_error=False)
        iters = res.info.iter
        if res.info.status != "solved":
            solver.update_settings(eps_abs=self.eps * 1e-2, eps_rel=self.eps * 1e-2)
            solver.warm_start(x=np.zeros(3 * m))
            res = solver.solve(raise_error=False)
            iters += res.info.iter
            solver.update_settings(eps_abs=self.eps, eps_rel=self.eps)
        if res.info.status not in ("solved", "solved inaccurate"):
            raise ContactSolveError(f"OSQP status '{res.info.status}' after {res.info.iter} iterations "
                                    f"(m = {m} contacts)")
        return res.x, iters, res.info.status != "solved"

    def _fixed_point(self, P, c, p, mu):
        """Friction bounded by mu pbar_N of the previous iterate, until p_N stops changing."""
        m = len(c) // 3
        solver = self._solver(m, P, c)
        pbar_N = np.maximum(p[0::3], 0.0)
        total, inaccurate, damped, last_change = 0, False, False, np.inf
        for fp in range(1, self.fp_max + 1):
            bound = np.repeat(mu * pbar_N, len(self.D))
            l = np.concatenate([np.zeros(m), -bound])
            u = np.concatenate([np.full(m, np.inf), bound])
            p, it, bad = self._run(solver, m, p, l, u)
            total, inaccurate = total + it, inaccurate or bad
            p_N = np.maximum(p[0::3], 0.0)
            change = np.abs(p_N - pbar_N).max()
            if change <= self.fp_tol * max(p_N.max(), 1e-12):
                return p, total, fp, True, inaccurate
            # full update while the iterates contract; relaxation 1/2 once they stop (two-cycles)
            damped = damped or change > 0.9 * last_change
            pbar_N = 0.5 * (pbar_N + p_N) if damped else p_N
            last_change = change
        return p, total, self.fp_max, False, inaccurate

    def _clip_friction(self, p, mu):
        """Scale each p_T into the pyramid of its own p_N: max_k |d_k . p_T| <= mu p_N."""
        p = p.copy()
        p_N = np.maximum(p[0::3], 0.0)
        p_T = np.stack([p[1::3], p[2::3]], axis=1)
        worst = np.max(np.abs(p_T @ self.D.T), axis=1)
        scale = np.where(worst > mu * p_N, mu * p_N / np.maximum(worst, 1e-300), 1.0)
        p[0::3], p[1::3], p[2::3] = p_N, p_T[:, 0] * scale, p_T[:, 1] * scale
        return p


def kkt_residuals(G: np.ndarray, c: np.ndarray, p: np.ndarray, mu, D: np.ndarray):
    """Complementarity, cone and stick residuals of p for the velocity-level eq. (2).

    Implements: the optimality (KKT) conditions of [COBRA] eq. (6) = eq. (2) at velocity level.

    w = G p + c. Returns (max |p_N w_N|, relative cone violation, max |w_T| among contacts
    whose tangential impulse is strictly inside the pyramid). ``mu``: scalar or one per contact.
    """
    w = G @ p + c
    p_N, w_N = p[0::3], w[0::3]
    mu = np.broadcast_to(np.asarray(mu, dtype=float), p_N.shape)
    p_T = np.stack([p[1::3], p[2::3]], axis=1)
    w_T = np.stack([w[1::3], w[2::3]], axis=1)
    comp = float(np.max(np.abs(p_N * w_N))) if len(p_N) else 0.0
    facet = np.abs(p_T @ D.T)  # (m, K/2)
    scale = max(float(p_N.max()), 1e-12) if len(p_N) else 1.0
    bound = (mu * p_N)[:, None]
    cone = float(max(0.0, np.max(facet - bound)) / scale) if len(p_N) else 0.0
    inside = np.all(facet < bound * (1 - 1e-6), axis=1) & (p_N > 1e-9 * scale)
    stick = float(np.max(np.linalg.norm(w_T[inside], axis=1))) if inside.any() else 0.0
    return comp, cone, stick


def _cond(P: np.ndarray) -> float:
    eig = np.linalg.eigvalsh(P)
    return float(eig[-1] / eig[0]) if eig[0] > 0 else np.inf
