"""The friction loop's first guess for K least-action problems at once: Newton's first round, batched.

For performance: ``first_guesses(problems, starts)`` is ``[least_action.guess(p, x) for p, x in
zip(problems, starts)]``, bit for bit, for the K members of a batched step
(:mod:`cobra_ref.fast.batch`). The first round of :func:`cobra_ref.coulomb_newton.coulomb_newton`
(its start, the Newton iterations on the start's active set, and the check of that set) runs for
every member together:

* the members' rows and contacts are concatenated (``members.MemberRows``), so each elementwise
  operation of the single member's code is one NumPy call for all of them, and each per-member
  maximum is a segment maximum (``members.segment_max``);
* the members' Newton matrices K lie side by side in one flat buffer, each (size, size) in C order
  as the single member's, written through index arrays built once per round (``_System``);
* the matrix-vector products and LU solves stay per member: the same BLAS and LAPACK calls on
  arrays of the same shape and strides.

A member whose active set needs correcting goes on with the single member's later rounds
(``coulomb_newton.newton_rounds``), and every member's guess is then chosen as ``guess`` chooses
it (``least_action.chosen_guess``). Tested equal to ``guess`` member by member.
"""

from __future__ import annotations

import numpy as np

from ..coulomb_newton import _SQRT_NEWTON_TOL, RELEASED, ActiveSet, _gesv, hessian, newton_answer, newton_rounds
from ..least_action import chosen_guess
from .members import Problems, segment_max

ROUNDS, STEPS = 4, 4  # coulomb_newton's rounds and Newton steps per round


def first_guesses(problems, starts, b: Problems | None = None) -> list:
    """``least_action.guess(problems[k], starts[k])`` for every member k (module docstring); every
    problem has at least one row. ``b``: ``Problems(problems)``, if made already."""
    b = Problems(problems) if b is None else b
    x = np.concatenate(starts)
    act, theta0 = _start(b, x)
    X, theta, failed = _newton_round(b, act, x, theta0)
    corrected = _corrected(b, X, theta, act, _residual(b, X))
    changed = np.zeros(b.rows.K, dtype=bool)
    for new, old, member in zip(corrected, act, (b.rows.of_contact, b.rows.of_contact, b.rows.of_servo,
                                                 b.rows.of_servo)):
        np.logical_or.at(changed, member, new != old)
    R = b.rows
    pbar_N, theta_out = np.maximum(X[R.N], 0.0), np.where(act.sliding, theta, np.arctan2(X[R.T2], X[R.T1]))
    out = []
    for k, (problem, x_k) in enumerate(zip(problems, starts)):
        rows, contacts = R.row_slice(k), R.contact_slice(k)
        if failed[k]:
            newton = None
        elif changed[k]:  # the single member's later rounds, from the corrected set
            newton = newton_rounds(problem, x_k, theta0[contacts].copy(),
                                   ActiveSet(*(a[s] for a, s in zip(corrected, R.slices(k)))), ROUNDS - 1, STEPS)
        else:
            newton = pbar_N[contacts], theta_out[contacts], X[rows]
        out.append(chosen_guess(problem, x_k, newton))
    return out


def _start(b: Problems, x: np.ndarray):
    """``coulomb_newton.newton_start`` of every member: (the active set, theta0), concatenated."""
    R = b.rows
    R_T = b.stick_slip(b.mu * np.maximum(x[R.N], 0.0))
    r = b.products([hessian(p, None, R_T[R.contact_slice(k)]) for k, p in enumerate(b.problems)], x) + b.c
    p_T1, p_T2, r_T1, r_T2 = x[R.T1], x[R.T2], r[R.T1], r[R.T2]
    has_friction = np.hypot(p_T1, p_T2) > 0
    theta0 = np.arctan2(np.where(has_friction, p_T2, -r_T2), np.where(has_friction, p_T1, -r_T1))
    # coulomb_newton.active_set, with the tangential diagonal of the stick-slip H
    a = 0.5 * ((b.H_diagonal[R.T1] + R_T) + (b.H_diagonal[R.T2] + R_T))
    p_N = x[R.N]
    released = p_N <= RELEASED * np.maximum(segment_max(p_N, R.of_contact, R.K), 1e-300)[R.of_contact]
    sliding = ~released & (np.hypot(p_T1 - r_T1 / a, p_T2 - r_T2 / a) > b.mu * p_N)
    x_s, r_s = x[R.servo], r[R.servo]
    act = ActiveSet(released, sliding, (x_s <= b.lo + b.hi_scale) & (r_s >= 0), (x_s >= b.hi - b.hi_scale) & (r_s <= 0))
    return act, theta0


def _residual(b: Problems, X: np.ndarray) -> np.ndarray:
    """``coulomb_newton.residual`` of every member at X with the stick-slip compliance of X's p_N."""
    R = b.rows
    r = b.products([p.H for p in b.problems], X) + b.c
    R_T = b.stick_slip(b.mu * np.maximum(X[R.N], 0.0))
    r[R.T1] += R_T * X[R.T1]
    r[R.T2] += R_T * X[R.T2]
    return r


def _corrected(b: Problems, X, theta, act: ActiveSet, r) -> ActiveSet:
    """``coulomb_newton._corrected`` of every member: the active set its Newton solution asks for."""
    R = b.rows
    p_N, p_T1, p_T2, r_N, r_T1, r_T2 = X[R.N], X[R.T1], X[R.T2], r[R.N], r[R.T1], r[R.T2]
    tol = 1e-9 * segment_max(np.abs(p_N), R.of_contact, R.K)[R.of_contact]
    r_max = np.maximum(np.maximum(np.abs(r_N), np.abs(r_T1)), np.abs(r_T2))
    tol_r = 1e-9 * segment_max(r_max, R.of_contact, R.K)[R.of_contact]
    outside = np.hypot(p_T1, p_T2) > b.mu * p_N + tol
    turned = np.cos(theta) * r_T1 + np.sin(theta) * r_T2 > tol_r
    engaged = act.released & (r_N < -tol_r)
    released = (act.released & ~engaged) | (~act.released & (p_N < -tol))
    sliding = ~released & ((act.sliding & ~turned) | (~act.sliding & outside) | engaged)
    x_s, r_s = X[R.servo], r[R.servo]
    tol_rs = 1e-9 * segment_max(np.abs(r_s), R.of_servo, R.K)[R.of_servo]
    free = ~act.at_lo & ~act.at_hi
    at_lo = (act.at_lo & (r_s >= -tol_rs)) | (free & (x_s < b.lo - b.hi_tol))
    at_hi = (act.at_hi & (r_s <= tol_rs)) | (free & (x_s > b.hi + b.hi_tol))
    return ActiveSet(released, sliding, at_lo, at_hi)


def _newton_round(b: Problems, act: ActiveSet, x: np.ndarray, theta0: np.ndarray):
    """(X, theta, failed (K,)): ``coulomb_newton``'s Newton iterations on the active set ``act`` from
    (x, theta0) for every member, each stopping where the single member's would."""
    system = _System(b, act)
    R = b.rows
    X, theta = x.copy(), theta0.copy()
    going, failed = np.ones(R.K, dtype=bool), np.zeros(R.K, dtype=bool)
    for _ in range(STEPS):
        F = system.at(X, theta)
        d = np.zeros(len(F))
        for k in np.flatnonzero(going):
            _, _, d_k, info = _gesv(system.K[k], -F[system.F_slice(k)])  # LAPACK's LU solve
            if info != 0 or not np.isfinite(d_k).all():
                failed[k], going[k] = True, False
                continue
            d[system.F_slice(k)] = d_k
        X = np.where(going[R.of_row], X + d[system.F_row], X)
        theta[system.S] = np.where(going[system.S_member], theta[system.S] + d[system.F_D], theta[system.S])
        step = segment_max(np.abs(d), system.F_member, R.K)
        going &= ~(step <= _SQRT_NEWTON_TOL * segment_max(np.abs(X), R.of_row, R.K))
        if not going.any():
            break
    return X, theta, failed


class _System:
    """``coulomb_newton._NewtonSystem`` of every member for one active set: the members' matrices K
    side by side in one flat buffer (each (size, size), C order), their right-hand sides F likewise."""

    def __init__(self, b: Problems, act: ActiveSet):
        R = b.rows
        self.b = b
        self.S = S = np.flatnonzero(act.sliding)  # the sliding contacts
        self.S_member = R.of_contact[S]
        sliding = np.bincount(self.S_member, minlength=R.K)  # per member
        size = R.n + sliding
        K0, F0 = np.cumsum(size**2) - size**2, np.cumsum(size) - size
        self.F_member = np.repeat(np.arange(R.K), size)
        self.F_bounds = np.stack([F0, F0 + size], axis=1)
        local = np.arange(len(R.of_row)) - R.row0[R.of_row]  # each row's index within its member
        self.F_row = F0[R.of_row] + local  # each row's entry of F
        rank = np.arange(len(S)) - (np.cumsum(sliding) - sliding)[self.S_member]
        D = R.n[self.S_member] + rank  # each sliding contact's angle row, within its member
        self.F_D = F0[self.S_member] + D

        def at(member, rows, cols):  # positions in the flat buffer of (row, col) within a member
            return K0[member] + rows * size[member] + cols

        def whole_rows(member, rows, width):  # ... of the first ``width`` entries of those rows
            col = np.arange(width.sum()) - np.repeat(np.cumsum(width) - width, width)
            return np.repeat(K0[member] + rows * size[member], width) + col

        N, T1, T2 = (local[r] for r in (R.N, R.T1, R.T2))
        # the contacts that are not released (a released contact's rows are pinned)
        E = np.flatnonzero(~act.released)
        e = R.of_contact[E]
        self.E, self.diag_T1, self.diag_T2 = E, at(e, T1[E], T1[E]), at(e, T2[E], T2[E])
        self.dT1_dN, self.dT2_dN = at(e, T1[E], N[E]), at(e, T2[E], N[E])
        # the sliding contacts' angle rows, from their tangent rows, and their circle's entries
        s, n_s = self.S_member, R.n[self.S_member]
        self.row_D, self.row_T1, self.row_T2 = (whole_rows(s, rows, n_s) for rows in (D, T1[S], T2[S]))
        self.per_entry = np.repeat(np.arange(len(S)), n_s)
        self.rows_T = np.concatenate([whole_rows(s, T1[S], size[s]), whole_rows(s, T2[S], size[s])])
        self.circle = np.concatenate([at(s, T1[S], T1[S]), at(s, T2[S], T2[S]), at(s, T1[S], N[S]),
                                      at(s, T2[S], N[S]), at(s, T1[S], D), at(s, T2[S], D), at(s, D, D)])
        self.ones = np.ones(2 * len(S))
        # the pinned rows (released contacts, saturated servo rows), zero but for a one on the diagonal
        pinned = np.zeros(len(R.of_row), dtype=bool)
        for rows in (R.N, R.T1, R.T2):
            pinned[rows] = act.released
        pinned[R.servo] = act.at_lo | act.at_hi
        P = np.flatnonzero(pinned)
        target = np.zeros(len(R.of_row))
        target[R.servo] = np.where(act.at_lo, b.lo, b.hi)
        self.pinned, self.target, self.F_pinned = P, target[P], self.F_row[P]
        # the part of K that every iterate starts from: H, and the pinned rows
        self.flat = np.zeros(K0[-1] + size[-1] ** 2)
        for k, p in enumerate(b.problems):
            self.flat[K0[k]:K0[k] + size[k] ** 2].reshape(size[k], size[k])[:R.n[k], :R.n[k]] = p.H
        p_member = R.of_row[P]
        self.flat[whole_rows(p_member, local[P], size[p_member])] = 0.0
        self.flat[at(p_member, local[P], local[P])] = 1.0
        # ``at`` writes K in place: the entries it changes are restored from their values here first
        self.changed = np.concatenate([self.diag_T1, self.diag_T2, self.dT1_dN, self.dT2_dN, self.row_D,
                                       self.rows_T, self.circle])
        self.saved = self.flat[self.changed]
        self.K = [self.flat[K0[k]:K0[k] + size[k] ** 2].reshape(size[k], size[k]) for k in range(R.K)]
        self.H_part = [K[:n, :n] for K, n in zip(self.K, R.n)]

    def F_slice(self, k: int) -> slice:
        return slice(*self.F_bounds[k])

    def at(self, X: np.ndarray, theta: np.ndarray) -> np.ndarray:
        """F at (X, theta), with every member's K written into ``self.K`` (``_NewtonSystem.at``)."""
        b, R, S, flat = self.b, self.b.rows, self.S, self.flat
        flat[self.changed] = self.saved
        p_N = np.maximum(X[R.N], 0.0)
        R_T = b.stick_slip(b.mu * p_N)
        E = self.E
        flat[self.diag_T1] += R_T[E]
        flat[self.diag_T2] += R_T[E]
        r = b.products(self.H_part, X) + b.c
        F = np.zeros(len(self.F_member))
        F[self.F_row] = r
        # the stick-slip compliance's derivative by p_N where it is not capped
        uncapped = (R_T < b.R_max) & (p_N > 0)
        dR = np.where(uncapped, R_T / np.where(uncapped, p_N, 1.0), 0.0)
        flat[self.dT1_dN] -= dR[E] * X[R.T1[E]]
        flat[self.dT2_dN] -= dR[E] * X[R.T2[E]]
        # the sliding contacts: their angle rows, then their tangent rows replaced by the circle's conditions
        mu, c, sn = b.mu[S], np.cos(theta[S]), np.sin(theta[S])
        flat[self.row_D] = c[self.per_entry] * flat[self.row_T2] - sn[self.per_entry] * flat[self.row_T1]
        r_T1, r_T2, mu_p_N = r[R.T1[S]], r[R.T2[S]], mu * X[R.N[S]]
        F[self.F_D] = c * r_T2 - sn * r_T1
        flat[self.rows_T] = 0.0
        flat[self.circle] = np.concatenate([self.ones, -mu * c, -mu * sn, mu_p_N * sn, -mu_p_N * c,
                                            -(c * r_T1 + sn * r_T2)])
        F[self.F_row[R.T1[S]]], F[self.F_row[R.T2[S]]] = X[R.T1[S]] - mu_p_N * c, X[R.T2[S]] - mu_p_N * sn
        F[self.F_pinned] = X[self.pinned] - self.target
        return F
