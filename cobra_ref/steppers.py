"""The steppers by name: the one place where "fast" and "reference" are mapped to their classes.

A stepper advances (q, qd) by one step and keeps what carries from one step to the next (the
friction fixed point's warm start). Both have the same interface::

    stepper = make_stepper(name, model, settings)
    result = stepper.step(q, qd, t, reference, tau_ext=None)   # -> step.StepResult
    stepper.memory                                           # the warm start of the next step
    stepper.timing                                           # seconds spent, by phase
    stepper.reset()                                          # forget both (a new run)

* ``"reference"``: :class:`ReferenceStepper`, the readable step :func:`cobra_ref.step.step`;
  its ``timing`` has one phase, ``"total"``;
* ``"fast"``: :class:`cobra_ref.fast.stepper.FastStepper`, the same steps with batched parts and
  certified QP solves; its ``timing`` has the phases ``fast.stepper.PHASES``. It is imported only
  when asked for, so a reference run never imports the fast wing.

With ``settings.substeps`` = n > 1 (the compliant law's default, A33), either kind comes wrapped in a
:class:`cobra_ref.touchdown.TouchdownStepper`, which takes the steps around a touch-down in n
substeps (A33) and has the same interface.

``start.initial_state`` and ``simulate.simulate`` take a stepper *name* and make their own stepper
with ``make_stepper``, so a run is taken by one kind of stepper from its settle to its last step.
"""

from __future__ import annotations

import time

from .infra import arguments
from .model import Model
from .step import StepResult, StepSettings, step
from .touchdown import TouchdownStepper

STEPPERS = ("fast", "reference")


class ReferenceStepper:
    """The reference step :func:`cobra_ref.step.step` with its warm start carried from step to step."""

    name = "reference"

    def __init__(self, model: Model, settings: StepSettings = StepSettings()):
        self.model, self.settings = model, settings
        self.memory = None
        self.timing = {"total": 0.0}

    def reset(self) -> None:
        """Forget the warm start and the timing: between runs on one stepper."""
        self.memory = None
        self.timing = {"total": 0.0}

    def step(self, q, qd, t: float, reference, tau_ext=None) -> StepResult:
        """One step from (q, qd) at time t (:func:`cobra_ref.step.step`), from this stepper's memory."""
        start = time.perf_counter()
        result = step(self.model, q, qd, t, reference, self.settings, self.memory, tau_ext)
        self.memory = result.memory
        self.timing["total"] += time.perf_counter() - start
        return result


def make_stepper(name: str, model: Model, settings: StepSettings = StepSettings()):
    """A new stepper of kind ``name`` (one of ``STEPPERS``) for ``model`` under ``settings``.

    Raises ValueError naming the allowed names for any other ``name``, an
    ``infra.arguments.ArgumentTypeError`` for a model that is not a ``Model`` or settings that are
    not a ``StepSettings``.
    """
    arguments.instance("model", model, Model, "cobra_model()")
    arguments.instance("settings", settings, StepSettings, "StepSettings(dt=0.001)")
    if settings.substeps > 1 and name in STEPPERS:
        return TouchdownStepper(lambda m, s: make_stepper(name, m, s), model, settings)
    if name == "fast":
        from .fast.stepper import FastStepper

        return FastStepper(model, settings)
    if name == "reference":
        return ReferenceStepper(model, settings)
    raise ValueError(f"stepper must be one of {', '.join(STEPPERS)}, got {name!r}")
