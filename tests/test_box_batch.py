"""The certified box solves of K members at once: each member's held set, rounds and certificate are its own.

Worked on random box QPs min 1/2 x^T H x + c^T x, lo <= x <= hi (H = A A^T + I, some bounds
infinite, some equal), concatenated as a batch, against :mod:`cobra_ref.fast.active_set`'s single
member code.
"""

import numpy as np
import pytest

from cobra_ref.fast import active_set, box_batch
from cobra_ref.fast.active_set import BoxQP, box_certificate, held_at_bounds, solve_box
from cobra_ref.fast.members import member_rows
from cobra_ref.qp import EPS


def _random_box_qps(rng, sizes):
    """Box QPs of the given sizes: H = A A^T + I, some bounds infinite, some equal (a fixed variable)."""
    qps = []
    for n in sizes:
        A = rng.normal(size=(n, n))
        lo, hi = -rng.uniform(0.1, 1.0, n), rng.uniform(0.1, 1.0, n)
        lo[::4], hi[1::5] = -np.inf, np.inf
        lo[2::7] = hi[2::7] = 0.0
        qps.append(BoxQP(A @ A.T + np.eye(n), rng.normal(size=n), lo, hi))
    return qps


def test_the_batched_certificate_decides_as_each_members_own(rng):
    """On random box QPs with guessed held sets, right (from OSQP-free active-set solves) and wrong
    (random), answers x solved on them and perturbed: each member's batched certificate is
    ``active_set.box_certificate``'s, and both verdicts occur."""
    sizes = [5, 9, 14, 3, 11, 7]
    qps = _random_box_qps(rng, sizes)
    R = member_rows(np.zeros(len(sizes), dtype=int), np.array(sizes))
    verdicts = []
    for trial in range(40):
        xs, held = [], []
        for qp in qps:
            answer = solve_box(qp, np.zeros(len(qp.c)), (EPS, EPS))
            if answer is not None and trial % 4 == 0:
                x, at_lo, at_hi, _ = answer
            elif answer is not None and trial % 4 == 1 and (answer[1] | answer[2]).any():
                # one held variable released and the free ones solved again: stationary, but out of its box
                x, at_lo, at_hi, _ = answer
                at_lo, at_hi = at_lo.copy(), at_hi.copy()
                i = np.flatnonzero(at_lo | at_hi)[0]
                at_lo[i] = at_hi[i] = False
                F, W = ~(at_lo | at_hi), at_lo | at_hi
                x = x.copy()
                x[F] = np.linalg.solve(qp.H[np.ix_(F, F)], -(qp.c[F] + qp.H[np.ix_(F, W)] @ x[W]))
            else:
                n = len(qp.c)
                at_hi = rng.random(n) < 0.2
                at_lo = (rng.random(n) < 0.2) & ~at_hi
                x = rng.normal(size=n)
                x = x if trial % 3 == 0 else np.clip(x, qp.lo, qp.hi)  # out of the box, or in it
            xs.append(x)
            held.append((at_lo & np.isfinite(qp.lo), at_hi & np.isfinite(qp.hi)))
        x = np.concatenate(xs)
        at_lo, at_hi = (np.concatenate(part) for part in zip(*held))
        lo, hi, c = (np.concatenate(part) for part in zip(*((q.lo, q.hi, q.c) for q in qps)))
        fixed = lo == hi
        at_hi, at_lo = at_hi & ~fixed, (at_lo | fixed) & ~(at_hi & ~fixed)
        r = np.concatenate([q.H @ xk + q.c for q, xk in zip(qps, xs)])
        got = box_batch.certificates(R, x, (at_lo, at_hi, fixed, ~(at_lo | at_hi)), r, c, (lo, hi))
        for k, qp in enumerate(qps):
            rows = R.row_slice(k)
            want = box_certificate(qp, x[rows], at_lo[rows], at_hi[rows], (EPS, EPS))
            assert got[k] == want
            verdicts.append(want)
    assert any(verdicts) and not all(verdicts)


def test_the_batched_held_set_is_each_members_own(rng):
    """Variables at, within 1e-13 and 1e-7 (relative) of, and away from their bounds, with and without
    OSQP's duals: each member's held set is ``active_set.held_at_bounds``'s."""
    sizes = [6, 10, 4]
    qps = _random_box_qps(rng, sizes)
    R = member_rows(np.zeros(len(sizes), dtype=int), np.array(sizes))
    lo, hi = (np.concatenate(part) for part in zip(*((q.lo, q.hi) for q in qps)))
    near = rng.choice([0.0, 1e-13, 1e-7, 0.3], size=len(lo))
    top, bottom = np.where(np.isfinite(hi), hi, 0.0), np.where(np.isfinite(lo), lo, 0.0)
    x = np.where(np.isfinite(hi), top - near * np.abs(top), np.where(np.isfinite(lo), bottom + near, 0.5))
    y = rng.normal(size=len(lo))
    has_y = np.repeat([True, False, True], sizes)
    for duals in (None, y):
        got = box_batch.held(R, x, lo, hi, duals, has_y)
        for k in range(len(sizes)):
            rows = R.row_slice(k)
            own = None if duals is None or not has_y[rows][0] else duals[rows]
            for a, b in zip(got, held_at_bounds(x[rows], lo[rows], hi[rows], own)):
                np.testing.assert_array_equal(a[rows], b)


@pytest.mark.parametrize("sizes", [[7], [5, 9, 14, 3, 11, 7, 20, 12]])
def test_each_members_rounds_end_where_its_own_solve_box_ends(rng, monkeypatch, sizes):
    """Held sets guessed right, one variable off, or at random, so that members need 0 to several
    primal-dual rounds: with ``solve_box``'s single flips off (``SINGLE_FLIPS`` = 0, the rounds the
    batch leaves to the member alone), a member is certified by the batch exactly when ``solve_box``
    certifies it, with its x bit for bit; the batch reaches members certified after one round and
    after more, and members left uncertified (the last member, 40 variables with H = A A^T + I / 10
    and a large c, cycles in about one guess in ten)."""
    monkeypatch.setattr(active_set, "SINGLE_FLIPS", 0)
    A = rng.normal(size=(40, 40))
    qps = _random_box_qps(rng, sizes) + [BoxQP(A @ A.T + 0.1 * np.eye(40), 5 * rng.normal(size=40),
                                               -rng.uniform(0.1, 1.0, 40), rng.uniform(0.1, 1.0, 40))]
    sizes = [len(qp.c) for qp in qps]
    R = member_rows(np.zeros(len(sizes), dtype=int), np.array(sizes))
    lo, hi, c = (np.concatenate(part) for part in zip(*((q.lo, q.hi, q.c) for q in qps)))
    seen = {"rounds": set(), "refused": 0}
    for trial in range(60):
        guesses, rounds = [], []
        for qp in qps:
            n = len(qp.c)
            answer = solve_box(qp, np.zeros(n), (EPS, EPS))
            if answer is not None and trial % 3 == 0:
                at_lo, at_hi = answer[1].copy(), answer[2].copy()
                i = rng.integers(n)
                at_lo[i], at_hi[i] = not (at_lo[i] or at_hi[i]), False  # one variable held or released
            else:
                at_hi = rng.random(n) < 0.3
                at_lo = (rng.random(n) < 0.3) & ~at_hi
            guesses.append((at_lo & np.isfinite(qp.lo), at_hi & np.isfinite(qp.hi)))
        guess = tuple(np.concatenate(part) for part in zip(*guesses))
        x, certified = box_batch.solve_boxes(R, [q.H for q in qps], c, (lo, hi), guess)
        for k, (qp, own) in enumerate(zip(qps, guesses)):
            solves = []
            monkeypatch.setattr(active_set, "_posv", lambda *a, **kw: solves.append(1) or _posv(*a, **kw))
            want = solve_box(qp, np.zeros(len(qp.c)), (EPS, EPS), guess=own)
            monkeypatch.setattr(active_set, "_posv", _posv)
            assert certified[k] == (want is not None)
            if want is not None:
                assert x[R.row_slice(k)].tobytes() == want[0].tobytes()
                seen["rounds"].add(min(len(solves), 3))
            else:
                seen["refused"] += 1
    assert seen["rounds"] >= {2, 3} and seen["refused"] > 0


_posv = active_set._posv
