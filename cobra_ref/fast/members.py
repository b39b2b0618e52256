"""Where K members of a batched step lie when their rows and contacts are concatenated.

For performance: the batched parts of a step (:mod:`cobra_ref.fast.newton_batch`,
:mod:`cobra_ref.fast.problem_batch`) concatenate the members' least-action rows (each member's
3 m contact rows, then its servo rows) and contacts, so that an elementwise operation of the single
member's code is one NumPy call for all of them; ``MemberRows`` says where each member's part lies,
and ``segment_max`` takes a maximum per member.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


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

    def slices(self, k: int) -> tuple:
        """Member k's slices of an ``ActiveSet``'s four masks."""
        servo = slice(self.servo0[k], self.servo0[k] + self.n[k] - 3 * self.m[k])
        return self.contact_slice(k), self.contact_slice(k), servo, servo


def member_rows(m: np.ndarray, n: np.ndarray) -> MemberRows:
    """The ``MemberRows`` of members with m contacts and n rows each."""
    K, s = len(m), n - 3 * m
    row0, contact0, servo0 = np.cumsum(n) - n, np.cumsum(m) - m, np.cumsum(s) - s
    N = np.repeat(row0, m) + 3 * (np.arange(m.sum()) - np.repeat(contact0, m))
    servo = np.repeat(row0 + 3 * m, s) + np.arange(s.sum()) - np.repeat(servo0, s)
    member = np.arange(K)
    return MemberRows(K, m, n, row0, contact0, servo0, np.repeat(member, n), np.repeat(member, m), np.repeat(member, s),
                 N, N + 1, N + 2, servo)


def segment_max(values: np.ndarray, member: np.ndarray, K: int) -> np.ndarray:
    """(K,) the maximum of ``values`` over each member's entries, 0 where it has none (ndarray.max
    with initial 0)."""
    out = np.zeros(K)
    np.maximum.at(out, member, values)
    return out
