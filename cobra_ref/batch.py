"""Rollouts in lockstep: K runs of one model advanced by one call per step, the batched rollout engine.

``BatchRun`` is :class:`cobra_ref.simulate.Run` for K members (each its own start, joint reference,
warm start and log) stepped together by :class:`cobra_ref.fast.batch.BatchStepper`;
``simulate_batch`` is :func:`cobra_ref.simulate.simulate` for a batch. Each member's trajectory is
its single run's, bit for bit (``tests/test_batch.py``). A member whose step fails leaves the batch
with what it computed, its trajectory's ``error`` saying why; the others go on.
"""

from __future__ import annotations

import math
import time

import numpy as np

from .fast.batch import BatchStepper
from .infra import arguments
from .infra.executors import one_blas_thread
from .simulate import RunLog, check_start, meta, step_failure
from .start import BoxPlacement, Hold, Relaxation, check_run_arguments, placed_state
from .step import StepSettings


class BatchRun:
    """K runs in lockstep (``simulate.Run`` for a batch): ``model`` (every member's) or a list of
    models (one per member, differing in anything but their bodies: ``fast.batch.same_bodies``),
    starts ``starts`` [(q0, qd0)], logs of at most ``capacity`` steps each; ``t0`` and ``memory``
    (a stepper's ``memory``, every member's) start them in the middle of another run, as
    ``simulate.Run``'s do."""

    def __init__(self, model, settings: StepSettings, starts, capacity: int, t0: float = 0.0,
                 memory: dict | None = None):
        starts = list(starts)
        models = list(model) if isinstance(model, (list, tuple)) else [model] * len(starts)
        if len(models) != len(starts):
            raise ValueError(f"a batch of {len(starts)} starts needs {len(starts)} models, got {len(models)}")
        self.models, self.settings, self.t0 = models, settings, float(t0)
        self.stepping = BatchStepper(models, settings)
        for member in self.stepping.members:
            member.memory = memory
        self.Q = np.array([m.check_q(q0) for m, (q0, _) in zip(models, starts)], dtype=float)
        self.QD = np.array([m.check_qd(np.zeros(m.nv) if qd0 is None else qd0) for m, (_, qd0) in zip(models, starts)],
                           dtype=float)
        for m, q in zip(models, self.Q):
            check_start(m, q)
        self.logs = [RunLog(m, capacity, settings.dt) for m in models]
        for log, q, qd in zip(self.logs, self.Q, self.QD):
            log.add_state(self.t0, q, qd)
        self.errors = [""] * len(starts)  # why each member left the batch ("": it did not)
        self.messages = [""] * len(starts)  # ... as simulate's SimulationError says it
        self.k, self.wall_time = 0, 0.0

    @property
    def size(self) -> int:
        return len(self.logs)

    def advance(self, references, n_steps: int, progress=None) -> None:
        """``n_steps`` more steps, member k following ``references[k]``; a member whose step fails
        (or leaves a non-finite state) keeps its log up to that step and its error. ``progress(done,
        total)`` is called every 250 steps and at the end, as ``simulate.Run.advance`` calls it."""
        if len(references) != self.size:
            raise ValueError(f"a batch of {self.size} needs {self.size} references, got {len(references)}")
        if self.k + n_steps > len(self.logs[0].tau):
            raise ValueError(f"the runs hold {len(self.logs[0].tau)} steps; {self.k} taken, {n_steps} more asked")
        dt = self.settings.dt
        start = time.perf_counter()
        try:
            with one_blas_thread():
                for i in range(n_steps):
                    active = [k for k, e in enumerate(self.errors) if not e]
                    if not active:
                        break
                    t = self.t0 + self.k * dt
                    for k, res in zip(active, self.stepping.step(self.Q, self.QD, t, references, active)):
                        self._record(k, res, t)
                    self.k += 1
                    if progress is not None and ((i + 1) % 250 == 0 or i + 1 == n_steps):
                        progress(i + 1, n_steps)
        except KeyboardInterrupt as exc:  # Ctrl-C: every member keeps what it computed
            self.wall_time += time.perf_counter() - start
            start = None
            where = f"step {self.k} (t = {self.t0 + self.k * dt:.4f} s): interrupted"
            self.errors = [e or where for e in self.errors]
            exc.trajectories = self.finish()
            raise
        finally:
            if start is not None:
                self.wall_time += time.perf_counter() - start

    def _record(self, k: int, res, t: float) -> None:
        """Member k's result of the step at t: logged, or its error (named as ``simulate.Run`` names it)."""
        if isinstance(res, BaseException):
            self.errors[k], self.messages[k] = step_failure(self.k, t, res)
        elif not math.isfinite(res.q.sum() + res.qd.sum()):
            self.errors[k], self.messages[k] = step_failure(self.k, t)
        else:
            self.Q[k], self.QD[k] = res.q, res.qd
            self.logs[k].add_step(self.k, res)
            self.logs[k].add_state(t + self.settings.dt, res.q, res.qd)

    def finish(self) -> list:
        """Every member's Trajectory so far (its ``error`` set if it left the batch); each records
        its share of the batch's wall time."""
        share = self.wall_time / self.size
        return [log.finish(share, error, meta(model, self.settings, member))
                for log, error, model, member in zip(self.logs, self.errors, self.models, self.stepping.steppers)]


def simulate_batch(model, references, duration: float, settings: StepSettings, starts, progress=None) -> list:
    """``simulate.simulate`` for a batch: member k of ``model`` (or of ``model[k]``, as ``BatchRun``
    takes it) from ``starts[k]`` = (q0, qd0) following ``references[k]`` for ``duration`` seconds,
    ``progress`` as ``BatchRun.advance`` calls it; a Trajectory per member, a failed member's with its
    ``error`` set (the others run to the end)."""
    n_steps = arguments.duration_steps(duration, settings.dt)
    run = BatchRun(model, settings, starts, n_steps)
    run.advance(references, n_steps, progress)
    return run.finish()


def initial_states(models, references, placements, settings: StepSettings = StepSettings()) -> list:
    """``start.initial_state`` for a batch: member k's (q0, qd0), ``models[k]`` placed by
    ``placements[k]`` (a ``BoxPlacement``) and settled holding ``references[k]``' t = 0 shape, the
    members' settling steps taken together; each member's start is its ``initial_state``, bit for bit.

    Implements: the start at rest (assumption A25), each member relaxed on its own
    (``start.Relaxation``) and leaving the batch once it has settled; a member whose step fails
    raises, as ``initial_state`` does.
    """
    models, references, placements = list(models), list(references), list(placements)
    if not len(models) == len(references) == len(placements):
        raise ValueError(f"a batch's starts need as many models, references and placements, got {len(models)}, "
                         f"{len(references)} and {len(placements)}")
    for model, reference, placement in zip(models, references, placements):
        check_run_arguments(model, reference, settings, "fast")
        arguments.instance("placement", placement, BoxPlacement, "BoxPlacement(gap=0.05)")
    if not models:
        return []
    Q = np.array([placed_state(m, ref, p) for m, ref, p in zip(models, references, placements)], dtype=float)
    QD = np.zeros((len(models), models[0].nv))
    holds = [Hold(reference(0.0)[0]) for reference in references]
    relaxations = [Relaxation(settings.dt) for _ in models]
    stepping, active = BatchStepper(models, settings), list(range(len(models)))
    with one_blas_thread():  # as initial_state settles
        while active:
            t = relaxations[active[0]].k * settings.dt  # the active members have taken the same steps
            settled = []
            for k, result in zip(active, stepping.step(Q, QD, t, holds, active)):
                if isinstance(result, BaseException):
                    raise result
                Q[k] = result.q
                QD[k], restart, done = relaxations[k].after(result)
                if restart:  # a step afresh, as start._settle takes it
                    stepping.members[k].memory = None
                if done:
                    settled.append(k)
            active = [k for k in active if k not in settled]
    return [(q.copy(), qd.copy()) for q, qd in zip(Q, QD)]
