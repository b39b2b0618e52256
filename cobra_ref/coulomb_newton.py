"""Coulomb's law on the rows of a least-action problem, and Newton's method on its active set.

Implements: the exact conditions of the friction fixed point of [COBRA] eq. (6)
(:mod:`cobra_ref.least_action`), for a problem ``least_action.LeastAction`` (H, c, mu, lo, hi,
stiction_velocity, m). The pieces the fixed point shares with this module:

* ``hessian`` and ``residual``: G + R of an iterate and r = (G + R) x + c, with the stick-slip
  compliance of the compliant friction law, which depends on the normal impulses (``stick_slip``);
* ``coulomb_split``: an iterate's normal and friction impulses, and where each contact's friction
  would go without its bound.

The accelerator, ``coulomb_newton``: given an iterate x, it reads the active set (which contacts
are released, which stick, which slide, which servo rows saturate: ``active_set``) and solves the
conditions of Coulomb's law on that set, with each sliding contact's friction angle as an extra
unknown, by Newton's method; rows whose solution breaks their set's inequalities change set and
it solves again (``_corrected``). When the set is right the fixed point's next QP reproduces
its guesses and the loop stops.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np
from scipy.linalg import get_lapack_funcs

from .compliance import STICK_SLIP_MAX, stick_slip_compliance

RELEASED = 1e-9  # a contact whose normal impulse is below RELEASED max p_N carries nothing
NEWTON_TOL = 1e-6  # Newton's iterations stop when a step changes no impulse by more than this (relative)
_SQRT_NEWTON_TOL = np.sqrt(NEWTON_TOL)
_gesv = get_lapack_funcs("gesv", (np.zeros(1),))


def hessian(problem, pbar_N: np.ndarray, R_T=None) -> np.ndarray:
    """G + R of an iterate, the QP matrix of one fixed-point iterate: the problem's H with the
    stick-slip compliance of pbar_N (or R_T) added (compliant law; the rigid law adds 0)."""
    m, H = problem.m, problem.H.copy()
    R_T = stick_slip(problem, pbar_N) if R_T is None else R_T
    diagonal = H.reshape(-1)[::len(H) + 1]  # a view of H's diagonal
    diagonal[1:3 * m:3] += R_T
    diagonal[2:3 * m:3] += R_T
    return H


def residual(problem, x: np.ndarray, pbar_N: np.ndarray) -> np.ndarray:
    """r = (G + R) x + c with the stick-slip compliance of pbar_N: each row's law residual,
    ``hessian(problem, pbar_N) @ x + problem.c`` without forming that matrix."""
    r = problem.H @ x + problem.c
    m = problem.m
    R_T = stick_slip(problem, pbar_N)
    r[1:3 * m:3] += R_T * x[1:3 * m:3]
    r[2:3 * m:3] += R_T * x[2:3 * m:3]
    return r


def stick_slip(problem, pbar_N: np.ndarray) -> np.ndarray:
    """The friction rows' compliance (m,) that depends on pbar_N (compliant law; 0 for the rigid
    one): :func:`cobra_ref.compliance.stick_slip_compliance` with this problem's v_s and G_TT (the
    mean tangential diagonal of H)."""
    return stick_slip_compliance(problem.stiction_velocity, problem.mu * pbar_N, _tangential_diagonal(problem.H, problem.m))


def _tangential_diagonal(H: np.ndarray, m: int) -> np.ndarray:
    """(m,) mean of each contact's two tangential diagonal entries of H."""
    d = H.diagonal()
    return 0.5 * (d[1:3 * m:3] + d[2:3 * m:3])


def coulomb_split(x: np.ndarray, r: np.ndarray, H: np.ndarray, m: int):
    """(p_N (m,), p_T (m, 2), z (m, 2)): normal and friction impulses, and z = p_T - r_T / a.

    z_i is where contact i's friction would go without its bound (``least_action``'s module
    docstring); a_i is the mean of its two tangential diagonal entries of H (the matrix H, or directly
    those means, (m,)).
    """
    p = x[:3 * m].reshape(m, 3)
    r_T = r[:3 * m].reshape(m, 3)[:, 1:]
    a = H if H.ndim == 1 else _tangential_diagonal(H, m)
    return p[:, 0], p[:, 1:], p[:, 1:] - r_T / a[:, None]


class ActiveSet(NamedTuple):
    """Which way each row of an iterate is held (``active_set``)."""

    released: np.ndarray  # (m,) contacts with p_N = 0
    sliding: np.ndarray  # (m,) contacts whose friction is on its circle
    at_lo: np.ndarray  # (n - 3m,) servo rows held at their lower bound
    at_hi: np.ndarray  # (n - 3m,) servo rows held at their upper bound


def active_set(problem, x: np.ndarray, r: np.ndarray, H: np.ndarray) -> ActiveSet:
    """The active set of impulses x with residual r = H x + c (H, or its tangential means: ``coulomb_split``):
    released, sliding, saturated rows.

    Released = p_N below RELEASED max p_N; sliding = |z_i| > mu p_N,i (the friction would
    leave its circle without the bound); a servo row is held at a bound it sits on when its
    residual pushes against that bound.
    """
    m = problem.m
    p_N, _, z = coulomb_split(x, r, H, m)
    released = p_N <= RELEASED * max(float(p_N.max(initial=0.0)), 1e-300)
    sliding = ~released & (np.hypot(*z.T) > problem.mu * p_N)
    x_s, r_s = x[3 * m:], r[3 * m:]
    tol = 1e-9 * max(float(np.abs(problem.hi).max(initial=0.0)), 1e-300)
    return ActiveSet(released, sliding, (x_s <= problem.lo + tol) & (r_s >= 0), (x_s >= problem.hi - tol) & (r_s <= 0))


def coulomb_newton(problem, x: np.ndarray, rounds: int = 4, steps: int = 4):
    """(pbar_N, theta, X) solving Coulomb's law exactly near x by Newton's method, or None.

    Implements: the friction fixed point of [COBRA] eq. (6) on an active set. With the friction
    angle theta_i of each sliding contact as an extra unknown, the conditions are a square
    system in (x, theta_S)::

        r_j = 0                              every free row j (r = (G + R(x)) x + c)
        x_j = 0 (released contact), x_j = bound (saturated servo row)
        p_T,i = mu_i p_N,i e(theta_i),  e_perp(theta_i) . r_T,i = 0      every sliding contact i

    (friction on its circle, pointing against the slip), with R(x) the stick-slip compliance of
    the compliant law, which depends on p_N. The active set starts as x's (``active_set``); after
    at most ``steps`` Newton iterations, rows whose solution breaks their set's inequalities
    change set (``_corrected``: a sticking contact outside its circle slides, a sliding one whose
    slip turns sticks, a contact pulling is released, a released one that closes is engaged, a
    servo row beyond its bound saturates, a saturated one pulled back is freed), for up to
    ``rounds`` rounds. None if the linear system is singular, the result not finite, or the set
    still changes.
    """
    act, theta0 = newton_start(problem, x)
    return newton_rounds(problem, x, theta0, act, rounds, steps)


def newton_start(problem, x: np.ndarray):
    """(act, theta0): where ``coulomb_newton`` starts from impulses x, their active set
    (``active_set``) and each contact's friction angle (against the slip where it has no friction yet)."""
    m = problem.m
    H = hessian(problem, np.maximum(x[0:3 * m:3], 0.0))
    r = H @ x + problem.c
    p_T, r_T = x[:3 * m].reshape(m, 3)[:, 1:], r[:3 * m].reshape(m, 3)[:, 1:]
    start = np.where((np.hypot(*p_T.T) > 0)[:, None], p_T, -r_T)
    return active_set(problem, x, r, H), np.arctan2(start[:, 1], start[:, 0])


def newton_rounds(problem, x: np.ndarray, theta0: np.ndarray, act: ActiveSet, rounds: int, steps: int):
    """``coulomb_newton``'s rounds from x, the angles theta0 and the active set ``act``: the answer
    (pbar_N, theta, X) of the first round whose set needs no correction, or None."""
    m = problem.m
    for _ in range(rounds):
        system = _NewtonSystem(problem, act)
        X, theta = x.copy(), theta0.copy()
        for _ in range(steps):
            K, F, r = system.at(X, theta)
            _, _, d, info = _gesv(K, -F)  # LAPACK's LU solve
            if info != 0 or not np.isfinite(d).all():
                return None
            X, theta[system.S] = X + d[:len(X)], theta[system.S] + d[len(X):]
            # Newton's method converges quadratically: after a step of relative size s the error is
            # of the order s^2, so a step below sqrt(NEWTON_TOL) ends it
            if np.abs(d).max() <= _SQRT_NEWTON_TOL * np.abs(X).max():
                break
        corrected = _corrected(problem, X, theta, act, system.residual(X))
        if (np.concatenate(corrected) == np.concatenate(act)).all():  # the same set: every mask equal
            return newton_answer(X, theta, act.sliding, m)
        act = corrected
    return None


def newton_answer(X: np.ndarray, theta: np.ndarray, sliding: np.ndarray, m: int):
    """(pbar_N, theta, X) of a Newton solution X, theta on a set whose sliding contacts are ``sliding``:
    the normal impulses, the sliding contacts' angles and the others' friction directions."""
    p_N, p_T = np.maximum(X[0:3 * m:3], 0.0), X[:3 * m].reshape(m, 3)[:, 1:]
    return p_N, np.where(sliding, theta, np.arctan2(p_T[:, 1], p_T[:, 0])), X


class _NewtonSystem:
    """Jacobian K and residual F of ``coulomb_newton``'s system for one active set, at (X, theta_S).

    The unknowns are X (n,) then theta_S; the rows are r's, replaced by the circle's conditions on
    the tangent rows of the sliding contacts, then one row per sliding contact (index D).
    """

    def __init__(self, problem, act: ActiveSet):
        m, n = problem.m, len(problem.c)
        pinned = np.concatenate([np.repeat(act.released, 3), act.at_lo | act.at_hi])
        layout = _layout(m, n, act.sliding.tobytes(), pinned.tobytes())
        self.problem, self.m, self.n, self.layout, self.S = problem, m, n, layout, layout.S
        target = np.zeros(n)
        target[3 * m:] = np.where(act.at_lo, problem.lo, problem.hi)
        self.target = target[layout.pinned]
        self.G_TT = _tangential_diagonal(problem.H, m)
        self.R_max = STICK_SLIP_MAX * self.G_TT
        size = n + len(self.S)
        self.K = np.zeros((size, size))
        self.K_flat = self.K.reshape(-1)  # a view
        self.F = np.zeros(size)

    def residual(self, X) -> np.ndarray:
        """r = (G + R(X)) X + c at X."""
        return residual(self.problem, X, np.maximum(X[0:3 * self.m:3], 0.0))

    def at(self, X, theta):
        """(K, F, r) at (X, theta) (``coulomb_newton``'s system)."""
        problem, m, n, K, K_flat, F, at = self.problem, self.m, self.n, self.K, self.K_flat, self.F, self.layout
        N, T1, T2 = at.N, at.T1, at.T2
        p_N = np.maximum(X[0:3 * m:3], 0.0)
        R_T = stick_slip_compliance(problem.stiction_velocity, problem.mu * p_N, self.G_TT)
        K[:n, :n], K[:n, n:] = problem.H, 0.0
        K_flat[at.diag_T] += np.concatenate([R_T, R_T])
        r = K[:n, :n] @ X + problem.c
        F[:n] = r
        # the stick-slip compliance R_T = v_s / (mu p_N) where it is not capped: d r_T / d p_N = -R_T p_T / p_N
        uncapped = (R_T < self.R_max) & (p_N > 0)
        dR = np.where(uncapped, R_T / np.where(uncapped, p_N, 1.0), 0.0)
        K_flat[at.dT_dN] -= np.concatenate([dR, dR]) * X[at.tangent]
        # sliding contact i (row D, the rows n: on): p_T = mu p_N e(theta) and e_perp . r_T = 0, d e_perp / d theta = -e
        mu, c, sn = problem.mu[at.S], np.cos(theta[at.S]), np.sin(theta[at.S])
        K[n:, :n] = c[:, None] * K.take(T2, 0)[:, :n] - sn[:, None] * K.take(T1, 0)[:, :n]
        K[n:, n:] = 0.0
        r_T1, r_T2, mu_p_N = r[T1], r[T2], mu * X[N]
        F[n:] = c * r_T2 - sn * r_T1
        # its tangent rows: the circle's conditions, in place of the law's rows
        K[at.T] = 0.0
        K_flat[at.circle] = np.concatenate([at.ones, -mu * c, -mu * sn, mu_p_N * sn, -mu_p_N * c,
                                            -(c * r_T1 + sn * r_T2)])
        F[T1], F[T2] = X[T1] - mu_p_N * c, X[T2] - mu_p_N * sn
        # released contacts and saturated servo rows are pinned at their targets
        K[at.pinned] = 0.0
        K_flat[at.diag_pinned] = 1.0
        F[at.pinned] = X[at.pinned] - self.target
        return K, F, r


class _Layout(NamedTuple):
    """Where ``_NewtonSystem``'s rows and entries sit for one active set (``_layout``)."""

    S: np.ndarray  # the sliding contacts
    N: np.ndarray  # their normal rows 3i
    T1: np.ndarray  # their first tangent rows 3i+1
    T2: np.ndarray  # their second tangent rows 3i+2
    D: np.ndarray  # their angle rows n, n+1, ...
    T: np.ndarray  # T1 then T2
    pinned: np.ndarray  # the pinned rows (released contacts, saturated servo rows)
    tangent: np.ndarray  # every contact's tangent rows 3i+1, then 3i+2
    diag_T: np.ndarray  # positions in K.flat of their diagonal entries
    dT_dN: np.ndarray  # ... of their derivatives by p_N, (3i+1, 3i), (3i+2, 3i)
    diag_pinned: np.ndarray  # ... of the pinned rows' diagonal entries
    circle: np.ndarray  # ... of the circle's entries, in the order ``_NewtonSystem.at`` lists their values
    ones: np.ndarray  # (2k,) the circle's first values


@functools.lru_cache(maxsize=256)
def _layout(m: int, n: int, sliding: bytes, pinned: bytes) -> _Layout:
    """The ``_Layout`` of m contacts and n rows with the masks ``sliding`` (m,) and ``pinned`` (n,),
    as bytes: it depends only on them, and an active set seldom changes, so it is kept (read only)."""
    S = np.flatnonzero(np.frombuffer(sliding, dtype=bool))
    size = n + len(S)
    N = 3 * S
    T1, T2, D = N + 1, N + 2, np.arange(n, size)
    pinned_rows = np.flatnonzero(np.frombuffer(pinned, dtype=bool))
    i = np.arange(m)
    tangent, normal = np.concatenate([3 * i + 1, 3 * i + 2]), np.concatenate([3 * i, 3 * i])
    # K.flat positions of (T1, T1), (T2, T2), (T1, N), (T2, N), (T1, D), (T2, D), (D, D)
    circle = np.concatenate([T1 * size + T1, T2 * size + T2, T1 * size + N, T2 * size + N, T1 * size + D,
                             T2 * size + D, D * size + D])
    layout = _Layout(S, N, T1, T2, D, np.concatenate([T1, T2]), pinned_rows, tangent, tangent * (size + 1),
                     tangent * size + normal, pinned_rows * (size + 1), circle, np.ones(2 * len(S)))
    for a in layout:
        a.flags.writeable = False
    return layout


def _corrected(problem, X, theta, act: ActiveSet, r) -> ActiveSet:
    """The active set after the changes that the Newton solution (X, theta) of ``act`` asks for (r: its residual)."""
    m = problem.m
    p = X[:3 * m].reshape(m, 3)
    r3 = r[:3 * m].reshape(m, 3)
    tol = 1e-9 * np.abs(p[:, 0]).max(initial=0.0)  # impulses
    tol_r = 1e-9 * np.abs(r3).max(initial=0.0)  # the laws' residuals (velocities)
    outside = np.hypot(p[:, 1], p[:, 2]) > problem.mu * p[:, 0] + tol
    turned = np.cos(theta) * r3[:, 1] + np.sin(theta) * r3[:, 2] > tol_r  # the slip runs along the friction: it should stick
    engaged = act.released & (r3[:, 0] < -tol_r)  # a released contact that would close: it is engaged, sliding
    released = (act.released & ~engaged) | (~act.released & (p[:, 0] < -tol))
    sliding = ~released & ((act.sliding & ~turned) | (~act.sliding & outside) | engaged)
    x_s, r_s, lo, hi = X[3 * m:], r[3 * m:], problem.lo, problem.hi
    tol_s = 1e-9 * np.abs(hi).max(initial=0.0)
    tol_rs = 1e-9 * np.abs(r_s).max(initial=0.0)
    free = ~act.at_lo & ~act.at_hi
    at_lo = (act.at_lo & (r_s >= -tol_rs)) | (free & (x_s < lo - tol_s))
    at_hi = (act.at_hi & (r_s <= tol_rs)) | (free & (x_s > hi + tol_s))
    return ActiveSet(released, sliding, at_lo, at_hi)
