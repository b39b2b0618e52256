"""Every input of cobra_ref checked by one rule, stated once: name, type, finiteness, range, unit.

Helper: the validation layer. A ``Rule`` checks one number and explains a refusal with a message
that names the field, the value, the allowed range and the unit (and why the range is what it
is); the same rule serves the command line (``Rule.arg``, an argparse ``type=``), the files read
(reference files, params JSON) and the public API (``StepSettings``, ``CobraParameters``). The
README's option table is rendered from these rules (``options_markdown``).

The time grid (``time_grid``) is checked as a whole before anything is allocated: a time step in
the range ``[DT_MIN, DT_MAX]``, a duration of at least one step, at most ``MAX_STEPS``.

Why dt <= 5 ms (``DT_MAX``): the contact's damper and friction and the servo's damper are implicit
in the step, and the contact's and the servo's springs as far as their stability needs
(``compliance.contact_theta``, ``compliance.servo_theta``), so one contact or one joint is stable at
every dt; what a large step loses is accuracy, and far above 5 ms the whole robot's run diverges
(C at 50 ms, below). The compliant contact's damping time
scale is m / d = 0.5 kg / 1e3 N s/m = 0.5 ms; a 5 ms step averages over it but still resolves the
gaits (0.5 Hz: 400 steps per period). Measured (``simulate`` from ``initial_state``, default
settings, the figures' box placement) against dt = 1 ms, C rolling for 3 s and sidewinding for 4 s:

    dt      C: penetration  C: box moved  C: head off   sidewinding: penetration  box moved  head off
    1 ms    0.035 mm        0.167 m       -             0.70 mm                   0.162 m    -
    2 ms    0.026 mm        0.170 m       0.7 cm        0.39 mm                   0.129 m    5.7 cm (of 1.8 m travelled)
    3 ms    0.036 mm        0.172 m       1.4 cm        0.31 mm                   0.103 m    6.3 cm
    5 ms    0.073 mm        0.176 m       2.8 cm        0.19 mm                   0.102 m    4.8 cm
    10 ms   0.24 mm         0.180 m       7.2 cm        5.4 mm                    0.200 m    2.3 cm
    20 ms   0.90 mm         0.182 m       17 cm         16 mm                     0.142 m    7.9 cm
    50 ms   diverges                                    34 mm                     0.455 m    38 cm

(at 50 ms C's run diverges, the robot thrown metres deep into the ground and far away, and
sidewinding's friction fixed point fails on 1.25 % of the steps). Up to 5 ms C
agrees with 1 ms within 3 cm and the penetration stays below 0.7 mm (sidewinding's box, which
the robot strikes and tips, moves 0.10-0.16 m depending on dt: its push is not converged at
these steps, docs/results.md); at 10 ms C's path parts by 7 cm and sidewinding sinks 5 mm into
the ground, 16 mm at 20 ms.
Why dt >= 10 us (``DT_MIN``): the solver's absolute tolerance of 1e-7 N s on an impulse is a force
error of 1e-7 / dt, 0.01 N (0.2 % of a link's weight) at 10 us. Why at most 10^6 steps
(``MAX_STEPS``): a run records about 2 kB per step (states, torques, solver records, the contact
log): 10^6 steps are about 2 GB, and about an hour at 3 ms per step.
"""

from __future__ import annotations

import argparse
import math
import numbers
import re
from dataclasses import dataclass

# ----------------------------------------------------------------------------------------- time grid
DEFAULT_DT = 1e-3  # [s] the time step of every run unless one is given (docs/assumptions.md A14)
DT_MIN = 1e-5  # [s] the QP's absolute tolerance 1e-7 N s is a force error of 1e-7 / dt: 0.01 N at 10 us
DT_MAX = 5e-3  # [s] (docs/assumptions.md A14; measured, see ``DT_WHY``)
MAX_STEPS = 1_000_000  # steps per run (see ``STEPS_WHY``)
BYTES_PER_STEP = 2_000  # [B] about, a run's record per step (states, torques, solver records, contact log)

DT_WHY = ("above 5 ms the runs leave the converged ones (the contact's damping time is m/d = 0.5 ms): measured, "
          "C rolling ends 7 cm off at 10 ms and 17 cm at 20 ms, sidewinding sinks 5 mm into the ground at 10 ms, "
          "16 mm at 20 ms; below "
          "10 us the solver's tolerance 1e-7 N s is a force error above 0.01 N; see cobra_ref/validation.py")
STEPS_WHY = (f"a run records about {BYTES_PER_STEP // 1000} kB per step: 10^6 steps are about "
             f"{MAX_STEPS * BYTES_PER_STEP / 1e9:.0f} GB and an hour of computing")


class ValidationError(ValueError):
    """An input outside its rule (the message names the field, the value, the range and the unit)."""


def _g(x) -> str:
    """A number as a user would type it (1e-5, 0.005, pi/2)."""
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
        ``note``: followed by the rule's note).

        Helper: the messages and the README's option table.
        """
        lo, hi = self.low, self.high
        if math.isinf(lo) and math.isinf(hi):
            text = "any finite number" if self.kind == "float" else "any integer"
        elif math.isinf(hi):
            text = f"{'>' if self.low_open else '>='} {_g(lo)}"
        elif math.isinf(lo):
            text = f"{'<' if self.high_open else '<='} {_g(hi)}"
        else:
            text = f"{'(' if self.low_open else '['}{_g(lo)}, {_g(hi)}{')' if self.high_open else ']'}"
        return f"{text}, {self.note}" if note and self.note else text

    def _unit(self) -> str:
        return "" if self.unit in ("-", "") else f" {self.unit}"

    def allowed(self) -> str:
        """"allowed (0, 0.005] s", the tail of every message.

        Helper: the messages.
        """
        what = "an integer " if self.kind == "int" else ""
        note = f", {self.note}" if self.note else ""
        return f"allowed: {what}{self.range_text(note=False)}{self._unit()}{note}"

    def check(self, value, field: str | None = None):
        """``value`` as a float (or int), or a ``ValidationError`` naming ``field`` (default the
        rule's name), the value, the allowed range and the unit.

        Helper: the validation layer (module docstring).
        """
        field = field or self.name
        if not is_number(value):
            raise ValidationError(f"{field} = {value!r} is not a number ({self.allowed()})")
        if self.kind == "int":
            if not isinstance(value, numbers.Integral):
                if not (math.isfinite(value) and float(value).is_integer()):
                    raise ValidationError(f"{field} = {_g(float(value))} is not an integer ({self.allowed()})")
            value = int(value)
        else:
            value = float(value)
            if not math.isfinite(value):
                raise ValidationError(f"{field} = {_g(value)} is not finite ({self.allowed()})")
        below = value <= self.low if self.low_open else value < self.low
        above = value >= self.high if self.high_open else value > self.high
        if below or above:
            why = f" ({self.why})" if self.why else ""
            raise ValidationError(f"{field} = {_g(value)}{self._unit()} is out of range ({self.allowed()}){why}")
        return value

    def parse(self, text: str, field: str | None = None):
        """The number written in ``text``, checked (``check``).

        Helper: the command line and text files.
        """
        field = field or self.name
        try:
            value = int(text) if self.kind == "int" else float(text)
        except (TypeError, ValueError):
            raise ValidationError(f"{field} = {text!r} is not {'an integer' if self.kind == 'int' else 'a number'} "
                                  f"({self.allowed()})") from None
        return self.check(value, field)

    def arg(self, option: str | None = None):
        """An argparse ``type=`` function built from the rule (its refusals become argparse errors,
        exit status 2, with the rule's message); the function carries the rule as ``.rule``.

        Helper: the command-line options.
        """
        field = option or self.name

        def parse(text: str):
            try:
                return self.parse(text, field)
            except ValidationError as exc:
                raise argparse.ArgumentTypeError(str(exc)) from None

        parse.rule = self
        parse.__name__ = self.name
        return parse


@dataclass(frozen=True)
class PairRule:
    """Two numbers written "X,Y", each under ``element`` (its unit and range)."""

    name: str
    element: Rule
    labels: tuple = ("X", "Y")

    def parse(self, text: str, field: str | None = None) -> tuple:
        """(x, y) from "X,Y", each checked; a ``ValidationError`` naming the field otherwise.

        Helper: the command line.
        """
        field = field or self.name
        parts = str(text).split(",")
        if len(parts) != 2:
            raise ValidationError(f"{field} = {text!r}: expected {','.join(self.labels)}, two numbers "
                                  f"({self.element.allowed()} each)")
        return tuple(self.element.parse(p.strip(), f"{field} {label}") for p, label in zip(parts, self.labels))

    def check(self, values, field: str | None = None) -> tuple:
        """(x, y) from a sequence of two numbers, each checked.

        Helper: files and the API.
        """
        field = field or self.name
        try:
            items = list(values)
        except TypeError:
            items = None
        if items is None or len(items) != 2:
            raise ValidationError(f"{field} = {values!r}: expected two numbers ({self.element.allowed()} each)")
        return tuple(self.element.check(v, f"{field} {label}") for v, label in zip(items, self.labels))

    def range_text(self) -> str:
        """The range of each of the two numbers.

        Helper: the README's option table.
        """
        inner, note = self.element.range_text(note=False), self.element.note
        text = f"{','.join(self.labels)}: " + ("two finite numbers" if inner == "any finite number" else f"each {inner}")
        return f"{text}, {note}" if note else text

    def arg(self, option: str | None = None):
        """An argparse ``type=`` for "X,Y" (carries the rule as ``.rule``).

        Helper: the command-line options.
        """
        field = option or self.name

        def parse(text: str):
            try:
                return self.parse(text, field)
            except ValidationError as exc:
                raise argparse.ArgumentTypeError(str(exc)) from None

        parse.rule = self
        parse.__name__ = self.name
        return parse

    @property
    def unit(self) -> str:
        return self.element.unit


def is_number(value) -> bool:
    """True for a real number (Python's or numpy's), False for a bool, a string, None, a list.

    Helper: the validation layer.
    """
    return isinstance(value, numbers.Real) and not isinstance(value, bool) and type(value).__name__ != "bool_"


# ------------------------------------------------------------------------------------------ the rules
MU_WHY = "a Coulomb coefficient; the paper's is 1.0 (A13); dry pairs above 2 are not these materials"

RULES = {
    # the time grid (time_grid checks them together)
    "dt": Rule("dt", "s", DT_MIN, DT_MAX, why=DT_WHY),
    "duration": Rule("duration", "s", 0.0, MAX_STEPS * DT_MAX, low_open=True,
                     why="at most 10^6 steps of the largest dt", note="a whole number of steps of dt, at most 10^6 steps"),
    "margin": Rule("margin", "m", 0.0, 1.0, why="the contact search margin (A16: 1 cm)"),
    "timestep": Rule("timestep", "s", 1e-6, 2e-3,
                     why="MuJoCo's timestep; MuJoCo integrates the exported stiff contact explicitly, stable below "
                         "about 0.2 ms with the box (docs/mujoco.md, A27)"),
    # friction, the box and its placement
    "mu": Rule("mu", "-", 0.0, 2.0, why=MU_WHY),
    "mu_robot_box": Rule("mu_robot_box", "-", 0.0, 2.0, why=MU_WHY + "; A22: 0.5"),
    "mu_box_ground": Rule("mu_box_ground", "-", 0.0, 2.0, why=MU_WHY + "; A13: the same as mu"),
    "box_mass": Rule("box_mass", "kg", 0.0, 100.0, low_open=True, why="the paper's box is 0.5 kg; A8"),
    "box_offset": Rule("box_offset", "m", -5.0, 5.0, why="from the middle of the robot, world axes; the robot "
                                                         "is 1.7 m long"),
    "box_yaw": Rule("box_yaw", "rad", -math.pi, math.pi, why="the box's heading about the vertical"),
    "box_gap": Rule("box_gap", "m", 0.0, 1.0, why="between the box and the middle link at the start (A9: 5 cm)"),
    "goal": Rule("goal", "m", why="relative to the box's start, world axes",
                 note="within reach: at most 0.5 m/s x duration and 5 m from the box (planning.problem.check_goal)"),
    # the optimizer
    "ramp_time": Rule("ramp_time", "s", 0.0, 100.0, why="the phase-rate ramp of the gaits"),
    "maxiter": Rule("maxiter", "-", 0, 10_000, kind="int"),
    "seed": Rule("seed", "-", 0, 2**32 - 1, kind="int", why="numpy's seeds"),
    "popsize": Rule("popsize", "-", 1, 1000, kind="int"),
    "workers": Rule("workers", "-", 1, 1024, kind="int"),
    "weight": Rule("weight", "-", 0.0, 1e6, why="a weight of the shooting cost (A17)"),
    # the benchmark
    "horizon": Rule("duration", "s", 0.0, MAX_STEPS * DT_MAX, low_open=True,
                    why="at most 10^6 steps of the largest dt", note="at most 10^6 steps of dt"),
    "bench_duration": Rule("duration", "s", 0.0, 60.0, low_open=True, why="a benchmark of at most a minute",
                           note="a whole number of 1 ms steps"),
    # gait parameters given on the command line (the gait checks each one's own range)
    "study_duration": Rule("duration", "s", 0.0, 20.0, low_open=True,
                           why="each of the study's runs; the finest dt (0.25 ms) takes 4000 steps per second"),
    "restart": Rule("restart", "s", 0.0, 20.0, why="the time at which every run of the study starts from one "
                                                     "state; below the study's duration"),
    "scenario_duration": Rule("duration", "s", 0.0, 60.0, low_open=True, why="each scenario of the sweep"),
    "count": Rule("count", "-", 1, 100_000, kind="int"),
    "members": Rule("members", "-", 1, 256, kind="int",
                    why="ensemble members per gait (A29); member 0 is the figure run"),
    "gait_param": Rule("gait parameter", "-", why="the gait checks its own range"),
    # replaying and rendering a run (viz.render checks the same ranges for API callers)
    "speed": Rule("speed", "-", 0.0, 100.0, low_open=True, why="simulated seconds per shown second"),
    "fps": Rule("fps", "1/s", 0.0, 120.0, low_open=True, why="video frames per second; a GIF plays at most 50"),
    "at": Rule("at", "s", 0.0, MAX_STEPS * DT_MAX, why="the time of a still frame, within the run"),
    "width": Rule("width", "px", 16, 1920, kind="int", why="MuJoCo's offscreen framebuffer"),
    "height": Rule("height", "px", 16, 1080, kind="int", why="MuJoCo's offscreen framebuffer"),
    "force_scale": Rule("force_scale", "m/N", 0.0, 1.0, low_open=True, why="the length of a force arrow per newton"),
}
RULES["box_offset_pair"] = PairRule("box_offset", RULES["box_offset"], ("DX", "DY"))
RULES["goal_pair"] = PairRule("goal", RULES["goal"], ("X", "Y"))

# CobraParameters: each field's rule (units as in cobra_ref.params.UNITS)
_MASS = dict(unit="kg", low=0.0, high=100.0, low_open=True)
_LENGTH = dict(unit="m", low=0.0, high=10.0, low_open=True)
PARAMETER_RULES = {
    "n_body_links": Rule("n_body_links", "-", 2, 50, kind="int", why="body links between the head and the tail"),
    "mass_head": Rule("mass_head", **_MASS), "mass_link": Rule("mass_link", **_MASS),
    "mass_tail": Rule("mass_tail", **_MASS),
    "length_head": Rule("length_head", **_LENGTH), "length_link": Rule("length_link", **_LENGTH),
    "length_tail": Rule("length_tail", **_LENGTH),
    "radius_head": Rule("radius_head", "m", 0.0, 1.0, low_open=True),
    "radius_link": Rule("radius_link", "m", 0.0, 1.0, low_open=True),
    "radius_tail": Rule("radius_tail", "m", 0.0, 1.0, low_open=True),
    "joint_gap": Rule("joint_gap", "m", 0.0, 1.0),
    "q_max": Rule("q_max", "rad", 0.0, math.pi, low_open=True, why="a revolute joint's range (A4: pi/2)"),
    "tau_max": Rule("tau_max", "N m", 0.0, 1e4, low_open=True, why="A5: 9.2 N m"),
    "qd_max": Rule("qd_max", "rad/s", 0.0, 1e4, low_open=True, why="A6: 3.77 rad/s"),
    "box_size": Rule("box_size", "m", 0.0, 2.0, low_open=True, why="A8: a 0.10 m cube"),
    "box_mass": RULES["box_mass"],
    "servo_kp": Rule("servo_kp", "N m/rad", 0.0, 1e7, low_open=True, why="A7: 500 N m/rad"),
    "servo_kd": Rule("servo_kd", "N m s/rad", 0.0, 1e5, why="A7: 5 N m s/rad"),
    "gravity": Rule("gravity", "m/s^2", 0.0, 100.0, why="A20: 9.81 m/s^2"),
    "mu": RULES["mu"],
    "mu_robot_box": RULES["mu_robot_box"],
    "mu_box_ground": RULES["mu_box_ground"],
    "contact_stiffness": Rule("contact_stiffness", "N/m", 0.0, 1e10, low_open=True, why="A12: 1e6 N/m"),
    "contact_damping": Rule("contact_damping", "N s/m", 0.0, 1e8, why="A12: 1e3 N s/m"),
    "stiction_velocity": Rule("stiction_velocity", "m/s", 0.0, 1.0, low_open=True, why="A13: 1e-3 m/s"),
}
OPTIONAL_PARAMETERS = ("mu_box_ground",)  # None means "the same as mu"
INERTIA_RULE = Rule("inertia", "kg m^2", 0.0, 100.0, low_open=True)


def rule(name: str) -> Rule:
    """The rule called ``name`` (``RULES``).

    Helper: the validation layer.
    """
    return RULES[name]


def check(name: str, value, field: str | None = None):
    """``RULES[name].check(value, field)``: the value, or a ``ValidationError``.

    Helper: the validation layer.
    """
    return RULES[name].check(value, field)


def check_choice(field: str, value, choices) -> str:
    """``value`` if it is one of ``choices``, else a ``ValidationError`` listing them.

    Helper: the validation layer (contact law, servo, stepper, gait).
    """
    if not isinstance(value, str) or value not in choices:
        raise ValidationError(f"{field} must be one of {', '.join(map(str, choices))}; got {field} = {value!r}")
    return value


def check_parameters(params) -> None:
    """Check every field of a ``CobraParameters`` by ``PARAMETER_RULES``; the inertias (Ixx, Iyy, Izz)
    must be three positive principal moments that satisfy the triangle inequality.

    Helper: ``CobraParameters.__post_init__``.
    """
    from dataclasses import fields

    for f in fields(params):
        value = getattr(params, f.name)
        if f.name.startswith("inertia_"):
            check_inertia(f.name, value)
        elif f.name in PARAMETER_RULES and not (value is None and f.name in OPTIONAL_PARAMETERS):
            PARAMETER_RULES[f.name].check(value, f.name)


def check_inertia(field: str, value) -> tuple:
    """Three principal moments (Ixx, Iyy, Izz) [kg m^2], each > 0, and each at most the sum of the
    other two (a rigid body's triangle inequality); a ``ValidationError`` otherwise.

    Helper: ``check_parameters``.
    """
    if isinstance(value, (str, bytes)):
        raise ValidationError(f"{field} = {value!r}: expected three numbers (Ixx, Iyy, Izz) in kg m^2")
    try:
        items = list(value)
    except TypeError:
        items = None
    if items is None or len(items) != 3:
        raise ValidationError(f"{field} = {value!r}: expected three numbers (Ixx, Iyy, Izz) in kg m^2")
    moments = [INERTIA_RULE.check(v, f"{field}[{i}]") for i, v in enumerate(items)]
    for i in range(3):
        others = sum(moments) - moments[i]
        if moments[i] > others * (1 + 1e-12):
            raise ValidationError(f"{field} = {tuple(moments)} kg m^2 violates the triangle inequality: "
                                  f"{field}[{i}] = {_g(moments[i])} exceeds the sum of the other two, "
                                  f"{_g(others)} (no rigid body has these principal moments)")
    return tuple(moments)


def time_grid(duration, dt, exact: bool = True, duration_field: str = "duration", dt_field: str = "dt") -> int:
    """The number of steps of ``duration`` at ``dt``, checked before anything is allocated.

    Helper: the time grid (module docstring). ``dt`` within [DT_MIN, DT_MAX]; ``duration`` > 0,
    finite, at least one step and at most ``MAX_STEPS``; with ``exact`` a whole number of steps
    (within 1e-6 of a step: 1.0 / 1e-3 is 1000.0000000000001), else rounded to the nearest.
    """
    dt = RULES["dt"].check(dt, dt_field)
    if not is_number(duration):
        raise ValidationError(f"{duration_field} = {duration!r} is not a number (allowed: > 0 s)")
    duration = float(duration)
    if not (math.isfinite(duration) and duration > 0):
        raise ValidationError(f"{duration_field} = {_g(duration)} s: must be positive and finite (allowed: > 0 s)")
    steps = duration / dt
    n = round(steps)
    if steps > MAX_STEPS + 0.5:
        raise ValidationError(f"{duration_field} = {_g(duration)} s at {dt_field} = {_g(dt)} s is {steps:.4g} steps: "
                              f"at most {MAX_STEPS} steps per run ({STEPS_WHY}); shorten {duration_field} "
                              f"or lengthen {dt_field}")
    if n < 1:
        raise ValidationError(f"{duration_field} = {_g(duration)} s is shorter than one step of {dt_field} = "
                              f"{_g(dt)} s (allowed: {duration_field} >= {dt_field})")
    if exact and abs(steps - n) > 1e-6:
        lo, hi = math.floor(steps) * dt, math.ceil(steps) * dt
        options = " or ".join(f"{_g(round(v, 12))} s" for v in (lo, hi) if v > 0)
        raise ValidationError(f"{duration_field} = {_g(duration)} s is not a whole number of steps of {dt_field} = "
                              f"{_g(dt)} s ({steps:.4g} steps): use {duration_field} = {options}, or another "
                              f"{dt_field}")
    return int(n)


# ---------------------------------------------------------------------------------- the option table
_UNIT_IN_HELP = re.compile(r"\[([^\]]+)\]")


def _option_rows(parser) -> list[tuple]:
    """(option, unit, range or choices, default) of every option of ``parser``."""
    rows = []
    for action in parser._actions:
        if isinstance(action, argparse._HelpAction):
            continue
        name = ", ".join(action.option_strings) or action.metavar or action.dest
        rule_ = getattr(action.type, "rule", None)
        if isinstance(action, (argparse._StoreTrueAction, argparse._StoreFalseAction)):
            rows.append((name, "-", "flag", "off"))
            continue
        if rule_ is not None:
            unit, allowed = rule_.unit, rule_.range_text()
        elif action.choices is not None:
            unit, allowed = "-", ", ".join(map(str, action.choices))
        else:
            found = _UNIT_IN_HELP.search(action.help or "")
            unit = found.group(1) if found else "-"
            allowed = getattr(action.type, "allowed", None) or _describe_type(action)
        if action.required:
            default = "required"
        elif isinstance(action, argparse._AppendAction):
            allowed += " (repeatable)"
            default = "none" if not action.default else str(action.default)
        elif action.default is None:
            found = _DEFAULT_IN_HELP.search(action.help or "")
            default = found.group(1) if found else "-"
        else:
            default = _g(action.default) if is_number(action.default) else str(action.default)
        rows.append((name, unit if unit not in ("", "-") else "-", allowed, default))
    return rows


_DEFAULT_IN_HELP = re.compile(r"\(default:? ([^;)]+)")


def _describe_type(action) -> str:
    """What an option without a rule takes: a file, an integer, a finite number, text."""
    metavar = str(action.metavar or "")
    name = getattr(action.type, "__name__", "")
    if action.type is int:
        return "integer"
    if action.type is float:
        return "number"
    if name == "finite_float":
        return "finite number"
    if name == "pixels":
        return "whole number of pixels"
    if "FILE" in metavar.upper() or "." in metavar or action.dest in ("out", "json", "cache", "run"):
        return "file path"
    if metavar:
        return metavar
    return "text"


def options_markdown(parser=None) -> str:
    """The README's option table: every subcommand's options with unit, range or choices and
    default, from the rules behind each option's ``type=`` (markdown).

    Helper: the README block between the options markers (``tests/test_inputs.py`` checks it).
    """
    if parser is None:
        from ..cli import build_parser

        parser = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    lines = []
    for command, p in sub.choices.items():
        rows = _option_rows(p)
        lines.append(f"**`cobra-ref {command}`**" + ("" if rows else ": no options"))
        lines.append("")
        if rows:
            lines.append("| option | unit | allowed | default |")
            lines.append("|---|---|---|---|")
            for name, unit, allowed, default in rows:
                cells = (f"`{name}`", unit, allowed, default)
                lines.append("| " + " | ".join(c.replace("|", "\\|") for c in cells) + " |")
            lines.append("")
    return "\n".join(lines).rstrip() + "\n"


OPTIONS_BEGIN = "<!-- options: generated from cobra_ref's validation layer; do not edit by hand -->"
OPTIONS_END = "<!-- /options -->"


def readme_with_options(text: str, table: str | None = None) -> str:
    """``text`` (the README) with the block between the options markers replaced by the table.

    Helper: ``python -m cobra_ref.infra.validation README.md`` rewrites the README's option table.
    """
    table = options_markdown() if table is None else table
    start, end = text.index(OPTIONS_BEGIN) + len(OPTIONS_BEGIN), text.index(OPTIONS_END)
    return text[:start] + "\n\n" + table + "\n" + text[end:]


def readme_options_block(text: str) -> str:
    """What the README holds between the options markers (the table, stripped).

    Helper: the README check.
    """
    start, end = text.index(OPTIONS_BEGIN) + len(OPTIONS_BEGIN), text.index(OPTIONS_END)
    return text[start:end].strip() + "\n"


if __name__ == "__main__":  # python -m cobra_ref.infra.validation README.md
    import sys

    from .output import write_text

    for path in sys.argv[1:]:
        with open(path, encoding="utf-8") as f:
            write_text(path, readme_with_options(f.read()))
