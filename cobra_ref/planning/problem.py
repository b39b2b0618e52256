"""The single-shooting problem: decision vector, bounds, goal, the common initial state, one rollout.

Implements: [COBRA] sec. "Results": "We take the shooting method to find optimal u_ref for
minimized joint torques tau such that generalized contact forces f_ext stand orthogonal to gap
functions and their derivative" and "the goal is to move the box on the flat ground towards a
specified point" (Eq. (6) constraints (2), (3) as penalties).

The model every rollout runs (``ShootingProblem.settings``, a ``StepSettings``, and
``ShootingProblem.cobra``, a ``CobraParameters``; by default the figures' model): the compliant
contact law (spring-damper normal contact and smooth stick-slip friction, assumptions A12, A13),
the position servo (each joint driven towards its reference, its torque clamped at tau_max =
9.2 N m, ``compliance.servo_rows``) and dt = ``DEFAULT_DT`` (A14). ``make_problem`` also accepts
the rigid law and the prescribed servo (``StepSettings(servo="prescribed")``: the joints follow
the reference exactly and the torques are recovered, unbounded).

The problem (``ShootingProblem``)::

    p = a gait family's parameters (below), bounded: lower <= p <= upper
    one rollout: simulate(p) over [0, T] from the common initial state (below)
    J(p) = w_e * E + w_g * (d_T / d_0)^2 + w_I * I + w_tau * P_tau + w_q * P_q

    E     = 1 / (n tau_max^2 T) * integral ||tau||^2 dt        effort: mean squared joint torque
                                                               as a fraction of the stall torque^2
    d_T   = || p_box(T) - p_goal ||,  d_0 = || p_box(0) - p_goal ||   (horizontal, box centre)
    I     = sum over impacts of m v_a / (m_robot g T)          impacts (A26, A28): impact impulse
                                                               per second / the robot's weight
    P_tau = 1 / (tau_max T) * integral max(0, max_i |tau_i| - tau_max) dt    (tau_excess per step)
    P_q   = 1 / (q_max T)   * integral max(0, max_i |q_i| - q_max) dt        (q_excess per step)

Every term is dimensionless. I is the paper's condition that the "generalized contact forces
f_ext stand orthogonal to gap functions and their derivative": no contact force where a gap
closes with speed, i.e. no impacts (``cost.impact_term``; ``Weights`` gives the weight and why).
The limit penalties are exact (L1) penalties, linear in the excess (a squared penalty would
barely see a sustained small excess). With the position servo the joint torque is clamped at
tau_max at every step, so P_tau is zero by construction; it is kept for the prescribed servo,
whose recovered torques are unbounded. |q| <= amplitude <= q_max holds for the reference
(``gaits``), and the servo follows it with a lag, so P_q is zero unless a joint overshoots; it is
kept to see that. A rollout whose simulation fails costs ``FAILED_COST`` (and its history entry
names the error).

Decision vectors (``DECISION``; phase phi_0 and the ramp are fixed, see below):

    C, S:          amplitude [0.25, 0.75] rad, frequency [0.25, 1.0] Hz
    J, J-mirror:   amplitude, frequency, s_J [0.3, 0.8]   (the hook's length; the side is the gait)
    sidewinding:   amplitude_yaw, amplitude_pitch [0.4, 0.8] rad, frequency [0.3, 0.7] Hz

The initial guess is the gait's default (assumption A10), with phi_0 = 0 (the planar start shape).
Left out on purpose: the rolling phase phi_0 (a nonzero phi_0 starts from a twisted shape that
``initial_state`` turns onto its flattest side, so it mostly starts the same roll at another point
of the cycle), sidewinding's spatial frequency and delta (they change the shape and the direction
of travel). Sidewinding's bounds are narrow because its direction of travel also depends on
amplitude and frequency (docs/results.md, "Planner"), and the box is placed once, for the initial
guess.
The frequency stays <= 1 Hz so that the joint speed A omega <= 0.75 * 2 pi = 4.7 rad/s stays
near the servo's 3.77 rad/s (not penalised: the servo speed is not a constraint of Eq. (6)).
The phase-rate ramp is shortened to ``RAMP_TIME`` = 0.25 s (the gaits' default, one period,
would take most of a short horizon).

The common initial state (``start_state``): the box is placed once, by the rule of
``reproduce`` (5 cm from the middle link on the concave side of the initial guess's start shape;
for sidewinding 5 cm ahead of the band the initial guess's wave sweeps, in the direction it
travels, A31), and kept there for every rollout.
Each candidate starts at rest in its own t = 0 shape (the servo starts on its
reference), moved rigidly in the plane so that its middle (the midpoint of the centres of mass
of L5 and L6, and the heading from L6 to L5) is where the initial guess's middle is: the box
then faces the same link across the same gap whatever the amplitude.

The goal is given relative to the box's start: ``goal`` = (dx, dy) [m] in world axes (x = the
robot's initial heading, y = its left). It is rejected if not finite, shorter than 1 mm, or
unreachable: farther than ``MAX_BOX_SPEED`` * T (0.5 m/s; the fastest gait in the bounds, lateral
rolling at 1 Hz, rolls a link's circumference 2 pi r = 0.34 m per period) or than 5 m.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..gaits import GaitError, gait, gait_params
from ..infra import arguments
from ..infra.rule import Rule
from ..infra.validation import DEFAULT_DT, number_text
from ..kinematics import forward_kinematics
from ..params import CobraParameters
from ..quaternion import quat_mul
from ..robots import cobra_model
from ..batch import BatchRun
from ..simulate import LeftPhysicsWarning, check_start, simulate
from ..start import BoxPlacement, initial_state
from ..step import SimulationError, StepSettings
from ..trajectory import Trajectory

ROLLING_DECISION = (("amplitude", 0.25, 0.75), ("frequency", 0.25, 1.0))
DECISION = {  # gait -> ((parameter, lower, upper), ...)  (module docstring)
    "C": ROLLING_DECISION,
    "S": ROLLING_DECISION,
    "J": ROLLING_DECISION + (("s_J", 0.3, 0.8),),
    "J-mirror": ROLLING_DECISION + (("s_J", 0.3, 0.8),),
    "sidewinding": (("amplitude_yaw", 0.4, 0.8), ("amplitude_pitch", 0.4, 0.8), ("frequency", 0.3, 0.7)),
}
# gait -> (goal (dx, dy) [m], horizon T [s], maxiter) of ``optimize_gait`` and ``cobra-ref optimize``:
# the goal is about 1.5 times as far as the initial guess pushes the box in T, in the direction it pushes
# it, rounded to 1 cm; sidewinding's initial guess (its box ahead of the wave's band, A31) reaches the box
# only after 1.5 s, hence T = 3 s; maxiter 6 keeps ``regenerate.reoptimize`` within its budget
# (docs/planning.md, "The goals and horizons" and "Timings").
DEFAULTS = {"C": ((0.16, -0.03), 1.5, 6), "S": ((0.11, -0.21), 1.5, 6), "J": ((0.31, -0.05), 1.5, 6),
            "J-mirror": ((0.31, 0.05), 1.5, 6), "sidewinding": ((-0.19, -0.02), 3.0, 6)}
RAMP_TIME = 0.25  # [s] phase-rate ramp of every candidate (module docstring)
DEFAULT_DURATION = 1.5  # [s] horizon T (rolling gaits, see DEFAULTS)
DEFAULT_MAXITER = 6  # iterations (polls of the compass search, generations of DE)
MAX_BOX_SPEED = 0.5  # [m/s] reachability bound (module docstring)
MAX_GOAL_DISTANCE = 5.0  # [m]
MIN_GOAL_DISTANCE = 1e-3  # [m]
FAILED_COST = 1e3  # cost of a rollout whose simulation failed
HORIZON = Rule("duration", "s", 0.0, low_open=True)  # check_goal's duration; make_problem's: validation.step_count
FORMAT = "cobra-ref optimize v1"


class ShootingError(arguments.ArgumentError):
    """Bad input to the shooting problem or a malformed params JSON (the message says which)."""


@dataclass(frozen=True)
class Weights:
    """Weights of the cost terms (module docstring): J = effort E + goal (d_T/d_0)^2 + impacts I + penalties.

    The goal term dominates until the box is within about 10 % of the start distance
    (10 * 0.1^2 = 0.1, the size of the initial guesses' effort E); a sustained 10 % torque excess
    costs as much (P_tau = 0.1). The impact weight w_I = 100 makes an impact impulse rate at claim
    NI's threshold, 1 % of the robot's weight (I = 0.01), cost 1, ten times the initial guesses'
    effort and as much as the goal term with the box a third of its start distance away: the paper
    states the condition as a constraint ("such that"), and an exact penalty stands for a
    constraint only when its weight is large enough to decide between points that reach the goal
    about equally well. The initial guesses' terms and the choice of w_I: docs/planning.md, "What
    the planner minimizes".
    """

    effort: float = 1.0
    goal: float = 10.0
    impact: float = 100.0
    tau: float = 1.0
    q: float = 1.0

    def __post_init__(self):
        """Each weight by the rule of the params JSON (``RULES["weight"]``: finite, in [0, 1e6])."""
        for name in self.__dataclass_fields__:
            arguments.number(f"weights.{name}", getattr(self, name), "weight", ShootingError)


@dataclass(frozen=True)
class DecisionSpace:
    """What ``make_problem`` optimises and from where: ``names`` = the parameters to optimise
    (default: every bounded one; the other gait parameters stay at the initial guess), ``bounds``
    = {name: (lo, hi)} replacing or adding to ``DECISION[gait]``, ``x0`` = {name: value}
    overriding the initial guess (default: the gait's defaults, with phase 0 and ``ramp_time``),
    ``ramp_time`` [s] = the phase-rate ramp of every candidate."""

    names: tuple | None = None
    bounds: dict | None = None
    x0: dict | None = None
    ramp_time: float = RAMP_TIME

    def __post_init__(self):
        """Each field of its kind: ``names`` a sequence of names (one name alone is refused: a str is
        a sequence of letters), ``bounds`` and ``x0`` dicts, ``ramp_time`` by ``RULES["ramp_time"]``
        (the command line's --ramp-time)."""
        if isinstance(self.names, str):
            raise arguments.ArgumentTypeError(f"space.names = {self.names!r} is one str, not a sequence of names "
                                              f"(allowed: a tuple of names, e.g. ({self.names!r},))")
        for name in ("bounds", "x0"):
            arguments.instance(f"space.{name}", getattr(self, name), dict, "{'frequency': ...}", optional=True)
        arguments.number("space.ramp_time", self.ramp_time, "ramp_time", ShootingError)


@dataclass(frozen=True)
class ShootingProblem:
    """Everything a rollout needs, picklable: see the module docstring. Built by ``make_problem``
    (which checks the input) or ``results.problem_from_dict`` (JSON)."""

    gait: str
    goal: tuple  # (dx, dy) [m] from the box's start, world axes
    duration: float
    names: tuple  # decision parameters
    lower: tuple
    upper: tuple
    x0: tuple  # initial guess
    fixed: tuple  # ((name, value), ...) gait parameters held fixed (ramp_time, phase, ...)
    weights: Weights
    box_pose0: tuple  # (x, y, z, qw, qx, qy, qz) of the box at t = 0, the same for every rollout
    middle_pose0: tuple  # (x, y, heading) of the robot's middle at t = 0
    box_direction: tuple | None  # sidewinding: the direction the box was placed in
    settings: StepSettings  # time step, contact law and servo of every rollout
    cobra: CobraParameters  # the robot, the box and the ground of every rollout

    @property
    def dt(self) -> float:
        return self.settings.dt

    @property
    def goal_world(self) -> np.ndarray:
        return np.asarray(self.box_pose0[:2]) + np.asarray(self.goal)

    def params(self, x) -> dict:
        """The gait parameters of decision vector x (fixed ones included), as plain floats."""
        return {**dict(self.fixed), **{n: float(v) for n, v in zip(self.names, x)}}

    def reference(self, x):
        return gait(self.gait, **self.params(x))


def make_problem(gait_name: str, goal, duration: float = DEFAULT_DURATION, settings: StepSettings | None = None,
                 space: DecisionSpace = DecisionSpace(), weights: Weights = Weights(),
                 cobra: CobraParameters | None = None, box_gap: float = 0.05) -> ShootingProblem:
    """Check the input and build the problem: bounds, initial guess, the common box placement.

    The input side of the shooting method (module docstring). ``settings``: the rollouts' step
    settings (default ``StepSettings(dt=DEFAULT_DT)``: the compliant law and the position servo,
    whose joint torques are clamped at tau_max, so the torque limit holds at every step by
    construction; with the prescribed servo the joints follow the reference exactly and any
    torque above tau_max is penalised); ``space``: the decision vector (``DecisionSpace``);
    ``cobra``: the model's parameters (default ``CobraParameters()``); ``box_gap``: the gap between
    the box and the middle link at the start (``start.initial_state``, assumption A9: 5 cm).
    Checks every argument by the command line's rules (``infra.arguments``): an
    ``ArgumentTypeError`` (a TypeError) for an argument of the wrong type (settings that are not a
    StepSettings, weights that are not Weights, a duration that is not a number); a
    ``ShootingError`` (an ``ArgumentError``, a ValueError) for an unknown gait, a horizon of more
    than 10^6 steps (``validation.step_count``), a weight outside ``RULES["weight"]``, a box_gap
    outside ``RULES["box_gap"]``, a goal that is not two finite numbers or is unreachable, bounds
    that are empty or exclude the initial guess, or values the gait rejects. Sidewinding runs one box-free simulation
    (``placement.travel_placement``) to place the box.
    """
    arguments.choice("gait_name", gait_name, tuple(DECISION), ShootingError)
    settings = StepSettings(dt=DEFAULT_DT) if settings is None else settings
    arguments.instance("settings", settings, StepSettings, "StepSettings(dt=0.001)")
    cobra = CobraParameters() if cobra is None else cobra
    arguments.instance("cobra", cobra, CobraParameters, "CobraParameters()")
    arguments.instance("space", space, DecisionSpace, "DecisionSpace(names=('frequency',))")
    arguments.instance("weights", weights, Weights, "Weights(goal=10.0)")
    arguments.duration_steps(duration, settings.dt, error=ShootingError)  # the command line's step-count rule
    box_gap = arguments.number("box_gap", box_gap, "box_gap", ShootingError)
    goal = check_goal(goal, duration)
    names, lower, upper = _decision(gait_name, space.bounds, space.names)
    guess = _initial_guess(gait_name, names, lower, upper, space.x0, space.ramp_time)
    x_guess = tuple(guess.pop(n) for n in names)
    ref = gait(gait_name, **guess, **dict(zip(names, x_guess)))
    box_pose0, middle0, direction = _box_placement(gait_name, ref, settings, cobra, box_gap)
    return ShootingProblem(gait_name, goal, float(duration), names, lower, upper, x_guess,
                           tuple(sorted(guess.items())), weights, box_pose0, middle0, direction, settings, cobra)


def check_goal(goal, duration: float) -> tuple:
    """The goal as (dx, dy) floats, or a ShootingError: not two finite numbers, closer than 1 mm,
    or unreachable (farther than MAX_BOX_SPEED * duration or MAX_GOAL_DISTANCE): the goal's input
    check (module docstring). ``duration`` [s] finite and > 0 (``HORIZON``);
    a goal or duration that is not made of numbers: an ``infra.arguments.ArgumentTypeError``.
    """
    duration = arguments.number("duration", duration, HORIZON, ShootingError)
    g = arguments.numbers("goal", goal, 2, "goal", ("X", "Y"), ShootingError)
    d, reach = float(np.hypot(*g)), min(MAX_BOX_SPEED * duration, MAX_GOAL_DISTANCE)
    where, n = f"goal = ({number_text(g[0])}, {number_text(g[1])}) m", lambda x: number_text(float(f"{x:.3g}"))
    if d < MIN_GOAL_DISTANCE:
        raise ShootingError(f"{where} is where the box starts (closer than {n(MIN_GOAL_DISTANCE)} m)")
    if d > reach:
        raise ShootingError(f"{where} is unreachable: {n(d)} m from the box's start, but in "
                            f"{number_text(duration)} s the robot can push it at most {n(reach)} m "
                            f"({n(MAX_BOX_SPEED)} m/s, at most {n(MAX_GOAL_DISTANCE)} m); "
                            "use a closer goal or a longer duration")
    return g


def _decision(gait_name: str, bounds, decision) -> tuple:
    """names, lower, upper: DECISION[gait] updated by ``bounds`` = {name: (lo, hi)}, restricted to
    ``decision`` (names) if given."""
    table = {n: (lo, hi) for n, lo, hi in DECISION[gait_name]}
    for name, pair in (bounds or {}).items():
        try:
            lo, hi = (float(v) for v in pair)
        except (TypeError, ValueError):
            raise ShootingError(f"bounds for {name!r} must be two numbers (lo, hi), got {pair!r}") from None
        if not (np.isfinite(lo) and np.isfinite(hi) and lo < hi):
            raise ShootingError(f"bounds for {name!r} must be finite with lo < hi, got ({lo}, {hi})")
        table[str(name)] = (lo, hi)
    names = tuple(table) if decision is None else tuple(str(n) for n in decision)
    if not names or len(set(names)) != len(names):
        raise ShootingError(f"the decision vector must name distinct parameters, got {names}")
    missing = [n for n in names if n not in table]
    if missing:
        raise ShootingError(f"no bounds for decision parameter(s) {', '.join(missing)}: pass them in bounds")
    return names, tuple(table[n][0] for n in names), tuple(table[n][1] for n in names)


def _initial_guess(gait_name, names, lower, upper, x0, ramp_time) -> dict:
    """Every free gait parameter's initial value (defaults, phase 0, ramp_time, then x0), checked."""
    try:
        guess = gait_params(gait(gait_name, phase=0.0, ramp_time=float(ramp_time)))
        for k, v in (x0 or {}).items():
            guess[str(k)] = float(v)
        gait(gait_name, **guess)
        for n in names:
            if n not in guess:
                raise GaitError(f"{n!r} is not a parameter of gait {gait_name!r}; use {', '.join(guess)}")
        for corner in (lower, upper):  # the gait checks each parameter on an interval: corners suffice
            gait(gait_name, **{**guess, **dict(zip(names, corner))})
    except (GaitError, TypeError, ValueError) as exc:
        raise ShootingError(f"bad bounds or initial guess for gait {gait_name!r}: {exc}") from None
    for n, lo, hi in zip(names, lower, upper):
        if not lo <= guess[n] <= hi:
            raise ShootingError(f"the bounds exclude the initial guess: {n} = {guess[n]} is not in [{lo}, {hi}]")
    return {k: float(v) for k, v in guess.items()}


def _box_placement(gait_name: str, ref, settings: StepSettings, cobra: CobraParameters, box_gap: float):
    """The common box pose, the initial guess's middle pose and (sidewinding) the box direction."""
    direction = None
    if gait_name == "sidewinding":
        from ..placement import travel_placement

        try:
            placement = travel_placement(cobra_model(cobra, with_box=False), ref, settings.dt, box_gap, settings)
        except SimulationError as exc:
            raise ShootingError(f"cannot place the box for the initial guess: {exc}") from None
        direction, box_gap = placement.direction, placement.box_gap
    model = cobra_model(cobra)
    q0, _ = initial_state(model, ref, settings, BoxPlacement(gap=box_gap, direction=direction))
    box = model.q_idx[model.boxes[0].body]
    return tuple(float(v) for v in q0[box]), tuple(float(v) for v in middle_pose(model, q0)), direction


def middle_pose(model, q) -> np.ndarray:
    """(x, y, heading) of the robot's middle: the midpoint of the centres of mass of its two middle
    bodies (L5, L6 for COBRA) and the horizontal direction from the second to the first: the
    anchor of the common initial state (module docstring).
    """
    kin = forward_kinematics(model, q)
    robot = [i for i in range(model.nb) if all(b.body != i for b in model.boxes)]
    a, b = robot[len(robot) // 2 - 1], robot[len(robot) // 2]
    com_a, com_b = (kin.o[i] + kin.R[i] @ model.com[i] for i in (a, b))
    d = com_a - com_b
    return np.array([*(0.5 * (com_a + com_b))[:2], np.arctan2(d[1], d[0])])


def start_state(problem: ShootingProblem, x, model=None):
    """(q0, qd0) of the rollout of x: candidate x's start shape at rest, moved in the plane so that
    its middle is at ``problem.middle_pose0``; the box at ``problem.box_pose0`` (the common
    initial state, module docstring). ``model``: the problem's own (``cobra_model(problem.cobra)``,
    built if not given).
    """
    model = model or cobra_model(problem.cobra)
    q0, qd0 = _settled(problem, problem.reference(x), model)
    now, goal = middle_pose(model, q0), np.asarray(problem.middle_pose0)
    # planar rigid motion of the robot: p -> Rz(dpsi) (p - m_now) + m_goal, quat -> q_z(dpsi) * quat
    dpsi = goal[2] - now[2]
    c, s = np.cos(dpsi), np.sin(dpsi)
    base = model.q_idx[0].start
    rel = q0[base:base + 2] - now[:2]
    q0[base:base + 2] = goal[:2] + np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])
    q0[base + 3:base + 7] = quat_mul(np.array([np.cos(dpsi / 2), 0.0, 0.0, np.sin(dpsi / 2)]),
                                     q0[base + 3:base + 7])
    # the base's world linear velocity (what is left of the settling) turns with it
    v = model.v_idx[0].start
    qd0[v:v + 2] = [c * qd0[v] - s * qd0[v + 1], s * qd0[v] + c * qd0[v + 1]]
    box = model.q_idx[model.boxes[0].body]
    q0[box] = problem.box_pose0
    return q0, qd0


_SETTLED: dict = {}  # this process's settled starts (``_settled``), by everything they depend on
_SETTLED_MAX = 256


def _settled(problem: ShootingProblem, reference, model):
    """Copies of ``start.initial_state`` of the reference's t = 0 shape, settled once per process.

    The settled start depends on the reference only through its t = 0
    joint angles (the shape that is placed and held), so candidates that differ only in
    parameters that leave that shape alone (a compass poll along the frequency) start from the
    same numbers, computed once (bit for bit what a fresh settle gives; tests/test_shooting.py).
    """
    shape = np.asarray(reference(0.0)[0], dtype=float)
    key = (repr(problem.cobra), repr(problem.settings), problem.box_direction, shape.tobytes())
    if key not in _SETTLED:
        if len(_SETTLED) >= _SETTLED_MAX:
            _SETTLED.clear()
        _SETTLED[key] = initial_state(model, reference, problem.settings, BoxPlacement(direction=problem.box_direction))
    q0, qd0 = _SETTLED[key]
    return q0.copy(), qd0.copy()


def rollout(problem: ShootingProblem, x, progress=None) -> Trajectory:
    """One rollout: simulate candidate x over the horizon from the common initial state.

    Implements: the "shooting" of [COBRA] sec. "Results": one simulation per u_ref.
    ``x`` holds one finite number per decision parameter (``problem.names``), else a
    ``ShootingError`` (an ``ArgumentTypeError`` for values that are not numbers); raises
    ``SimulationError`` as ``simulate`` does.
    """
    arguments.instance("problem", problem, ShootingProblem, "make_problem('C', (0.1, 0.0))")
    x = arguments.numbers("x", x, len(problem.names), labels=problem.names, error=ShootingError)
    arguments.function("progress", progress, "a function progress(done, total)", optional=True)
    model = cobra_model(problem.cobra)
    q0, qd0 = start_state(problem, x, model)
    with warnings.catch_warnings():  # a rollout's excess torque is the cost's tau_limit term, not news
        warnings.simplefilter("ignore", LeftPhysicsWarning)
        return simulate(model, problem.reference(x), problem.duration, problem.settings, q0, qd0, progress)


def rollouts(problem: ShootingProblem, xs) -> list:
    """``rollout`` of each candidate in xs, advanced together as one batch (:mod:`cobra_ref.batch`:
    each the same steps, bit for bit, as its own ``rollout``): [(Trajectory or None, error)], the
    error what ``rollout``'s ``SimulationError`` says ("" for a rollout that did not fail; a failed
    one's trajectory ends where it failed, or is None if its start was refused)."""
    arguments.instance("problem", problem, ShootingProblem, "make_problem('C', (0.1, 0.0))")
    xs = [arguments.numbers("x", x, len(problem.names), labels=problem.names, error=ShootingError) for x in xs]
    model = cobra_model(problem.cobra)
    out, starts, members = [None] * len(xs), [], []
    for i, x in enumerate(xs):
        try:  # a start the simulation refuses fails this candidate alone, as in rollout
            start = start_state(problem, x, model)
            check_start(model, start[0])
        except SimulationError as exc:
            out[i] = (exc.trajectory, str(exc))
            continue
        starts.append(start)
        members.append(i)
    if members:
        n_steps = arguments.duration_steps(problem.duration, problem.dt)
        run = BatchRun(model, problem.settings, starts, n_steps)
        run.advance([problem.reference(xs[i]) for i in members], n_steps)
        for i, traj, message in zip(members, run.finish(), run.messages):
            out[i] = (traj, message)
    return out
