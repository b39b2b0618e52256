"""The search of the shooting problem: a parallel compass search (default) or differential evolution.

Implements: the single-shooting optimizer (derivative-free, bounded, deterministic) over the
decision vector of ``planning.problem``; ``optimize`` explains the choice of method.
"""

from __future__ import annotations

import math
import os
import sys
import time
from concurrent.futures import Executor
from dataclasses import dataclass

import numpy as np

from ..infra.executors import default_executor, shutdown
from ..infra.signals import signal_name
from ..gaits import gait_params
from .cost import cost_without_impact, evaluate_batch
from .problem import DEFAULT_MAXITER, DEFAULTS, ShootingError, ShootingProblem, make_problem
from .checkpoint import Checkpoint
from .results import CHECK_DT, transfer


@dataclass
class ShootingResult:
    """The outcome of ``optimize``: the best rollout, every rollout, and how the run ended.

    Written to JSON by ``result_to_dict`` / ``write_result``.
    """

    problem: ShootingProblem
    method: str
    seed: int
    maxiter: int
    options: dict
    history: list
    best: dict
    iterations: int
    interrupted: bool
    message: str
    wall_time: float
    transfer: dict | None = None  # results.transfer of the optimum, when checked (optimize_gait)
    without_impact: dict | None = None  # the rollout of least J - w_I I (optimize's companion search)
    checkpoint: bool = False  # the rollouts so far of a search still running (optimize's ``checkpoint``)

    @property
    def params(self) -> dict:
        """The full gait parameters of the optimum (``gait(problem.gait, **params)`` rebuilds it)."""
        x = [self.best["params"][n] for n in self.problem.names]
        return gait_params(self.problem.reference(x))


class _Evaluations:
    """Runs batches of rollouts on the executor, keeps the history and prints a line per batch.

    A point already rolled out (by either search of ``optimize``) is not run again: the rollouts
    are deterministic, and ``index`` keeps each point's history entry.
    """

    def __init__(self, problem: ShootingProblem, executor: Executor, progress, maxiter: int, width: int = 1):
        self.problem, self.executor, self.progress, self.maxiter = problem, executor, progress, maxiter
        self.history: list = []
        self.index: dict = {}
        self.label, self.search = "", "J"
        self.iteration, self.start = 0, time.perf_counter()
        self.width = max(int(width), 1)  # rollouts that run at once
        self.rollout_seconds = None  # the wall time of one rollout, measured on the first batch
        self.after_first = None  # a callable(rollout_seconds) -> line, said after the first batch
        self.after_batch = None  # a callable() called once each batch is in the history

    def best(self, cost=lambda e: e["cost"]) -> dict | None:
        """The history entry of least ``cost`` (default J; the first of equals)."""
        return min(self.history, key=cost) if self.history else None

    def __call__(self, xs) -> list:
        """J of each x in the batch xs, in order (``entries``)."""
        return [e["cost"] for e in self.entries(xs)]

    def without_impact(self, xs) -> list:
        """J - w_I I of each x in the batch xs, in order: the companion search's cost."""
        return [cost_without_impact(self.problem, e) for e in self.entries(xs)]

    def entries(self, xs) -> list:
        """The history entry of each x in xs, rolling out in parallel the points not run before
        (a Ctrl-C keeps what finished)."""
        xs = [np.asarray(x, dtype=float) for x in xs]
        new = list({_key(x): x for x in xs if _key(x) not in self.index}.values())
        futures, done, t0 = [], [], time.perf_counter()
        # one batch of rollouts per worker (cobra_ref.batch: the same entries as one task per point)
        size = max(1, math.ceil(len(new) / self.width))
        try:
            for i in range(0, len(new), size):
                futures.append(self.executor.submit(evaluate_batch, self.problem, new[i:i + size]))
            for f in futures:
                done.extend(f.result())
        except KeyboardInterrupt:
            for f in futures:
                f.cancel()
            self._record([e for f in futures if f.done() and not f.cancelled() and f.exception() is None
                          for e in f.result()])
            raise
        if new and self.rollout_seconds is None:
            self.rollout_seconds = (time.perf_counter() - t0) / math.ceil(len(new) / self.width)
        self._record(done)
        if done and self.after_first is not None and self.progress:
            self.progress(self.after_first(self.rollout_seconds))
            self.after_first = None
        self.index.update(zip(map(_key, new), done))
        return [self.index[_key(x)] for x in xs]

    def _record(self, entries) -> None:
        if not entries:
            return
        for e in entries:
            self.history.append({"rollout": len(self.history), "search": self.search, "iteration": self.iteration, **e})
        if self.progress:
            self.progress(self._line(entries))
        self.iteration += 1
        if self.after_batch is not None:
            self.after_batch()

    def _line(self, entries) -> str:
        it, b, best = self.iteration, min(entries, key=lambda e: e["cost"]), self.best()
        return (f"{self.label}iteration {it:>2}/{self.maxiter}: {len(entries)} rollouts, cost {b['cost']:.5g}, box to goal "
                f"{_distance_text(b)}; best so far {best['cost']:.5g} ({_distance_text(best)}), "
                f"{len(self.history)} rollouts, {time.perf_counter() - self.start:.0f} s")


def search_budget(search: "SearchOptions", n: int, width: int = 1) -> tuple[int, int]:
    """(at most how many rollouts, in how many waves of ``width`` parallel rollouts) one search
    of ``search`` over ``n`` parameters makes: the compass search rolls out x0, then ``maxiter``
    polls of 2n points; differential evolution ``maxiter`` + 1 generations of max(5, popsize n)
    members. A wave lasts about one rollout, so waves x the time of a rollout estimates the search's."""
    width = max(int(width), 1)
    if search.method == "pattern":
        return 1 + 2 * n * search.maxiter, 1 + search.maxiter * math.ceil(2 * n / width)
    population = max(5, search.popsize * n)
    return population * (search.maxiter + 1), (search.maxiter + 1) * math.ceil(population / width)


def _announce(problem: ShootingProblem, search: "SearchOptions", evals: _Evaluations, searches: int) -> None:
    """Say, through ``evals.progress``, which searches ``optimize`` runs and at most how many
    rollouts each makes, and, once the first rollout is timed, about how long each takes
    (``search_budget``: waves x the first rollout's wall time)."""
    if not evals.progress:
        return
    n_max, waves = search_budget(search, len(problem.names), evals.width)
    method = "compass search" if search.method == "pattern" else "differential evolution"
    then = " (then search 2, the companion without the impact term)" if searches == 2 else ""
    evals.progress(f"search 1 of {searches}: J, {method}{then}: at most {n_max} rollouts of {problem.duration:g} s "
                   f"on {evals.width} worker(s); a time estimate follows the first rollout")

    def estimate(seconds: float) -> str:
        more = f", and up to {waves * seconds:.0f} s for search 2" if searches == 2 else ""
        return f"first rollout: {seconds:.1f} s; estimated {waves * seconds:.0f} s for search 1{more}"

    evals.after_first = estimate


def _announce_companion(problem: ShootingProblem, search: "SearchOptions", evals: _Evaluations) -> None:
    """Say that the companion search starts, with its most rollouts and estimated time."""
    if evals.progress:
        n_max, waves = search_budget(search, len(problem.names), evals.width)
        seconds = evals.rollout_seconds or 0.0
        evals.progress(f"search 2 of 2: J - w_I I, the companion without the impact term (the optimum's 'impacts' "
                       f"comparison; --no-companion skips it): at most {n_max} rollouts, the points of search 1 "
                       f"not run again; estimated up to {waves * seconds:.0f} s")


def _key(x) -> tuple:
    """A rolled-out point, up to rounding (the searches compute the same point the same way)."""
    return tuple(np.round(np.asarray(x, dtype=float), 12))


def _distance_text(entry: dict) -> str:
    d = entry["box_distance_to_goal"]
    return "simulation failed" if d is None else f"{d:.4f} m"


@dataclass(frozen=True)
class SearchOptions:
    """How ``optimize`` searches (its docstring says what each method does): ``method``
    ("pattern" or "de"), ``maxiter`` (polls or generations), ``seed`` (DE's; recorded only for the
    pattern search), ``step`` and ``min_step`` (the compass search's first and smallest step, as
    fractions of the bounds' range), ``popsize`` (DE's members per parameter), ``companion`` (the
    search without the impact term after the search of J). ShootingError for a bad method or
    maxiter."""

    method: str = "pattern"
    maxiter: int = DEFAULT_MAXITER
    seed: int = 0
    step: float = 0.25
    min_step: float = 1 / 64
    popsize: int = 2
    companion: bool = True

    def __post_init__(self):
        if self.method not in ("pattern", "de"):
            raise ShootingError(f"method must be 'pattern' or 'de', got {self.method!r}")
        if int(self.maxiter) != self.maxiter or self.maxiter < 0:
            raise ShootingError(f"maxiter must be a non-negative integer, got {self.maxiter}")


def optimize(problem: ShootingProblem, search: SearchOptions = SearchOptions(), executor: Executor | None = None,
             progress=None, workers: int | None = None, checkpoint=None) -> ShootingResult:
    """Minimise J(p) over the bounds from ``problem.x0``; every rollout goes through ``executor``.

    Implements: the single-shooting optimizer (derivative-free, bounded, deterministic).

    ``search.method="pattern"`` (default): a parallel compass search (Kolda, Lewis, Torczon 2003,
    "Optimization by direct search", sec. 3) in the box scaled to [0, 1]^n: each iteration polls
    the 2n points x +- step e_i (clipped to the bounds) in one parallel batch, moves to the best if
    it lowers J, else halves ``step``; it stops after ``maxiter`` polls or when step <
    ``min_step``. Why this default: a rollout costs seconds (docs/results.md, "Planner"), so a
    budget of minutes buys a few dozen rollouts; the compass search starts from the known-good
    default gait, needs no gradient (J is non-smooth through the contacts), uses the 2n independent
    polls to fill the cores, never re-runs a point, and makes progress within a few dozen rollouts
    (docs/planning.md, the optima's table).
    It has no randomness (``seed`` is recorded only).
    ``search.method="de"``: ``scipy.optimize.differential_evolution`` (best1bin, Latin hypercube
    start with x0 as its first member, ``popsize`` * n members, ``updating="deferred"``,
    ``polish=False``, ``rng=seed``), whose ``workers`` map is our executor: a global search for
    users with an executor bigger than one machine (for example Dask's ``Client.get_executor()``).

    The companion search (``search.companion``, when w_I > 0): after the search of J, the same
    search from the same x0 minimizes J - w_I I, the cost without the impact term, on the same
    record of rollouts (a point either search polled runs once). The optimum is the rollout of
    least J among all of both searches, and ``without_impact`` the rollout of least J - w_I I among
    the same. Over one common set of rollouts this makes the optimum's impact term no larger than
    the unpenalized optimum's: J(p*) <= J(p0) and J(p0) - w_I I(p0) <= J(p*) - w_I I(p*) give
    w_I I(p*) <= w_I I(p0), equal only when both are the same rollout (or tie). Without the
    companion, a local search's two optima come from two different paths, and either can have
    fewer impacts (docs/planning.md, "With and without the impact term").

    ``executor``: any ``concurrent.futures.Executor`` whose workers can import cobra_ref; default
    ``default_executor(workers)``, a process pool on the local cores, shut down at the end.
    ``progress``: a callable taking one line of text per iteration (the CLI prints it on stderr).
    ``checkpoint``: a callable taking a ``ShootingResult`` of every rollout so far (``checkpoint``
    true), called after each batch: the CLI writes it to the params JSON as the search goes.
    Ctrl-C (KeyboardInterrupt) stops the search and returns the best rollout found so far with
    ``interrupted=True`` (before any rollout finished, the KeyboardInterrupt goes on). The result
    is the same for any executor (the rollouts are deterministic and each batch is collected in
    order).
    """
    own = executor is None
    executor = default_executor(workers) if own else executor
    evals = _Evaluations(problem, executor, progress, search.maxiter, _width(executor, workers if own else None))
    stop, message = None, ""  # stop: the interrupt that ended the search early
    run = _compass_search if search.method == "pattern" else _differential_evolution
    companion = search.companion and problem.weights.impact > 0
    iterations = 0
    if checkpoint is not None:
        evals.after_batch = lambda: checkpoint(_result(problem, search, evals, iterations, False, (
            f"checkpoint after {len(evals.history)} rollouts: the search was still running"), checkpoint=True))
    try:
        _announce(problem, search, evals, 2 if companion else 1)
        message = run(problem, evals, search)
        iterations = evals.iteration
        if companion:
            _announce_companion(problem, search, evals)
            evals.label, evals.search, evals.iteration = "without the impact term: ", "J - w_I I", 0
            message += "; without the impact term: " + run(problem, evals.without_impact, search)
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM under the command line (signals.Terminated)
        stop, message = exc, f"interrupted ({signal_name(exc)}): the best rollout so far is kept"
    finally:
        if own:
            shutdown(executor, stop is not None)
    if not evals.history:  # interrupted before any rollout finished: nothing to keep
        raise stop if stop is not None else ShootingError("no rollout finished")
    return _result(problem, search, evals, iterations, stop is not None, message)


def _result(problem: ShootingProblem, search: SearchOptions, evals: _Evaluations, iterations: int,
            interrupted: bool, message: str, checkpoint: bool = False) -> ShootingResult:
    """The ``ShootingResult`` of the rollouts in ``evals`` (``checkpoint``: of a search still
    running). ``iterations``: those of the search of J once it has ended (while it runs, its own
    count)."""
    iterations = evals.iteration if evals.search == "J" else iterations
    unpenalized = evals.best(lambda e: cost_without_impact(problem, e)) if evals.search != "J" else None
    options = {"step": search.step, "min_step": search.min_step, "popsize": search.popsize,
               "companion": evals.search != "J"}
    return ShootingResult(problem, search.method, search.seed, int(search.maxiter), options, list(evals.history),
                          evals.best(), max(iterations - 1, 0), interrupted, message,
                          time.perf_counter() - evals.start, without_impact=unpenalized,
                          checkpoint=checkpoint)


def _width(executor: Executor, workers: int | None) -> int:
    """How many rollouts ``executor`` runs at once: ``workers``, else its ``_max_workers`` (a process
    pool's; 1 when it does not say, as for ``SerialExecutor``)."""
    return int(workers or getattr(executor, "_max_workers", None) or 1)


def compass_search(evaluate_batch, x0, lower, upper, maxiter: int, step: float = 0.25,
                   min_step: float = 1 / 64) -> tuple[np.ndarray, float, str]:
    """Bounded parallel compass search: returns (x_best, f_best, why it stopped).

    Implements: compass (coordinate pattern) search, Kolda, Lewis and Torczon 2003,
    "Optimization by direct search", SIAM Review 45(3), sec. 3, with the whole poll evaluated
    at once. In the box scaled to [0, 1]^n, u = (x - lower) / (upper - lower)::

        poll:   P = { clip(u +- step e_i, 0, 1) } minus u           (2n points, one batch;
                                                               points seen before are not re-run)
        accept: u <- argmin_P f   if  min_P f < f(u)     (ties: the first in P)
        else:   step <- step / 2
        stop:   after maxiter polls, or when step < min_step

    ``evaluate_batch(list of x) -> list of f`` evaluates a batch (in parallel, in order).
    No randomness: the same inputs give the same iterates.
    """
    lo, hi = np.asarray(lower, dtype=float), np.asarray(upper, dtype=float)
    to_x = lambda u: lo + u * (hi - lo)  # noqa: E731
    key = lambda u: tuple(np.round(u, 12))  # noqa: E731  (a point on the mesh, up to rounding)
    u = (np.asarray(x0, dtype=float) - lo) / (hi - lo)
    (f_u,) = evaluate_batch([np.asarray(x0, dtype=float)])  # x0 itself, not to_x(u) (rounding)
    seen = {key(u): f_u}  # the rollouts are deterministic: never evaluate a point twice
    for _ in range(maxiter):
        if step < min_step:
            return to_x(u), f_u, f"converged: step {step:.4g} < min_step {min_step:.4g} (of the bounds' range)"
        polls = [np.clip(u + sign * step * e, 0.0, 1.0) for e in np.eye(len(u)) for sign in (1.0, -1.0)]
        polls = [p for p in polls if key(p) != key(u)]
        new = list({key(p): p for p in polls if key(p) not in seen}.values())
        if new:
            seen.update(zip(map(key, new), evaluate_batch([to_x(p) for p in new])))
        costs = [seen[key(p)] for p in polls]
        k = int(np.argmin(costs))
        if costs[k] < f_u:
            u, f_u = polls[k], costs[k]
        else:
            step /= 2
    return to_x(u), f_u, f"stopped after maxiter = {maxiter} polls (step {step:.4g})"


def _compass_search(problem: ShootingProblem, evaluate_batch, search: SearchOptions) -> str:
    """``compass_search`` on the shooting problem (see ``optimize``); returns why it stopped."""
    return compass_search(evaluate_batch, problem.x0, problem.lower, problem.upper, search.maxiter, search.step,
                          search.min_step)[2]


def differential_evolution_search(evaluate_batch, x0, lower, upper, maxiter: int, seed: int = 0,
                                  popsize: int = 2) -> tuple[np.ndarray, float, str]:
    """scipy's differential evolution with ``evaluate_batch`` as its parallel map: (x_best, f_best, message).

    Implements: ``scipy.optimize.differential_evolution`` (Storn and Price 1997), strategy best1bin,
    a Latin hypercube start of max(5, popsize * n) members whose first is x0, ``maxiter``
    generations, ``updating="deferred"`` (one batch per generation), ``polish=False``, ``rng=seed``
    (deterministic), ``tol = atol = 0`` (runs every generation).
    """
    from scipy.optimize import differential_evolution

    res = differential_evolution(_not_called, list(zip(lower, upper)), maxiter=maxiter, popsize=popsize, tol=0.0,
                                 atol=0.0, rng=seed, polish=False, init="latinhypercube", updating="deferred",
                                 workers=lambda func, xs: evaluate_batch(list(xs)), x0=np.asarray(x0, dtype=float))
    return res.x, float(res.fun), f"differential evolution: {res.message}"


def _differential_evolution(problem: ShootingProblem, evaluate_batch, search: SearchOptions) -> str:
    """``differential_evolution_search`` on the shooting problem (see ``optimize``)."""
    return differential_evolution_search(evaluate_batch, problem.x0, problem.lower, problem.upper, search.maxiter,
                                         search.seed, search.popsize)[2]


def _not_called(x):
    """The objective handed to scipy; the rollouts run through the workers map instead."""
    raise RuntimeError("the shooting objective is evaluated through the executor map")


def optimize_gait(name: str, goal=None, out: str | None = None, executor: Executor | None = None, progress=None,
                  check_dt: float | None = CHECK_DT, search: SearchOptions | None = None,
                  **problem_options) -> ShootingResult:
    """Optimize one gait at its defaults (``DEFAULTS[name]``: goal, horizon and maxiter, unless
    given), check the optimum at ``check_dt`` (``results.transfer``; None = no check) and write the
    params JSON to ``out`` (default ``optimized/<name>.json``; "" = do not write), after every
    batch of rollouts too (``checkpoint.Checkpoint``): what ``cobra-ref figures --reoptimize`` runs
    per gait. An ``OutputError`` names the file and where the result is kept when ``out`` cannot
    be written at the end.

    ``progress`` defaults to lines on stderr; ``search``: ``SearchOptions`` (default: the gait's
    maxiter); ``problem_options`` go to ``make_problem`` (duration, settings, space, weights, cobra,
    box_gap).
    """
    d_goal, d_duration, d_maxiter = DEFAULTS[name]
    problem_options["duration"] = problem_options.get("duration") or d_duration
    problem = make_problem(name, d_goal if goal is None else goal, **problem_options)
    if progress is None:
        progress = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
    out = os.path.join("optimized", f"{name}.json") if out is None else out
    if out:
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
    keeper = Checkpoint(out, progress) if out else None
    result = optimize(problem, SearchOptions(maxiter=d_maxiter) if search is None else search, executor, progress,
                      checkpoint=keeper)
    if check_dt is not None and result.best["terms"] is not None:
        x = [result.best["params"][n] for n in problem.names]
        result.transfer = transfer(problem, x, result.best, check_dt)
        t = result.transfer
        progress(f"check at dt = {check_dt:g} s: box to goal {t['plan_distance_to_goal']:.4f} m (plan) -> "
                 + ("failed: " + t["check_error"] if t["check_error"] else
                    f"{t['check_distance_to_goal']:.4f} m (check); impact impulse "
                    f"{t['plan_impact_impulse_per_s']:.4g} -> {t['check_impact_impulse_per_s']:.4g} N s/s"))
    if keeper is not None:
        keeper.final(result)
    return result
