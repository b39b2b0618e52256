"""The friction loops of K members run together: each member's impulses and record are its own, bit for bit."""

import numpy as np
import pytest

from cobra_ref.fast import iterate_batch
from cobra_ref.fast.active_set import BoxQP, box_certificate, held_at_bounds, solve_box
from cobra_ref.fast.least_action import FastBoxQP
from cobra_ref.fast.members import member_rows
from cobra_ref.least_action import kkt_residuals, solve_least_action
from cobra_ref.qp import EPS


def _solved_alone(problem, x):
    qp = FastBoxQP()
    qp.new_step()
    return solve_least_action(problem, x, qp)


def _solved_together(batch):
    qps = [FastBoxQP() for _ in batch]
    for qp in qps:
        qp.new_step()
    return iterate_batch.solve_all([p for p, _ in batch], [x for _, x in batch], qps)


@pytest.mark.parametrize("K", [1, 4, 16])
def test_each_members_impulses_and_record_are_its_own_solve_bit_for_bit(least_action_steps, K):
    """Batches of K problems drawn from real steps (C with its box, sidewinding, the rigid law,
    prescribed joints, saturating servos), each member with a fresh FastBoxQP on both sides:
    every member's x and LeastActionInfo equal ``solve_least_action``'s, and the batches reach
    the path a member takes alone, a loop past its first iterate."""
    order = np.random.default_rng(K).permutation(len(least_action_steps))[:480]
    more_iterates = 0
    for i in range(0, len(order), K):
        batch = [least_action_steps[j] for j in order[i:i + K]]
        for (problem, x), (got_x, got_info) in zip(batch, _solved_together(batch)):
            want_x, want_info = _solved_alone(problem, x)
            np.testing.assert_array_equal(got_x, want_x)
            assert got_x.tobytes() == want_x.tobytes() and got_info == want_info
            more_iterates += want_info.iterations > 1
    assert more_iterates > 0


def test_a_member_whose_guessed_set_is_refused_is_solved_on_as_alone(least_action_steps, monkeypatch):
    """The batched certificate refusing member 1's first held set (forced here): that member goes on
    with its own FastBoxQP.certified, and every member's answer is still its own solve's."""
    batch = least_action_steps[300:304]
    certificates = iterate_batch._certificates
    monkeypatch.setattr(iterate_batch, "_certificates",
                        lambda *args: certificates(*args) & (np.arange(len(batch)) != 1))
    for (problem, x), (got_x, got_info) in zip(batch, _solved_together(batch)):
        want_x, want_info = _solved_alone(problem, x)
        np.testing.assert_array_equal(got_x, want_x)
        assert got_info == want_info


def test_a_member_whose_osqp_fails_fails_alone(least_action_steps, monkeypatch):
    """OSQP raising for one member (its loose solve): that member's answer is the exception, the
    others' are their own solves."""
    batch = least_action_steps[200:203]
    qps = [FastBoxQP() for _ in batch]
    for qp in qps:
        qp.new_step()
    osqp = FastBoxQP._osqp

    def failing(self, *args, **kwargs):
        if self is qps[1]:
            raise RuntimeError("OSQP broke")
        return osqp(self, *args, **kwargs)

    monkeypatch.setattr(FastBoxQP, "_osqp", failing)
    got = iterate_batch.solve_all([p for p, _ in batch], [x for _, x in batch], qps)
    monkeypatch.setattr(FastBoxQP, "_osqp", osqp)
    assert isinstance(got[1], RuntimeError)
    for k in (0, 2):
        want_x, want_info = _solved_alone(*batch[k])
        np.testing.assert_array_equal(got[k][0], want_x)
        assert got[k][1] == want_info


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
        got = iterate_batch._certificates(R, x, (at_lo, at_hi, fixed, ~(at_lo | at_hi)), r, c, (lo, hi))
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
        got = iterate_batch._held(R, x, lo, hi, duals, has_y)
        for k in range(len(sizes)):
            rows = R.row_slice(k)
            own = None if duals is None or not has_y[rows][0] else duals[rows]
            for a, b in zip(got, held_at_bounds(x[rows], lo[rows], hi[rows], own)):
                np.testing.assert_array_equal(a[rows], b)


@pytest.mark.parametrize("K", [1, 16])
def test_each_members_kkt_residuals_are_its_own(least_action_steps, K):
    """The KKT residuals of each member's solved impulses (and of its warm start, a point that is not
    a solution) equal ``least_action.kkt_residuals``, value for value."""
    order = np.random.default_rng(K).permutation(len(least_action_steps))[:160]
    for i in range(0, len(order), K):
        batch = [least_action_steps[j] for j in order[i:i + K]]
        solved = [x for x, _ in _solved_together(batch)]
        for xs in (solved, [x for _, x in batch]):
            for (problem, _), x, got in zip(batch, xs, iterate_batch.kkt_all([p for p, _ in batch], xs)):
                assert got == kkt_residuals(problem, x)
