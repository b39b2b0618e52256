"""The friction loops of K members run together: each member's impulses and record are its own, bit for bit."""

import numpy as np
import pytest

from cobra_ref.fast import iterate_batch
from cobra_ref.fast.least_action import FastBoxQP
from cobra_ref.least_action import kkt_residuals, solve_least_action


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


def test_a_member_whose_box_qp_is_left_uncertified_is_solved_on_as_alone(least_action_steps, monkeypatch):
    """The batched rounds leaving member 1's box QP uncertified (forced here): that member goes on
    with its own FastBoxQP.certified, and every member's answer is still its own solve's."""
    batch = least_action_steps[300:304]
    solve_boxes = iterate_batch.solve_boxes

    def refusing(*args):
        x, certified = solve_boxes(*args)
        return x, certified & (np.arange(len(batch)) != 1)

    monkeypatch.setattr(iterate_batch, "solve_boxes", refusing)
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
