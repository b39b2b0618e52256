"""The argument checks of the public Python functions: the command line's rules, at the API's door.

``simulate``, ``initial_state``, ``gait``, ``make_problem``, ``rollout``, ``check_goal``,
``load_reference`` and ``Trajectory.from_npz`` check their arguments at the top, one line each,
with these functions and the rules of :mod:`cobra_ref.infra.validation` (the same rules the
command line's options use). A refusal names the argument, its value (numbers as a person writes
them: 0.005, 1e-5, pi/2) and what is allowed:

* ``ArgumentTypeError`` (a ``TypeError``): an argument of the wrong kind (a string for a number,
  a dict for a ``StepSettings``, None for a model);
* ``ArgumentError`` (a ``ValueError``, and a ``ValidationError``): the right kind, outside its
  rule (a negative gap, a NaN weight, a horizon of more than 10^6 steps). A function with an error
  of its own (``GaitError``, ``ShootingError``, ``ReferenceError``) passes it as ``error``: each
  of those is an ``ArgumentError``.
"""

from __future__ import annotations

import os

from .rule import Rule, ValidationError, as_list, is_number, number_text
from .validation import RULES, step_count

__all__ = ["ArgumentError", "ArgumentTypeError", "choice", "duration_steps", "function", "instance", "number",
           "numbers", "path", "shown"]

FINITE = Rule("value")  # any finite number


class ArgumentError(ValidationError):
    """An argument of a public function outside its rule (the message names the argument, the value
    and what is allowed)."""


class ArgumentTypeError(TypeError):
    """An argument of a public function of the wrong type (the message names the argument, the
    value and what is allowed)."""


def shown(value, limit: int = 80) -> str:
    """``value`` as a message shows it: a number as a person writes it, anything else by its repr,
    cut to ``limit`` characters."""
    text = number_text(value) if is_number(value) else repr(value)
    return text if len(text) <= limit else text[:limit - 3] + "..."


def number(name: str, value, rule: Rule | str = FINITE, error: type = ArgumentError):
    """``value`` checked by ``rule`` (a ``Rule`` or a name in ``RULES``): a float (an int for an
    integer rule); an ``ArgumentTypeError`` for a value that is not a number (a string, a bool,
    None, a list), else ``error`` with the rule's message naming ``name``."""
    rule = RULES[rule] if isinstance(rule, str) else rule
    if not is_number(value):
        raise ArgumentTypeError(f"{name} = {shown(value)} is not a number ({rule.allowed()})")
    try:
        return rule.check(value, name)
    except ValidationError as exc:
        raise error(str(exc)) from None


def numbers(name: str, values, count: int, rule: Rule | str = FINITE, labels=None, error: type = ArgumentError):
    """``values`` as a tuple of ``count`` numbers, each checked by ``rule`` (``number``) and named
    ``name label`` (``labels``: one per number; default ``name[i]``); ``error`` for a sequence of
    another length (naming the labels), an ``ArgumentTypeError`` for a string or a non-sequence."""
    labels = tuple(labels) if labels else tuple(f"[{i}]" for i in range(count))
    items = None if isinstance(values, (str, bytes)) else as_list(values)
    what = f"{count} numbers ({', '.join(labels)})"
    if items is None:
        raise ArgumentTypeError(f"{name} = {shown(values)} is not a sequence (allowed: {what})")
    if len(items) != count:
        raise error(f"{name} = {shown(values)} has {len(items)} value{'s' * (len(items) != 1)} "
                    f"(allowed: {what})")
    sep = "" if labels[0].startswith("[") else " "
    return tuple(number(f"{name}{sep}{label}", v, rule, error) for v, label in zip(items, labels))


def duration_steps(duration, dt: float, name: str = "duration", error: type = ArgumentError) -> int:
    """The number of steps of ``duration`` at the checked ``dt``, rounded (``validation.step_count``,
    the command line's rule: > 0, at least one step, at most 10^6 steps); an ``ArgumentTypeError``
    for a value that is not a number, else ``error``."""
    if not is_number(duration):
        raise ArgumentTypeError(f"{name} = {shown(duration)} is not a number (allowed: > 0 s)")
    try:
        return step_count(duration, dt, exact=False, duration_field=name)
    except ValidationError as exc:
        raise error(str(exc)) from None


def instance(name: str, value, kind, example: str = "", optional: bool = False):
    """``value`` if it is a ``kind`` (a type or a tuple of types; or None with ``optional``), else an
    ``ArgumentTypeError`` naming the argument, its value and ``example`` (how to make one)."""
    if isinstance(value, kind) or (optional and value is None):
        return value
    kinds = " or ".join(k.__name__ for k in (kind if isinstance(kind, tuple) else (kind,)))
    allowed = f"a {kinds}{' or None' if optional else ''}{f', e.g. {example}' if example else ''}"
    raise ArgumentTypeError(f"{name} = {shown(value)} is a {type(value).__name__}, not a {kinds} "
                            f"(allowed: {allowed})")


def function(name: str, value, what: str, optional: bool = False):
    """``value`` if it can be called (or is None with ``optional``), else an ``ArgumentTypeError``
    saying what it must be (``what``)."""
    if callable(value) or (optional and value is None):
        return value
    raise ArgumentTypeError(f"{name} = {shown(value)} is not callable (allowed: {what}"
                            f"{' or None' if optional else ''})")


def choice(name: str, value, choices, error: type = ArgumentError) -> str:
    """``value`` if it is one of ``choices`` (names), else ``error`` (an ``ArgumentTypeError`` for a
    value that is not a string) listing them."""
    allowed = ", ".join(map(str, choices))
    if not isinstance(value, str):
        raise ArgumentTypeError(f"{name} = {shown(value)} is not a name (allowed: {allowed})")
    if value not in choices:
        raise error(f"{name} = {value!r} is unknown (allowed: {allowed})")
    return value


def path(name: str, value) -> str:
    """``value`` as a file name (a str or an ``os.PathLike``), else an ``ArgumentTypeError``."""
    if isinstance(value, os.PathLike):
        value = os.fspath(value)
    if not isinstance(value, str) or not value:
        raise ArgumentTypeError(f"{name} = {shown(value)} is not a file name (allowed: a non-empty str or "
                                "os.PathLike)")
    return value
