"""One number's rule: its name, type, finiteness, range and unit, and the message of a refusal.

A ``Rule`` checks one number and explains a refusal with a message that names the field, the
value, the allowed range and the unit (and why the range is what it is); the same rule serves the
command line (``Rule.arg``, an argparse ``type=``), the files read and the public API. A
``PairRule`` checks two numbers written "X,Y". The tables of rules are in
:mod:`cobra_ref.infra.validation`.
"""

from __future__ import annotations

import argparse
import math
import numbers
import re
import reprlib
from dataclasses import dataclass


class ValidationError(ValueError):
    """An input outside its rule (the message names the field, the value, the range and the unit)."""


def number_text(x) -> str:
    """A number as a user would type it (1e-5, 0.005, pi/2), for messages and option tables."""
    if isinstance(x, bool) or isinstance(x, numbers.Integral):
        return str(x)
    if isinstance(x, numbers.Real):
        x = float(x)
        if math.isinf(x) or math.isnan(x):
            return str(x)
        for k, name in ((1.0, "pi"), (0.5, "pi/2")):
            if abs(abs(x) - k * math.pi) < 1e-12:
                return name if x > 0 else f"-{name}"
        text = f"{x:.6g}" if x != 0 and (abs(x) >= 1e5 or abs(x) < 1e-3) else f"{x:.10g}"
        return re.sub(r"e([+-])0*(\d)", lambda m: f"e{'-' if m.group(1) == '-' else ''}{m.group(2)}", text)
    return repr(x)


class _Shown(reprlib.Repr):
    """``reprlib``'s shortened repr with numbers as ``number_text`` writes them."""

    def repr1(self, x, level):
        return number_text(x) if is_number(x) else super().repr1(x, level)


_SHOWN = _Shown()
_SHOWN.maxlevel, _SHOWN.maxtuple, _SHOWN.maxlist, _SHOWN.maxdict, _SHOWN.maxstring, _SHOWN.maxother = 3, 6, 6, 6, 40, 40


def value_text(value) -> str:
    """A value as a message shows it: a repr cut to a line (at most six items per level, three
    levels, 40 characters of a string), numbers as ``number_text`` writes them (1e308, not
    np.float64(1e+308)); a 10 MB string or a list nested 200,000 deep stays one short line."""
    return _SHOWN.repr(value)


def is_number(value) -> bool:
    """True for a real number (Python's or numpy's), False for a bool, a string, None, a list."""
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and type(value).__name__ != "bool_"


def as_list(values) -> list | None:
    """``values`` as a list, or None where it is not a sequence (a number, None, ...)."""
    try:
        return list(values)
    except TypeError:
        return None


def check_choice(field: str, value, choices) -> str:
    """``value`` if it is one of ``choices`` (a contact law, a servo, a stepper, a gait), else a
    ``ValidationError`` listing them."""
    if not isinstance(value, str) or value not in choices:
        raise ValidationError(f"{field} must be one of {', '.join(map(str, choices))}; got {field} = {value_text(value)}")
    return value


def _argparse_type(rule, option: str | None):
    """An argparse ``type=`` function that parses with ``rule`` (its refusals become argparse
    errors, exit status 2, with the rule's message); it carries the rule as ``.rule``."""
    field = option or rule.name

    def parse(text: str):
        try:
            return rule.parse(text, field)
        except ValidationError as exc:
            raise argparse.ArgumentTypeError(str(exc)) from None

    parse.rule = rule
    parse.__name__ = rule.name
    return parse


@dataclass(frozen=True)
class Rule:
    """One number's rule: ``kind`` ("float" or "int"), always finite, within ``low`` .. ``high``
    (``low_open`` / ``high_open`` exclude the end), in ``unit``; ``why`` says where the range
    comes from (printed with a refusal)."""

    name: str
    unit: str = "-"
    low: float = -math.inf
    high: float = math.inf
    low_open: bool = False
    high_open: bool = False
    kind: str = "float"
    why: str = ""
    note: str = ""

    def range_text(self, note: bool = True) -> str:
        """The allowed range in interval notation ("(0, 0.005]"), or "any finite number" (with
        ``note``: followed by the rule's note); used by the messages and the option tables."""
        lo, hi = self.low, self.high
        if math.isinf(lo) and math.isinf(hi):
            text = "any finite number" if self.kind == "float" else "any integer"
        elif math.isinf(hi):
            text = f"{'>' if self.low_open else '>='} {number_text(lo)}"
        elif math.isinf(lo):
            text = f"{'<' if self.high_open else '<='} {number_text(hi)}"
        else:
            text = (f"{'(' if self.low_open else '['}{number_text(lo)}, {number_text(hi)}"
                    f"{')' if self.high_open else ']'}")
        return f"{text}, {self.note}" if note and self.note else text

    def _unit(self) -> str:
        return "" if self.unit in ("-", "") else f" {self.unit}"

    def allowed(self) -> str:
        """"allowed (0, 0.005] s", the tail of every message."""
        what = "an integer " if self.kind == "int" else ""
        note = f", {self.note}" if self.note else ""
        return f"allowed: {what}{self.range_text(note=False)}{self._unit()}{note}"

    def check(self, value, field: str | None = None):
        """``value`` as a float (or int), or a ``ValidationError`` naming ``field`` (default the
        rule's name), the value, the allowed range and the unit."""
        field = field or self.name
        if not is_number(value):
            raise ValidationError(f"{field} = {value_text(value)} is not a number ({self.allowed()})")
        if self.kind == "int":
            if not isinstance(value, numbers.Integral):
                if not (math.isfinite(value) and float(value).is_integer()):
                    raise ValidationError(f"{field} = {number_text(float(value))} is not an integer "
                                          f"({self.allowed()})")
            value = int(value)
        else:
            value = float(value)
            if not math.isfinite(value):
                raise ValidationError(f"{field} = {number_text(value)} is not finite ({self.allowed()})")
        below = value <= self.low if self.low_open else value < self.low
        above = value >= self.high if self.high_open else value > self.high
        if below or above:
            why = f" ({self.why})" if self.why else ""
            raise ValidationError(f"{field} = {number_text(value)}{self._unit()} is out of range "
                                  f"({self.allowed()}){why}")
        return value

    def parse(self, text: str, field: str | None = None):
        """The number written in ``text`` (the command line, text files), checked (``check``)."""
        field = field or self.name
        try:
            value = int(text) if self.kind == "int" else float(text)
        except (TypeError, ValueError):
            raise ValidationError(f"{field} = {value_text(text)} is not {'an integer' if self.kind == 'int' else 'a number'} "
                                  f"({self.allowed()})") from None
        return self.check(value, field)

    def arg(self, option: str | None = None):
        """An argparse ``type=`` built from the rule, for the option ``option`` (its refusals
        become argparse errors, exit status 2, with the rule's message); it carries the rule as
        ``.rule``."""
        return _argparse_type(self, option)


@dataclass(frozen=True)
class PairRule:
    """Two numbers written "X,Y", each under ``element`` (its unit and range)."""

    name: str
    element: Rule
    labels: tuple = ("X", "Y")

    def parse(self, text: str, field: str | None = None) -> tuple:
        """(x, y) from "X,Y" (the command line), each checked; a ``ValidationError`` naming the
        field otherwise."""
        field = field or self.name
        parts = str(text).split(",")
        if len(parts) != 2:
            raise ValidationError(f"{field} = {value_text(text)}: expected {','.join(self.labels)}, two numbers "
                                  f"({self.element.allowed()} each)")
        return tuple(self.element.parse(p.strip(), f"{field} {label}") for p, label in zip(parts, self.labels))

    def check(self, values, field: str | None = None) -> tuple:
        """(x, y) from a sequence of two numbers (files and the API), each checked."""
        field = field or self.name
        items = as_list(values)
        if items is None or len(items) != 2:
            raise ValidationError(f"{field} = {value_text(values)}: expected two numbers ({self.element.allowed()} each)")
        return tuple(self.element.check(v, f"{field} {label}") for v, label in zip(items, self.labels))

    def range_text(self) -> str:
        """The range of each of the two numbers (the option tables)."""
        inner, note = self.element.range_text(note=False), self.element.note
        text = f"{','.join(self.labels)}: " + ("two finite numbers" if inner == "any finite number" else f"each {inner}")
        return f"{text}, {note}" if note else text

    def arg(self, option: str | None = None):
        """An argparse ``type=`` for "X,Y" (carries the rule as ``.rule``)."""
        return _argparse_type(self, option)

    @property
    def unit(self) -> str:
        return self.element.unit
