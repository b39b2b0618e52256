"""Where K members of a batched step lie when their rows and contacts are concatenated.

For performance: the batched parts of a step (:mod:`cobra_ref.fast.problem_batch`,
:mod:`cobra_ref.fast.newton_batch`, :mod:`cobra_ref.fast.iterate_batch`) concatenate the members' least-action rows (each member's
3 m contact rows, then its servo rows) and contacts, so that an elementwise operation of the single
member's code is one NumPy call for all of them; ``MemberRows`` says where each member's part lies,
``segment_max`` takes a maximum per member, and ``Problems`` holds K least-action problems so
concatenated.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..compliance import STICK_SLIP_MAX, stick_slip_compliance


class MemberRows(NamedTuple):
    """Where each member's rows and contacts lie in the concatenation of K members."""

    K: int
    m: np.ndarray  # (K,) contacts per member
    n: np.ndarray  # (K,) rows per member
    row0: np.ndarray  # (K,) each member's first row
    contact0: np.ndarray  # (K,) each member's first contact
    servo0: np.ndarray  # (K,) each member's first servo row, among the servo rows
    of_row: np.ndarray  # (sum n,) the member of each row
    of_contact: np.ndarray  # (sum m,) the member of each contact
    of_servo: np.ndarray  # the member of each servo row
    N: np.ndarray  # (sum m,) each contact's normal row
    T1: np.ndarray  # ... its first tangent row
    T2: np.ndarray  # ... its second tangent row
    servo: np.ndarray  # the servo rows

    def row_slice(self, k: int) -> slice:
        return slice(self.row0[k], self.row0[k] + self.n[k])

    def contact_slice(self, k: int) -> slice:
        return slice(self.contact0[k], self.contact0[k] + self.m[k])

    def servo_slice(self, k: int) -> slice:
        """Member k's servo rows, among the servo rows."""
        return slice(self.servo0[k], self.servo0[k] + self.n[k] - 3 * self.m[k])

    def slices(self, k: int) -> tuple:
        """Member k's slices of an ``ActiveSet``'s four masks."""
        contacts, servo = self.contact_slice(k), self.servo_slice(k)
        return contacts, contacts, servo, servo


def member_rows(m: np.ndarray, n: np.ndarray) -> MemberRows:
    """The ``MemberRows`` of members with m contacts and n rows each."""
    K, s = len(m), n - 3 * m
    row0, contact0, servo0 = np.cumsum(n) - n, np.cumsum(m) - m, np.cumsum(s) - s
    N = np.repeat(row0, m) + 3 * (np.arange(m.sum()) - np.repeat(contact0, m))
    servo = np.repeat(row0 + 3 * m, s) + np.arange(s.sum()) - np.repeat(servo0, s)
    member = np.arange(K)
    return MemberRows(K, m, n, row0, contact0, servo0, np.repeat(member, n), np.repeat(member, m),
                      np.repeat(member, s), N, N + 1, N + 2, servo)


def segment_max(values: np.ndarray, member: np.ndarray, K: int) -> np.ndarray:
    """(K,) the maximum of ``values`` over each member's entries, 0 where it has none (ndarray.max
    with initial 0)."""
    out = np.zeros(K)
    np.maximum.at(out, member, values)
    return out


class Problems:
    """The K members' least-action problems, their data concatenated (``MemberRows``)."""

    def __init__(self, problems):
        self.problems = problems
        self.rows = R = member_rows(np.array([p.m for p in problems]), np.array([len(p.c) for p in problems]))
        self.c = np.concatenate([p.c for p in problems])
        self.mu = np.concatenate([p.mu for p in problems])
        self.lo = np.concatenate([p.lo for p in problems])
        self.hi = np.concatenate([p.hi for p in problems])
        H_diagonal = np.concatenate([p.H.diagonal() for p in problems])
        self.G_TT = 0.5 * (H_diagonal[R.T1] + H_diagonal[R.T2])  # coulomb_newton._tangential_diagonal
        self.R_max = STICK_SLIP_MAX * self.G_TT
        self.H_diagonal = H_diagonal
        self.v_s = [p.stiction_velocity for p in problems]
        self.v_s_values = set(self.v_s)
        hi_max = segment_max(np.abs(self.hi), R.of_servo, R.K)[R.of_servo]
        # the servo rows' tolerances at a bound: active_set's (floored) and _corrected's
        self.hi_scale, self.hi_tol = 1e-9 * np.maximum(hi_max, 1e-300), 1e-9 * hi_max

    def stick_slip(self, bound: np.ndarray) -> np.ndarray:
        """``stick_slip_compliance`` of each contact's member (its own v_s) for the bounds ``bound``."""
        if len(self.v_s_values) == 1:
            return stick_slip_compliance(self.v_s[0], bound, self.G_TT)
        out, v_s = np.empty_like(bound), np.asarray(self.v_s)[self.rows.of_contact]
        for value in self.v_s_values:
            own = v_s == value
            out[own] = stick_slip_compliance(value, bound[own], self.G_TT[own])
        return out

    def products(self, matrices, X: np.ndarray) -> np.ndarray:
        """The members' matrix-vector products, matrices[k] @ X_k, concatenated."""
        R = self.rows
        return np.concatenate([A @ X[R.row_slice(k)] for k, A in enumerate(matrices)])
