"""`optimize` says what it will run: each search (the search of J, then the companion without the
impact term), at most how many rollouts, and an estimated time from the first rollout's wall time.
Worked examples on made-up rollouts (no simulation): their costs and timings are chosen here."""

import time

import pytest

from cobra_ref import planning as sh
from cobra_ref.planning import search
from cobra_ref.planning.problem import Weights
from cobra_ref.planning.search import SearchOptions, search_budget


def one_by_one(evaluate):
    """A made-up ``evaluate(problem, x)`` as the search's ``evaluate_batch(problem, xs)``."""
    return lambda problem, xs: [evaluate(problem, x) for x in xs]


def test_the_budget_of_a_search_counts_its_rollouts_and_its_waves():
    # compass search over n = 3: x0, then 2 polls of 2n = 6 points: 13 rollouts; on 2 workers a poll
    # is 3 waves, so 1 + 2 x 3 = 7 waves; on 1 worker 13
    assert search_budget(SearchOptions(maxiter=2), 3, width=2) == (13, 7)
    assert search_budget(SearchOptions(maxiter=2), 3, width=1) == (13, 13)
    # differential evolution over n = 3, popsize 2: max(5, 6) = 6 members, maxiter + 1 = 3 generations
    assert search_budget(SearchOptions(method="de", maxiter=2), 3, width=4) == (18, 6)
    assert search_budget(SearchOptions(method="de", maxiter=0, popsize=1), 2, width=1) == (5, 5)


@pytest.fixture
def problem():
    space = sh.DecisionSpace(names=("frequency",), bounds={"frequency": (0.5, 1.5)}, ramp_time=0.1)
    return sh.make_problem("C", (0.05, -0.01), 0.3, None, space, box_gap=0.005, weights=Weights(impact=10.0))


def slow_made_up(problem, x):
    """A rollout of 0.05 s wall time whose cost falls with the frequency."""
    time.sleep(0.05)
    return {"params": {"frequency": float(x[0])}, "error": None, "cost": 2.0 - float(x[0]),
            "box_distance_to_goal": 0.0, "terms": {"impact": 0.0}, "contact": {"impact_impulse": 0.0}}


def test_optimize_announces_both_searches_with_rollouts_and_an_estimated_time(problem, monkeypatch):
    monkeypatch.setattr(search, "evaluate_batch", one_by_one(slow_made_up))
    lines = []
    sh.optimize(problem, SearchOptions(maxiter=2), executor=sh.SerialExecutor(), progress=lines.append)
    text = "\n".join(lines)
    assert lines[0].startswith("search 1 of 2: J, compass search (then search 2, the companion without the impact")
    assert "at most 5 rollouts of 0.3 s on 1 worker(s)" in lines[0]
    # the estimate follows the first rollout's line: 1 + 2 x 2 = 5 waves of about 0.05 s
    first = next(i for i, line in enumerate(lines) if line.startswith("first rollout: "))
    assert lines[first - 1].startswith("iteration  0/2: 1 rollouts")
    seconds = float(lines[first].split("first rollout: ")[1].split(" s")[0])
    assert 0.04 <= seconds < 1.0
    assert f"estimated {5 * seconds:.0f} s for search 1, and up to" in lines[first]
    assert "search 2 of 2: J - w_I I, the companion without the impact term" in text
    assert text.index("search 2 of 2") > text.index("first rollout")


def test_without_the_companion_one_search_is_announced(problem, monkeypatch):
    monkeypatch.setattr(search, "evaluate_batch", one_by_one(slow_made_up))
    lines = []
    sh.optimize(problem, SearchOptions(maxiter=1, companion=False), executor=sh.SerialExecutor(),
                progress=lines.append)
    assert lines[0].startswith("search 1 of 1: J, compass search: at most 3 rollouts")
    assert not any("search 2" in line for line in lines)
    assert any(line.startswith("first rollout: ") and "search 2" not in line for line in lines)
