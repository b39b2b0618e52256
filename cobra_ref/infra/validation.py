"""The rules of every input of cobra_ref, each stated once, and the time grid.

``RULES`` holds the rule (:class:`cobra_ref.infra.rule.Rule`: name, type, finiteness, range,
unit) of every number a user gives: the command line's options (an option's ``type=`` is
``RULES[name].arg(option)``), the files read (reference files, params JSON) and the public API
(``StepSettings``). ``PARAMETER_RULES`` holds those of the model's numbers, checked by
``CobraParameters`` (``check_parameters``) and, for the numbers a ``Model`` carries by name
(``MODEL_NUMBERS``), by ``Model`` too; each range is bounded by what the rest of the code supports
(``n_body_links``: the gaits' 11 joints).

The time grid (``time_grid``) is checked as a whole before anything is allocated: a time step in
the range [DT_MIN, DT_MAX], a duration of at least one step, at most MAX_STEPS.

Why dt <= 5 ms (DT_MAX): the contact's damper and friction and the servo's damper are implicit in
the step, and the contact's and the servo's springs as far as their stability needs
(``compliance.contact_theta``, ``compliance.servo_theta``), so one contact or one joint is stable at
every dt; what a large step loses is accuracy. The compliant contact's damping time is
m / d = 0.5 kg / 1e3 N s/m = 0.5 ms; a 5 ms step averages over it but still resolves the gaits
(0.5 Hz: 400 steps per period). Above 5 ms C rolling's path parts from the one at 1 ms by many
centimetres and the robot sinks deeper into the ground (docs/results.md, "How large may the time
step be?").
Why dt >= 10 us (DT_MIN): the solver's absolute tolerance of 1e-7 N s on an impulse is a force
error of 1e-7 / dt, 0.01 N (0.2 % of a link's weight) at 10 us. Why at most 10^6 steps
(MAX_STEPS): a run records about 2 kB per step (states, torques, solver records, the contact
log): 10^6 steps are about 2 GB.
"""

from __future__ import annotations

import math

from .rule import PairRule, Rule, ValidationError, as_list, check_choice, is_number, number_text, value_text

__all__ = ["BYTES_PER_STEP", "DEFAULT_DT", "DT_MAX", "DT_MIN", "DT_WHY", "INERTIA_RULE", "MAX_STEPS", "MODEL_NUMBERS",
           "OPTIONAL_PARAMETERS", "PARAMETER_RULES", "RULES", "STEPS_WHY", "PairRule", "Rule", "ValidationError",
           "check", "check_choice", "check_inertia", "check_parameters", "check_pose", "is_number", "number_text", "rule",
           "step_count", "time_grid", "value_text"]

# ----------------------------------------------------------------------------------------- time grid
DEFAULT_DT = 1e-3  # [s] the time step of every run unless one is given (docs/assumptions.md A14)
DT_MIN = 1e-5  # [s] the QP's absolute tolerance 1e-7 N s is a force error of 1e-7 / dt: 0.01 N at 10 us
DT_MAX = 5e-3  # [s] (docs/assumptions.md A14; ``DT_WHY``)
MAX_STEPS = 1_000_000  # steps per run (see ``STEPS_WHY``)
BYTES_PER_STEP = 2_000  # [B] about, a run's record per step (states, torques, solver records, contact log)

DT_WHY = ("above 5 ms the runs part from those at 1 ms by many centimetres and sink deeper into the ground "
          "(the contact's damping time is m/d = 0.5 ms; docs/results.md); below 10 us the solver's tolerance "
          "1e-7 N s is a force error above 0.01 N")
STEPS_WHY = (f"a run records about {BYTES_PER_STEP // 1000} kB per step: 10^6 steps are about "
             f"{MAX_STEPS * BYTES_PER_STEP / 1e9:.0f} GB and an hour of computing")


# ------------------------------------------------------------------------------------------ the rules
MU_WHY = "a Coulomb coefficient; the paper's is 1.0 (A13); dry pairs above 2 are not these materials"

RULES = {
    # the time grid (time_grid checks them together)
    "dt": Rule("dt", "s", DT_MIN, DT_MAX, why=DT_WHY),
    "duration": Rule("duration", "s", 0.0, MAX_STEPS * DT_MAX, low_open=True,
                     why="at most 10^6 steps of the largest dt", note="a whole number of steps of dt, at most 10^6 steps"),
    "margin": Rule("margin", "m", 0.0, 1.0, why="the contact search margin (A16: 1 cm)"),
    "touchdown_substeps": Rule("touchdown_substeps", "-", 1, 16, kind="int",
                               why="the substeps of a step around a touch-down (A33; 1: whole steps)"),
    "timestep": Rule("timestep", "s", 1e-6, 2e-3,
                     why="MuJoCo's timestep; MuJoCo integrates the exported stiff contact explicitly, stable below "
                         "about 0.2 ms with the box (docs/mujoco.md, A27)"),
    # friction, the box and its placement
    "mu": Rule("mu", "-", 0.0, 2.0, why=MU_WHY),
    "mu_robot_box": Rule("mu_robot_box", "-", 0.0, 2.0, why=MU_WHY + "; A22: 0.5"),
    "mu_box_ground": Rule("mu_box_ground", "-", 0.0, 2.0, why=MU_WHY + "; A13: the same as mu"),
    "box_mass": Rule("box_mass", "kg", 1e-3, 100.0,
                     why="the paper's box is 0.5 kg; A8; at least 1 g, so that its inertia m a^2 / 6 is positive"),
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
    # the push planner
    "push_budget": Rule("budget", "s", 0.0, 600.0, low_open=True, why="simulated time of one push"),
    "push_period": Rule("period", "s", 0.1, 5.0, why="one re-plan per period; a rolling cycle at 0.5 Hz is 2 s"),
    "push_horizon": Rule("horizon", "-", 1, 5, kind="int", why="periods each rollout looks ahead"),
    "push_samples": Rule("samples", "-", 0, 64, kind="int", why="noisy copies of the last choice per re-plan"),
    "push_tolerance": Rule("tolerance", "m", 1e-3, 1.0, why="the box within this of the goal ends the push"),
    # the benchmark
    "horizon": Rule("duration", "s", 0.0, MAX_STEPS * DT_MAX, low_open=True,
                    why="at most 10^6 steps of the largest dt", note="at most 10^6 steps of dt"),
    "bench_duration": Rule("duration", "s", 0.0, 60.0, low_open=True, why="a benchmark of at most a minute",
                           note=f"a whole number of {DEFAULT_DT * 1e3:g} ms steps"),
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
# a cylinder of length L gets round(L / 2r) contact spheres (robots.cobra_model, A16): r >= 1 mm keeps them countable
_RADIUS = dict(unit="m", low=1e-3, high=1.0, why="a cylinder of length L gets L / 2r contact spheres (A16)")
PARAMETER_RULES = {
    "n_body_links": Rule("n_body_links", "-", 10, 10, kind="int",
                         why="body links between the head and the tail; the gaits, the reference files and the "
                             "figures are written for COBRA's 11 joints (gaits.N_JOINTS, A3)"),
    "mass_head": Rule("mass_head", **_MASS), "mass_link": Rule("mass_link", **_MASS),
    "mass_tail": Rule("mass_tail", **_MASS),
    "length_head": Rule("length_head", **_LENGTH), "length_link": Rule("length_link", **_LENGTH),
    "length_tail": Rule("length_tail", **_LENGTH),
    "radius_head": Rule("radius_head", **_RADIUS), "radius_link": Rule("radius_link", **_RADIUS),
    "radius_tail": Rule("radius_tail", **_RADIUS),
    "joint_gap": Rule("joint_gap", "m", 0.0, 1.0),
    "q_max": Rule("q_max", "rad", 0.0, math.pi, low_open=True, why="a revolute joint's range (A4: pi/2)"),
    "tau_max": Rule("tau_max", "N m", 0.0, 1e4, low_open=True, why="A5: 9.2 N m"),
    "qd_max": Rule("qd_max", "rad/s", 0.0, 1e4, low_open=True, why="A6: 3.77 rad/s"),
    "box_size": Rule("box_size", "m", 1e-3, 2.0, why="A8: a 0.10 m cube; at least 1 mm: its inertia is positive"),
    "box_mass": RULES["box_mass"],
    "servo_kp": Rule("servo_kp", "N m/rad", 0.0, 1e7, low_open=True, why="A7: 500 N m/rad"),
    "servo_kd": Rule("servo_kd", "N m s/rad", 0.0, 1e5, low_open=True, why="A7: 5 N m s/rad"),
    "gravity": Rule("gravity", "m/s^2", 0.0, 100.0, why="A20: 9.81 m/s^2"),
    "mu": RULES["mu"],
    "mu_robot_box": RULES["mu_robot_box"],
    "mu_box_ground": RULES["mu_box_ground"],
    "contact_stiffness": Rule("contact_stiffness", "N/m", 0.0, 1e10, low_open=True, why="A12: 1e6 N/m"),
    "contact_damping": Rule("contact_damping", "N s/m", 0.0, 1e8, low_open=True, why="A12: 1e3 N s/m"),
    "stiction_velocity": Rule("stiction_velocity", "m/s", 0.0, 1.0, low_open=True, why="A13: 1e-3 m/s"),
}
OPTIONAL_PARAMETERS = ("mu_box_ground",)  # None means "the same as mu"
# the numbers a Model carries by name: Model checks them by the same rules (model._validate)
MODEL_NUMBERS = ("mu", "mu_robot_box", "mu_box_ground", "contact_stiffness", "contact_damping", "stiction_velocity",
                 "servo_kp", "servo_kd")
INERTIA_RULE = Rule("inertia", "kg m^2", 0.0, 100.0, low_open=True)


def rule(name: str) -> Rule:
    """The rule called ``name`` (``RULES``)."""
    return RULES[name]


def check(name: str, value, field: str | None = None):
    """``RULES[name].check(value, field)``: the value, or a ``ValidationError``."""
    return RULES[name].check(value, field)


def check_parameters(params) -> None:
    """Check every field of a ``CobraParameters`` by ``PARAMETER_RULES``; the inertias (Ixx, Iyy, Izz)
    must be three positive principal moments that satisfy the triangle inequality
    (``CobraParameters.__post_init__`` calls it)."""
    from dataclasses import fields

    for f in fields(params):
        value = getattr(params, f.name)
        if f.name.startswith("inertia_"):
            check_inertia(f.name, value)
        elif f.name in PARAMETER_RULES and not (value is None and f.name in OPTIONAL_PARAMETERS):
            PARAMETER_RULES[f.name].check(value, f.name)


def check_inertia(field: str, value) -> tuple:
    """Three principal moments (Ixx, Iyy, Izz) [kg m^2], each > 0, and each at most the sum of the
    other two (a rigid body's triangle inequality); a ``ValidationError`` otherwise."""
    if isinstance(value, (str, bytes)):
        raise ValidationError(f"{field} = {value_text(value)}: expected three numbers (Ixx, Iyy, Izz) in kg m^2")
    items = as_list(value)
    if items is None or len(items) != 3:
        raise ValidationError(f"{field} = {value_text(value)}: expected three numbers (Ixx, Iyy, Izz) in kg m^2")
    moments = [INERTIA_RULE.check(v, f"{field}[{i}]") for i, v in enumerate(items)]
    for i in range(3):
        others = sum(moments) - moments[i]
        if moments[i] > others * (1 + 1e-12):
            raise ValidationError(f"{field} = {tuple(moments)} kg m^2 violates the triangle inequality: "
                                  f"{field}[{i}] = {number_text(moments[i])} exceeds the sum of the other two, "
                                  f"{number_text(others)} (no rigid body has these principal moments)")
    return tuple(moments)


def check_pose(field: str, value) -> tuple:
    """A free body's pose (x, y, z, qw, qx, qy, qz): seven finite numbers [m, -] whose quaternion
    has unit norm (within 1e-6, the tolerance of ``Model.check_q``); a ``ValidationError`` naming
    ``field`` otherwise."""
    items = None if isinstance(value, (str, bytes)) else as_list(value)
    if items is None or len(items) != 7 or not all(is_number(v) and math.isfinite(v) for v in items):
        raise ValidationError(f"{field}: expected 7 finite numbers (x, y, z in m; qw, qx, qy, qz, a unit "
                              f"quaternion), got {value_text(value)}")
    norm = math.sqrt(sum(float(v) ** 2 for v in items[3:]))
    if abs(norm - 1.0) > 1e-6:
        raise ValidationError(f"{field}: the quaternion (qw, qx, qy, qz) = ({', '.join(number_text(float(v)) for v in items[3:])}) "
                              f"has norm {number_text(norm)} (allowed: a unit quaternion, norm 1 within 1e-6)")
    return tuple(float(v) for v in items)


def time_grid(duration, dt, exact: bool = True, duration_field: str = "duration", dt_field: str = "dt") -> int:
    """The number of steps of ``duration`` at ``dt``, both checked before anything is allocated
    (module docstring): ``dt`` within [DT_MIN, DT_MAX], then ``step_count``; for a caller whose
    ``dt`` is not checked yet."""
    return step_count(duration, RULES["dt"].check(dt, dt_field), exact, duration_field, dt_field)


def step_count(duration, dt: float, exact: bool = True, duration_field: str = "duration",
               dt_field: str = "dt") -> int:
    """The number of steps of ``duration`` at a time step ``dt`` that is already checked (an
    option's rule, a ``StepSettings``): ``duration`` > 0, finite, at least one step and at most
    ``MAX_STEPS``; with ``exact`` a whole number of steps (within 1e-6 of a step: 1.0 / 1e-3 is
    1000.0000000000001), else rounded to the nearest. A ``ValidationError`` names ``duration_field``
    and ``dt_field`` otherwise.
    """
    g = number_text
    if not is_number(duration):
        raise ValidationError(f"{duration_field} = {value_text(duration)} is not a number (allowed: > 0 s)")
    duration = float(duration)
    if not (math.isfinite(duration) and duration > 0):
        raise ValidationError(f"{duration_field} = {g(duration)} s: must be positive and finite (allowed: > 0 s)")
    steps = duration / dt
    n = round(steps)
    if steps > MAX_STEPS + 0.5:
        raise ValidationError(f"{duration_field} = {g(duration)} s at {dt_field} = {g(dt)} s is {g(steps)} steps: "
                              f"at most {MAX_STEPS} steps per run ({STEPS_WHY}); shorten {duration_field} "
                              f"or lengthen {dt_field}")
    if n < 1:
        raise ValidationError(f"{duration_field} = {g(duration)} s is shorter than one step of {dt_field} = "
                              f"{g(dt)} s (allowed: {duration_field} >= {dt_field})")
    if exact and abs(steps - n) > 1e-6:
        lo, hi = math.floor(steps) * dt, math.ceil(steps) * dt
        options = " or ".join(f"{g(round(v, 12))} s" for v in (lo, hi) if v > 0)
        raise ValidationError(f"{duration_field} = {g(duration)} s is not a whole number of steps of {dt_field} = "
                              f"{g(dt)} s ({g(round(steps, 2))} steps): use {duration_field} = {options}, or another "
                              f"{dt_field}")
    return int(n)
