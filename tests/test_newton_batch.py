"""Newton's first round batched over K least-action problems: each member's guess is its own, bit for bit."""

import numpy as np
import pytest

from cobra_ref.fast import newton_batch
from cobra_ref.fast.members import Problems
from cobra_ref.least_action import LeastAction, guess


@pytest.fixture(scope="module")
def problems(least_action_steps):
    return least_action_steps


def _same(a, b):
    for want, got in zip(a, b):
        np.testing.assert_array_equal(got, want)
        assert got.tobytes() == want.tobytes()  # the signs of zeros too


@pytest.mark.parametrize("K", [1, 3, 16])
def test_each_members_batched_guess_is_its_own_guess_bit_for_bit(problems, K):
    """Batches of K problems drawn from the runs' steps, shuffled so that a batch mixes gaits, laws
    and servos: every member's (pbar_N, theta, x) is ``least_action.guess`` of its own problem."""
    order = np.random.default_rng(K).permutation(len(problems))[:480]
    for i in range(0, len(order), K):
        batch = [problems[j] for j in order[i:i + K]]
        for (problem, x), got in zip(batch, newton_batch.first_guesses(*zip(*batch))):
            _same(guess(problem, x), got)


def test_the_runs_exercise_every_branch_of_the_batched_round(problems):
    """The problems above reach what the batched round treats apart: sliding contacts (the angle
    rows), pinned rows (released contacts, saturated servo rows), members whose active set the
    round corrects (they go on alone) and members of different stiction velocities in one batch."""
    batch = [problems[j] for j in np.random.default_rng(0).permutation(len(problems))[:300]]
    b = Problems([p for p, _ in batch])
    x = np.concatenate([x for _, x in batch])
    act, theta0 = newton_batch._start(b, x)
    X, theta, failed = newton_batch._newton_round(b, act, x, theta0)
    corrected = newton_batch._corrected(b, X, theta, act, newton_batch._residual(b, X))
    assert act.sliding.sum() > 0 and act.released.sum() > 0 and (act.at_lo | act.at_hi).sum() > 0
    assert sum(int((new != old).sum()) for new, old in zip(corrected, act)) > 0
    assert len(set(b.v_s)) == 2 and not failed.any()


def test_a_member_whose_newton_system_is_singular_gets_the_plain_update_and_leaves_the_others_alone(problems):
    """A problem with H = 0 and no contacts (two free servo rows): its Newton matrix is zero, LAPACK
    reports it singular, and its guess is the plain update (x itself), as ``guess`` gives it; its
    neighbours in the batch are unchanged."""
    singular = LeastAction(np.zeros((2, 2)), np.ones(2), np.zeros(0), -np.ones(2), np.ones(2), 0.0)
    batch = [problems[0], (singular, np.zeros(2)), problems[-1]]
    got = newton_batch.first_guesses(*zip(*batch))
    for (problem, x), mine in zip(batch, got):
        _same(guess(problem, x), mine)
    np.testing.assert_array_equal(got[1][2], np.zeros(2))
