"""The batched step: K members of one model advanced by one call per step.

For performance: K members, each with its own state, joint reference and warm start, share one
model and one step size and are advanced together, one ``BatchStepper.step`` per step for all of
them (:mod:`cobra_ref.batch` runs and records them). Batched so far, for all members in one call
each:

* the chain terms (poses, motion subspaces, M and h): :meth:`cobra_ref.fast.chain.ChainModel.terms`
  with a leading K axis;
* the contacts and their Jacobians (:func:`cobra_ref.fast.contacts.find_contacts_batch`,
  ``contact_jacobian_batch``);
* from ``BATCHED_FROM`` members on, the rows of the least-action problems
  (:func:`cobra_ref.fast.problem_batch.least_action_problems`) and the vector work of the friction
  loop's first guess and first iterate (:func:`cobra_ref.fast.iterate_batch.solve_all`, its certified
  box solves' rounds in :mod:`cobra_ref.fast.box_batch`), and the KKT residuals of the impulses
  (``iterate_batch.kkt_all``).

The rest of each member's step (its free velocity and G, its OSQP and LAPACK solves, the result) is
its own :class:`cobra_ref.fast.stepper.FastStepper`'s (``rows``, ``posed``, ``finish``), given
those. Each member takes its single run's steps bit for bit (``tests/test_batch.py``). A member
whose step fails gets its exception back in place of a result; the others go on.
"""

from __future__ import annotations

import time

import numpy as np

from ..model import Model
from ..step import StepSettings, midpoint_velocity
from ..touchdown import TouchdownStepper, sub_settings
from .chain import ChainTerms
from .contacts import contact_jacobian_batch, find_contacts_batch
from .iterate_batch import kkt_all, solve_all
from .problem_batch import least_action_problems
from .stepper import FastStepper

# the fewest members whose least-action problems, friction loops and KKT residuals are batched: for
# one or two, each member's own step is faster than the batched parts' set-up
BATCHED_FROM = 3


def same_bodies(a: Model, b: Model) -> bool:
    """Whether two models have the same bodies, joints, gravity and contact geometry: what the
    batched chain terms and contact search read (the rest of a step reads each member's model)."""
    arrays = lambda m: (m.tree_pos + m.tree_rot + m.com + m.I_com  # noqa: E731
                        + (m.gravity, m.spheres.body, m.spheres.center, m.spheres.radius)
                        + tuple(x for box in m.boxes for x in (np.array(box.body), box.half)))
    return (a.parent == b.parent and a.joint_type == b.joint_type and a.mass == b.mass
            and len(a.boxes) == len(b.boxes) and all(np.array_equal(x, y) for x, y in zip(arrays(a), arrays(b))))


class BatchStepper:
    """Fast steppers (``members``) of ``models`` (one per member) stepped in lockstep (module
    docstring); the models may differ in anything but their bodies (``same_bodies``: friction,
    contact and servo parameters are each member's own)."""

    name = "batch"

    def __init__(self, models, settings: StepSettings):
        models = list(models)
        if not models:
            raise ValueError("a batch has at least one member")
        if not all(m is models[0] or same_bodies(models[0], m) for m in models[1:]):
            raise ValueError("the members of a batch must have the same bodies, joints and contact geometry")
        self.model, self.settings = models[0], settings
        # touch-down substeps (A33): each member's whole steps are its TouchdownStepper's, its substeps those
        # of its member of a second batch, of dt / n
        self.touchdowns, self.sub = None, None
        if settings.substeps > 1:
            self.sub = BatchStepper(models, sub_settings(settings))
            self.touchdowns = [TouchdownStepper(FastStepper, model, settings, sub=sub)
                               for model, sub in zip(models, self.sub.members)]
            self.members = [touchdown.whole for touchdown in self.touchdowns]
        else:
            self.members = [FastStepper(model, settings) for model in models]
        self.chain = self.members[0].chain
        self.batched_seconds = 0.0  # the batched parts' time, summed

    @property
    def steppers(self) -> list:
        """Each member's stepper as its single run has it (its name and timing): its
        ``TouchdownStepper`` with touch-down substeps, else its ``FastStepper``."""
        return self.members if self.touchdowns is None else self.touchdowns

    def step(self, Q: np.ndarray, QD: np.ndarray, t: float, references, active) -> list:
        """One step at time t of the members ``active`` (indices), from their rows of Q (K, nq) and
        QD (K, nv), each following its ``references[k]``: a ``step.StepResult`` per active member,
        or the exception its step raised (that member's step is then not taken). With touch-down
        substeps, the members' whole steps are taken together, and then the substeps of those members
        that take their step in substeps, together, as each one's ``TouchdownStepper`` takes them."""
        if self.touchdowns is None:
            return self._whole(Q, QD, t, references, active)
        held = [k for k in active if self.touchdowns[k].holding(QD[k])]
        whole = [k for k in active if k not in held]
        memories = {k: self.members[k].memory for k in whole}
        out = dict(zip(whole, self._whole(Q, QD, t, references, whole))) if whole else {}
        # in substeps: the held members, and those whose whole step touched down
        sub = [k for k in active if k in held
               or not isinstance(out[k], Exception) and self.touchdowns[k].touched(out[k], memories[k])]
        if sub:
            out.update(self._substepped(Q, QD, t, references, sub))
        return [out[k] for k in active]

    def _substepped(self, Q: np.ndarray, QD: np.ndarray, t: float, references, members) -> dict:
        """Each of ``members``' step at t taken in substeps (``TouchdownStepper.substepped``), the
        members' substeps together by the batch of dt / n: member k's result, or its exception."""
        dt, n = self.settings.dt, self.settings.substeps
        out = {k: _call(self.touchdowns[k].entered, QD[k], self.members[k].memory) for k in members}
        going = [k for k in members if not isinstance(out[k], Exception)]
        Q_sub, QD_sub = Q.copy(), QD.copy()
        for k in going:
            QD_sub[k] = out[k]
        results = {k: [] for k in going}
        for i in range(n):
            if not going:
                break
            for k, r in zip(going, self.sub._whole(Q_sub, QD_sub, t + i * dt / n, references, going)):
                if isinstance(r, Exception):
                    out[k] = r
                else:
                    results[k].append(r)
                    Q_sub[k], QD_sub[k] = r.q, r.qd
            going = [k for k in going if not isinstance(out[k], Exception)]
        for k in going:
            out[k] = _call(self.touchdowns[k].left, results[k])
        return out

    def _whole(self, Q: np.ndarray, QD: np.ndarray, t: float, references, active) -> list:
        """``step`` of whole steps (module docstring)."""
        start = time.perf_counter()
        W = np.stack([midpoint_velocity(QD[k], self.members[k].memory) for k in active])
        terms = self.chain.terms(Q[active], W)
        contacts = find_contacts_batch(self.model, terms.R, terms.o, self.settings.margin)
        J_c = contact_jacobian_batch(self.chain, terms.S, contacts)
        self.batched_seconds += time.perf_counter() - start
        own_terms = [ChainTerms(*(part[j] for part in terms)) for j in range(len(active))]
        if len(active) < BATCHED_FROM:  # each member's own step is faster
            prepared = [self._member(k, "prepare", Q[k], QD[k], t, references[k], None, own_terms[j], contacts[j],
                                     J_c[j]) for j, k in enumerate(active)]
            return [p if isinstance(p, Exception) else self._member(k, "finish", p) for k, p in zip(active, prepared)]
        rows = [self._member(k, "rows", Q[k], QD[k], t, references[k], None, own_terms[j], contacts[j], J_c[j])
                for j, k in enumerate(active)]
        prepared = self._posed(rows, active)
        solved = self._solved(prepared, active)
        residuals = self._residuals(prepared, solved)
        return [p if isinstance(p, Exception) else s if isinstance(s, Exception) else
                self._member(k, "finish", p, s, kkt) for k, p, s, kkt in zip(active, prepared, solved, residuals)]

    def _member(self, k: int, phase: str, *args):
        """Member k's ``FastStepper`` method ``phase`` (``prepare``, ``rows``, ``posed``, ``finish``)
        on ``args``, or the exception it raised (that member fails; the others go on)."""
        return _call(getattr(self.members[k], phase), *args)

    def _posed(self, rows, active) -> list:
        """Each member's step of ``rows`` prepared with its least-action problem, the problems written
        together (``problem_batch.least_action_problems``); a member's exception stays in its place."""
        start = time.perf_counter()
        ready = [j for j, r in enumerate(rows) if not isinstance(r, Exception)]
        if not ready:
            return rows
        problems = least_action_problems([self.members[active[j]].model for j in ready],
                                         [(rows[j].system.G, rows[j].problem_args) for j in ready])
        self.batched_seconds += time.perf_counter() - start
        prepared = list(rows)
        for j, problem in zip(ready, problems):
            prepared[j] = self._member(active[j], "posed", rows[j], problem)
        return prepared

    def _solved(self, prepared, active) -> list:
        """Each prepared member's (x, info) of its least-action problem, the friction loops run together
        (``iterate_batch.solve_all``), or the exception its solve raised; None for a member with no
        rows (its own ``finish`` has nothing to solve)."""
        start = time.perf_counter()
        solving = [j for j, p in enumerate(prepared) if not isinstance(p, Exception) and len(p.system.problem.c)]
        solved = [None] * len(prepared)
        if not solving:
            return solved
        qps = [self.members[active[j]].qp for j in solving]
        answers = solve_all([prepared[j].system.problem for j in solving], [prepared[j].x_start for j in solving], qps)
        for j, answer in zip(solving, answers):
            solved[j] = answer
        self.batched_seconds += time.perf_counter() - start
        return solved

    def _residuals(self, prepared, solved) -> list:
        """``least_action.kkt_residuals`` of each member's converged impulses, batched
        (``iterate_batch.kkt_all``); None for the others (their own ``finish`` computes them)."""
        start = time.perf_counter()
        done = [j for j, s in enumerate(solved) if isinstance(s, tuple) and s[1].converged]
        residuals = [None] * len(solved)
        if done:
            for j, kkt in zip(done, kkt_all([prepared[j].system.problem for j in done], [solved[j][0] for j in done])):
                residuals[j] = kkt
        self.batched_seconds += time.perf_counter() - start
        return residuals


def _call(method, *args):
    """``method(*args)``, or the exception it raised: a member's failure, which the others outlive."""
    try:
        return method(*args)
    except KeyboardInterrupt:
        raise
    except Exception as exc:
        return exc
