"""Touch-downs sub-stepped: the steps around a contact's strike taken as n steps of dt / n.

Implements: assumption A33 (``docs/assumptions.md``), ``StepSettings.substeps`` = n (by default
2 for the compliant law, 1, whole steps, for the rigid law). On the paper's ground
(k = 1e6 N/m, d = 1e3 N s/m) a link's touch-down is over within two or three steps of 1 ms
(omega dt = 1.4 on a 0.5 kg link), so a step of 1 ms resolves the strike only roughly, and
where the links of a travelling gait arrive carries that error along (docs/results.md). With
n > 1:

* a step in which a contact touches down (its gap closes within the step, or it starts to
  carry a normal impulse that it did not carry after the step before) is taken again as n
  steps of dt / n, from the same state and memory (``onset``);
* so are the steps after it while a loaded contact still approaches faster than
  ``step.IMPACT_SPEED``, and ``HOLD`` steps after the last that did;
* a step that starts whole from anything but the state the last step returned (a caller that
  changed the velocity, as dynamic relaxation does) forgets the refinement.

The step reads qd as the velocity half a step back (q+ = q + dt qd+, ``step.midpoint_velocity``),
so where the step size changes the velocity is re-read, with the acceleration a of the last
two velocities::

    qd_f = qd + (dt - dt_f) / 2 a        (into substeps of dt_f = dt / n)
    qd   = qd_f - (dt - dt_f) / 2 a      (out of them)

which keeps a constant acceleration exact (``tests/test_touchdown.py``). A sub-stepped step
returns one ``StepResult`` of dt (``merged``): the state after the last substep; the contacts,
approach speeds, energies and Delassus diagonal of the first; each contact's impulse summed over
the substeps in the world frame and read in the first substep's frame (a contact within the
search margin at the step's start: the 1 cm margin holds every contact a step can close); each
contact's normal rate the one that takes its first gap to the smallest gap a substep ends at, so
that g + dt w_N is closed (at most 0) wherever a substep closed the contact; the torque's mean
and the works' sums; ``substeps`` = n. The re-reading of the velocity where the step size changes
is no logged force, so over a sub-stepped stretch the state's momentum and energy change by the
logged impulses and works plus the re-reads' shifts (each (dt - dt_f) / 2 a); on whole steps
the ledger closes as before. A batch
(:mod:`cobra_ref.fast.batch`) takes its members' whole steps together, and then the substeps of
the members that take their step in substeps together, in a batch of dt / n whose members are
their ``TouchdownStepper``'s substeps' steppers (``holding``, ``touched``, ``entered``, ``left``),
so that each member is its single run, bit for bit.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .least_action import LeastActionInfo
from .step import IMPACT_SPEED, StepResult

HOLD = 3  # steps still sub-stepped after the last in which a loaded contact approached
LOADED = 1e-12  # [N s] a normal impulse that carries load (below it, an unloaded contact's QP rounding)


def _scaled(memory: dict | None, factor: float, qd_prev: np.ndarray) -> dict | None:
    """A stepper's memory for another step size: impulses scaled by ``factor`` (dt_new / dt_old;
    they only start the next friction fixed point), the velocity before the step ``qd_prev``."""
    if not memory:
        return memory
    return {"contacts": {key: P * factor for key, P in memory["contacts"].items()},
            "servo": memory["servo"] * factor, "qd": qd_prev}


def onset(result: StepResult, memory_before: dict | None, dt: float) -> bool:
    """Whether a contact touches down in the step ``result`` of dt: its gap closes within it (apart
    at the start, g > 0, and not at the end, g + dt w_N <= 0), or it starts to carry a normal
    impulse that it did not carry after the step before (on a run's first step, with no memory,
    only one that strikes: ``striking``)."""
    c, m = result.contacts, result.contacts.m
    if np.any((c.g > 0.0) & (c.g + dt * result.w[0:3 * m:3] <= 0.0)):
        return True
    if not memory_before:
        return striking(result)
    before = memory_before["contacts"]
    return any(on and key not in before for key, on in zip(c.keys(), _loaded(result).tolist()))


def striking(result: StepResult) -> bool:
    """Whether a loaded contact of ``result`` approached faster than ``IMPACT_SPEED``."""
    return bool(np.any(result.approach[_loaded(result)] > IMPACT_SPEED))


def _loaded(result: StepResult) -> np.ndarray:
    """(m,) whether each contact of ``result`` carries a normal impulse above ``LOADED``."""
    return result.p[0:3 * result.contacts.m:3] > LOADED


def merged(results: list, dt: float, q, qd, memory: dict) -> StepResult:
    """One step of dt from the substeps ``results`` (module docstring), ending at (q, qd) with
    the whole step's ``memory``."""
    first, last, n = results[0], results[-1], len(results)
    # each loaded contact's world impulse, summed: the substeps' memories hold them by key (an unloaded
    # contact carries none, friction included); each contact's smallest gap at a substep's end (a
    # contact can close and open again within the step)
    total, end_gap = {}, {}
    for r in results:
        for key, P_k in r.memory["contacts"].items():
            total[key] = total.get(key, 0.0) + P_k
        for key, g, w_N in zip(r.contacts.keys(), r.contacts.g, r.w[0::3]):
            end_gap[key] = min(end_gap.get(key, np.inf), g + dt / n * w_N)
    m = first.contacts.m
    p, w = first.p.copy(), first.w.copy()
    for i, key in enumerate(first.contacts.keys()):
        p[3 * i:3 * i + 3] = first.contacts.frame[i].T @ total.get(key, np.zeros(3))
        if key in end_gap:  # the normal rate that takes the first gap to the smallest end gap
            w[3 * i] = (end_gap[key] - first.contacts.g[i]) / dt
    p[3 * m:] = np.sum([r.p[3 * r.contacts.m:] for r in results], axis=0)
    infos = [r.info for r in results]
    info = LeastActionInfo(all(i.converged for i in infos), sum(i.iterations for i in infos),
                           sum(i.qp_iterations for i in infos), sum(i.qp_solves for i in infos),
                           max(i.residual for i in infos), last.info.status)
    residuals = {key: max(r.residuals[key] for r in results) for key in first.residuals}
    return first._replace(q=q, qd=qd, p=p, w=w, info=info, residuals=residuals,
                          tau=np.sum([r.tau for r in results], axis=0) / n,
                          work_actuators=sum(r.work_actuators for r in results),
                          work_contacts=sum(r.work_contacts for r in results), q_ref=last.q_ref, memory=memory,
                          substeps=n)


class TouchdownStepper:
    """A stepper (``make(model, settings)``, of either kind) whose touch-downs are sub-stepped into
    ``settings.substeps`` steps (module docstring); the same interface as the others."""

    def __init__(self, make, model, settings, sub=None):
        self.model, self.settings = model, settings
        self.n, self.dt = settings.substeps, settings.dt
        whole = replace(settings, touchdown_substeps=1)
        self.whole = make(model, whole)
        # the stepper of dt / n (a batch passes its member of the substeps' batch; ``sub_settings``)
        self.sub = make(model, sub_settings(settings)) if sub is None else sub
        self.name = self.whole.name
        self.hold, self._qd_sub, self._returned = 0, None, None

    @property
    def memory(self):
        return self.whole.memory

    @memory.setter
    def memory(self, memory):
        self.whole.memory = memory
        self.hold, self._returned = 0, None

    @property
    def timing(self) -> dict:
        return {k: v + self.sub.timing.get(k, 0.0) for k, v in self.whole.timing.items()}

    def reset(self) -> None:
        """Forget the warm start, the timing and the refinement: between runs on one stepper."""
        self.whole.reset()
        self.sub.reset()
        self.hold, self._qd_sub, self._returned = 0, None, None

    def step(self, q, qd, t: float, reference, tau_ext=None) -> StepResult:
        """One step of dt from (q, qd) at time t, sub-stepped around a touch-down (module docstring)."""
        if self.holding(qd):
            return self.substepped(q, qd, t, reference, tau_ext, self.whole.memory)
        memory = self.whole.memory
        result = self.whole.step(q, qd, t, reference, tau_ext)
        return self.substepped(q, qd, t, reference, tau_ext, memory) if self.touched(result, memory) else result

    def holding(self, qd) -> bool:
        """Whether the step from qd goes straight to substeps: within the hold after a strike, and
        from the velocity the last step returned (any other forgets the hold)."""
        if self.hold and (self._returned is None or not np.array_equal(qd, self._returned)):
            self.hold = 0
        return bool(self.hold)

    def touched(self, result: StepResult, memory) -> bool:
        """Whether a contact touched down (``onset``) in the whole step ``result``, taken from
        ``memory``; if so the whole stepper's memory goes back to ``memory``, for the step to be
        taken again in substeps."""
        if not onset(result, memory, self.dt):
            return False
        self.whole.memory = memory
        return True

    def substepped(self, q, qd, t: float, reference, tau_ext, memory) -> StepResult:
        """The step of dt from (q, qd) at t as n substeps, from the whole step's ``memory`` (or,
        while held, from where the last substep left), merged into one result (module docstring)."""
        qd_sub, results = self.entered(qd, memory), []
        for i in range(self.n):
            results.append(self.sub.step(q, qd_sub, t + i * self.dt / self.n, reference, tau_ext))
            q, qd_sub = results[-1].q, results[-1].qd
        return self.left(results)

    def entered(self, qd, memory) -> np.ndarray:
        """The velocity the first substep starts from, the sub stepper's memory set for it: into
        substeps, qd (half a step back) re-read half a substep back from the whole step's ``memory``;
        while held, where the last substep left."""
        if self.hold:
            return self._qd_sub
        qd_prev = memory["qd"] if memory and memory.get("qd") is not None else qd
        a = (qd - qd_prev) / self.dt
        qd_sub = qd + 0.5 * (self.dt - self.dt / self.n) * a
        self.sub.memory = _scaled(memory, 1.0 / self.n, qd_sub - a * self.dt / self.n)
        return qd_sub

    def left(self, results: list) -> StepResult:
        """The step of dt from the n substeps' ``results``, merged, its velocity re-read half a step
        back, as the next whole step reads it; the hold counted on."""
        dt, n = self.dt, self.n
        self.hold = HOLD if any(striking(r) for r in results) or not self.hold else self.hold - 1
        q, qd_sub = results[-1].q, results[-1].qd
        a = (qd_sub - self.sub.memory["qd"]) * n / dt
        qd_whole = qd_sub - 0.5 * (dt - dt / n) * a
        memory = _scaled(self.sub.memory, float(n), qd_whole - a * dt)
        self.whole.memory, self._qd_sub, self._returned = memory, qd_sub, qd_whole
        return merged(results, dt, q, qd_whole, memory)


def sub_settings(settings):
    """The settings of a touch-down's substeps: whole steps of dt / ``settings.substeps``."""
    return replace(settings, touchdown_substeps=1, dt=settings.dt / settings.substeps)
