"""Single shooting: the gait parameters that push the box to a goal with the least joint torque.

Implements: [COBRA] sec. "Results": "We take the shooting method to find optimal u_ref for
minimized joint torques tau such that generalized contact forces f_ext stand orthogonal to gap
functions and their derivative" and "the goal is to move the box on the flat ground towards a
specified point" (DESIGN.md sec. 5; Eq. (6) constraints (2), (3) as penalties).

The problem (``ShootingProblem``)::

    p = a gait family's parameters (below), bounded: lower <= p <= upper
    one rollout: simulate(p) over [0, T] from the common initial state (below)
    J(p) = w_e * E + w_g * (d_T / d_0)^2 + w_tau * P_tau + w_q * P_q

    E     = 1 / (n tau_max^2 T) * integral ||tau||^2 dt        effort: mean squared joint torque
                                                               as a fraction of the stall torque^2
    d_T   = || p_box(T) - p_goal ||,  d_0 = || p_box(0) - p_goal ||   (horizontal, box centre)
    P_tau = 1 / (tau_max T) * integral max(0, max_i |tau_i| - tau_max) dt    (tau_excess per step)
    P_q   = 1 / (q_max T)   * integral max(0, max_i |q_i| - q_max) dt        (q_excess per step)

Every term is dimensionless. The limit penalties are exact (L1) penalties, linear in the excess:
with the prescribed servo the joint torques of an impact step reach 5-10 tau_max for one step
(the impulse that the prescribed joints must absorb, see ``stepper``), and a squared penalty
would let those few steps dominate while barely seeing a sustained small excess. With
prescribed joints |q| <= amplitude <= q_max by construction (``gaits``), so P_q is zero unless
the PD servo is used; it is kept for completeness. A rollout whose simulation fails costs
``FAILED_COST`` (and its history entry names the error).

Decision vectors (``DECISION``; phase phi_0 and the ramp are fixed, see below):

    C, S:          amplitude [0.25, 0.75] rad, frequency [0.25, 1.0] Hz
    J, J-mirror:   amplitude, frequency, s_J [0.3, 0.8]   (the hook's length; the side is the gait)
    sidewinding:   amplitude_yaw, amplitude_pitch [0.4, 0.8] rad, frequency [0.3, 0.7] Hz

The initial guess is the gait's default (notes C10), with phi_0 = 0 (the planar start shape).
Left out on purpose: the rolling phase phi_0 (a nonzero phi_0 starts from a twisted shape that
``initial_state`` turns onto its flattest side, so it mostly starts the same roll at another point
of the cycle; not measured), sidewinding's spatial frequency and delta (they change the shape and
the direction of travel). Sidewinding's bounds are narrow because its direction of travel also
depends on amplitude and frequency (measured: at 1 Hz the robot travels 2.5 m in 3 s and misses
the box placed for 0.5 Hz), and the box is placed once, for the initial guess.
The frequency stays <= 1 Hz so that the joint speed A omega <= 0.75 * 2 pi = 4.7 rad/s stays
near the servo's 3.77 rad/s (not penalised: the servo speed is not a constraint of Eq. (6)).
The phase-rate ramp is shortened to ``RAMP_TIME`` = 0.25 s (the gaits' default, one period,
would take most of a short horizon).

The common initial state (``start_state``): the box is placed once, by the rule of
``reproduce`` (5 cm from the middle link on the concave side of the initial guess's start shape;
for sidewinding in the direction the initial guess travels), and kept there for every rollout.
Each candidate starts at rest in its own t = 0 shape (the prescribed joints must start on their
reference), moved rigidly in the plane so that its middle (the midpoint of the centres of mass
of L5 and L6, and the heading from L6 to L5) is where the initial guess's middle is: the box
then faces the same link across the same gap whatever the amplitude.

The goal is given relative to the box's start: ``goal`` = (dx, dy) [m] in world axes (x = the
robot's initial heading, y = its left). It is rejected if not finite, shorter than 1 mm, or
unreachable: farther than ``MAX_BOX_SPEED`` * T (0.5 m/s; the fastest gait in the bounds, lateral
rolling at 1 Hz, rolls a link's circumference 2 pi r = 0.34 m per period) or than 5 m.

The optimizer (``optimize``): a parallel compass search by default (``method="pattern"``),
scipy's differential evolution on request (``method="de"``). See ``optimize`` for why.
"""

from __future__ import annotations

import json
import os
import sys
import time
from concurrent.futures import Executor, Future, ProcessPoolExecutor
from dataclasses import asdict, dataclass, field

import numpy as np

from .atomic import atomic_write
from .gaits import GaitError, gait, gait_params
from .kinematics import forward_kinematics
from .parallel import worker_init
from .params import CobraParameters
from .quaternion import quat_mul
from .robots import cobra_model
from .simulate import Trajectory, initial_state, simulate
from .stepper import SimulationError, StepSettings

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
# it (measured: C (0.13, -0.07), S (0.12, -0.11), J (0.22, -0.02), J-mirror (0.20, 0.02) in 1.5 s;
# sidewinding (-0.10, -0.07) in 3 s: it reaches the box only after about 2.5 s, hence its longer T).
# Measured on the shared 2-core machine: C 163 s (22 rollouts), sidewinding 79 s at maxiter 4.
DEFAULTS = {"C": ((0.2, -0.1), 1.5, 6), "S": ((0.17, -0.16), 1.5, 6), "J": ((0.3, -0.02), 1.5, 6),
            "J-mirror": ((0.3, 0.02), 1.5, 6), "sidewinding": ((-0.15, -0.1), 3.0, 6)}
RAMP_TIME = 0.25  # [s] phase-rate ramp of every candidate (module docstring)
DEFAULT_DURATION = 1.5  # [s] horizon T (rolling gaits, see DEFAULTS)
DEFAULT_MAXITER = 6  # iterations (polls of the compass search, generations of DE)
MAX_BOX_SPEED = 0.5  # [m/s] reachability bound (module docstring)
MAX_GOAL_DISTANCE = 5.0  # [m]
MIN_GOAL_DISTANCE = 1e-3  # [m]
FAILED_COST = 1e3  # cost of a rollout whose simulation failed
FORMAT = "cobra-ref optimize v1"


class ShootingError(ValueError):
    """Bad input to the shooting problem or a malformed params JSON (the message says which)."""


@dataclass(frozen=True)
class Weights:
    """Weights of the cost terms (module docstring): J = effort E + goal (d_T/d_0)^2 + penalties.

    Helper: the defaults make the goal term dominate until the box is within about 10 % of the
    start distance (10 * 0.1^2 = 0.1, the effort E of the default rolling gaits is 0.09-0.13);
    a sustained 10 % torque excess costs as much (P_tau = 0.1).
    """

    effort: float = 1.0
    goal: float = 10.0
    tau: float = 1.0
    q: float = 1.0


@dataclass(frozen=True)
class ShootingProblem:
    """Everything a rollout needs, picklable (plain numbers and tuples): see the module docstring.

    Helper: built by ``make_problem`` (which checks the input) or ``problem_from_dict`` (JSON).
    """

    gait: str
    goal: tuple  # (dx, dy) [m] from the box's start, world axes
    duration: float
    dt: float
    names: tuple  # decision parameters
    lower: tuple
    upper: tuple
    x0: tuple  # initial guess
    fixed: tuple  # ((name, value), ...) gait parameters held fixed (ramp_time, phase, ...)
    weights: Weights
    box_pose0: tuple  # (x, y, z, qw, qx, qy, qz) of the box at t = 0, the same for every rollout
    middle_pose0: tuple  # (x, y, heading) of the robot's middle at t = 0
    box_direction: tuple | None  # sidewinding: the direction the box was placed in
    cobra: tuple = field(default=())  # ((name, value), ...) of CobraParameters
    servo: str = "prescribed"  # the joint servo of every rollout (StepSettings.servo)

    @property
    def goal_world(self) -> np.ndarray:
        return np.asarray(self.box_pose0[:2]) + np.asarray(self.goal)

    def params(self, x) -> dict:
        """The gait parameters of decision vector x (fixed ones included), as plain floats."""
        return {**dict(self.fixed), **{n: float(v) for n, v in zip(self.names, x)}}

    def reference(self, x):
        return gait(self.gait, **self.params(x))

    def settings(self) -> StepSettings:
        return StepSettings(dt=self.dt, servo=self.servo)

    def cobra_parameters(self) -> CobraParameters:
        return CobraParameters(**{k: tuple(v) if isinstance(v, list) else v for k, v in self.cobra})


def make_problem(gait_name: str, goal, duration: float = DEFAULT_DURATION, dt: float = 1e-3, bounds=None,
                 x0=None, decision=None, ramp_time: float = RAMP_TIME, weights: Weights = Weights(),
                 cobra: CobraParameters | None = None, box_gap: float = 0.05,
                 servo: str = "prescribed") -> ShootingProblem:
    """Check the input and build the problem: bounds, initial guess, the common box placement.

    Helper: the input side of the shooting method (module docstring). ``bounds`` = {name: (lo, hi)}
    replaces or adds bounds (default ``DECISION[gait]``); ``decision`` = the names to optimise
    (default: every bounded one), the other gait parameters stay at the initial guess;
    ``x0`` = {name: value} overrides the initial guess (default: the gait's defaults, with
    phase 0 and ``ramp_time``); ``box_gap`` = the gap between the box and the middle link at the
    start (``simulate.initial_state``, assumption C9: 5 cm); ``servo`` = "prescribed" (the paper's
    "motion provided": joints follow the reference exactly, torques recovered, impact spikes above
    tau_max reported and penalised) or "pd" (torques saturated at tau_max, so the torque limit holds
    at every step by construction; the joints then lag the reference). Raises ``ShootingError`` for an
    unknown gait, a goal that is not two finite numbers or is unreachable, bounds that are empty
    or exclude the initial guess, or values the gait rejects. Sidewinding runs one box-free simulation
    (``reproduce.travel_direction``) to place the box.
    """
    if gait_name not in DECISION:
        raise ShootingError(f"unknown gait {gait_name!r}; gaits: {', '.join(DECISION)}")
    if servo not in ("prescribed", "pd"):
        raise ShootingError(f"servo must be 'prescribed' or 'pd', got {servo!r}")
    if not (np.isfinite(duration) and duration > 0):
        raise ShootingError(f"duration must be positive and finite, got {duration}")
    if not (np.isfinite(dt) and 0 < dt <= duration):
        raise ShootingError(f"dt must be positive, finite and <= duration, got {dt}")
    goal = check_goal(goal, duration)
    names, lower, upper = _decision(gait_name, bounds, decision)
    guess = _initial_guess(gait_name, names, lower, upper, x0, ramp_time)
    x_guess = tuple(guess.pop(n) for n in names)
    cobra = cobra or CobraParameters()
    ref = gait(gait_name, **guess, **dict(zip(names, x_guess)))
    if not (np.isfinite(box_gap) and box_gap >= 0):
        raise ShootingError(f"box_gap must be finite and >= 0, got {box_gap}")
    box_pose0, middle0, direction = _box_placement(gait_name, ref, duration, dt, cobra, box_gap)
    return ShootingProblem(gait_name, goal, float(duration), float(dt), names, lower, upper, x_guess,
                           tuple(sorted(guess.items())), weights, box_pose0, middle0, direction,
                           tuple(asdict(cobra).items()), servo)


def check_goal(goal, duration: float) -> tuple:
    """The goal as (dx, dy) floats, or a ShootingError: not two finite numbers, closer than 1 mm,
    or unreachable (farther than MAX_BOX_SPEED * duration or MAX_GOAL_DISTANCE).

    Helper: the goal's input check (module docstring).
    """
    try:
        g = np.asarray(goal, dtype=float).reshape(-1)
    except (TypeError, ValueError):
        raise ShootingError(f"goal must be two numbers (dx, dy) in metres, got {goal!r}") from None
    if g.shape != (2,) or not np.all(np.isfinite(g)):
        raise ShootingError(f"goal must be two finite numbers (dx, dy) in metres, got {goal!r}")
    d, reach = float(np.hypot(*g)), min(MAX_BOX_SPEED * duration, MAX_GOAL_DISTANCE)
    if d < MIN_GOAL_DISTANCE:
        raise ShootingError(f"goal {tuple(g)} is where the box starts (closer than {MIN_GOAL_DISTANCE} m)")
    if d > reach:
        raise ShootingError(f"goal {tuple(g)} is unreachable: {d:.3f} m from the box's start, but in "
                            f"{duration} s the robot can push it at most {reach:.3f} m "
                            f"({MAX_BOX_SPEED} m/s, at most {MAX_GOAL_DISTANCE} m); "
                            "use a closer goal or a longer --duration")
    return float(g[0]), float(g[1])


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


def _box_placement(gait_name, ref, duration, dt, cobra, box_gap):
    """The common box pose, the initial guess's middle pose and (sidewinding) the box direction."""
    direction = None
    if gait_name == "sidewinding":
        from .reproduce import RunSpec, travel_direction

        spec = RunSpec(gait_name, duration=max(duration, 2.0 / ref.frequency), dt=dt, params=gait_params(ref))
        try:
            direction = tuple(float(v) for v in travel_direction(spec))
        except SimulationError as exc:
            raise ShootingError(f"cannot place the box for the initial guess: {exc}") from None
    model = cobra_model(cobra)
    q0, _ = initial_state(model, ref, box_gap=box_gap, box_direction=direction)
    box = model.q_idx[model.boxes[0].body]
    return tuple(float(v) for v in q0[box]), tuple(float(v) for v in middle_pose(model, q0)), direction


def middle_pose(model, q) -> np.ndarray:
    """(x, y, heading) of the robot's middle: the midpoint of the centres of mass of its two middle
    bodies (L5, L6 for COBRA) and the horizontal direction from the second to the first.

    Helper: the anchor of the common initial state (module docstring).
    """
    kin = forward_kinematics(model, q)
    robot = [i for i in range(model.nb) if all(b.body != i for b in model.boxes)]
    a, b = robot[len(robot) // 2 - 1], robot[len(robot) // 2]
    com_a, com_b = (kin.p[i] + kin.R[i] @ model.com[i] for i in (a, b))
    d = com_a - com_b
    return np.array([*(0.5 * (com_a + com_b))[:2], np.arctan2(d[1], d[0])])


def start_state(problem: ShootingProblem, x, model=None):
    """(q0, qd0) of the rollout of x: candidate x's start shape at rest, moved in the plane so that
    its middle is at ``problem.middle_pose0``; the box at ``problem.box_pose0``.

    Helper: the common initial state (module docstring).
    """
    model = model or cobra_model(problem.cobra_parameters())
    q0, qd0 = initial_state(model, problem.reference(x), box_direction=problem.box_direction)
    now, goal = middle_pose(model, q0), np.asarray(problem.middle_pose0)
    # planar rigid motion of the robot: p -> Rz(dpsi) (p - m_now) + m_goal, quat -> q_z(dpsi) * quat
    dpsi = goal[2] - now[2]
    c, s = np.cos(dpsi), np.sin(dpsi)
    base = model.q_idx[0].start
    rel = q0[base:base + 2] - now[:2]
    q0[base:base + 2] = goal[:2] + np.array([c * rel[0] - s * rel[1], s * rel[0] + c * rel[1]])
    q0[base + 3:base + 7] = quat_mul(np.array([np.cos(dpsi / 2), 0.0, 0.0, np.sin(dpsi / 2)]),
                                     q0[base + 3:base + 7])
    box = model.q_idx[model.boxes[0].body]
    q0[box] = problem.box_pose0
    return q0, qd0


def rollout(problem: ShootingProblem, x, progress=None) -> Trajectory:
    """One rollout: simulate candidate x over the horizon from the common initial state.

    Implements: the "shooting" of [COBRA] sec. "Results": one simulation per u_ref.
    Raises ``SimulationError`` as ``simulate`` does.
    """
    model = cobra_model(problem.cobra_parameters())
    q0, qd0 = start_state(problem, x, model)
    return simulate(model, problem.reference(x), problem.duration, problem.settings(), q0, qd0, progress)


def shooting_cost(problem: ShootingProblem, traj: Trajectory) -> dict:
    """The cost J of a rollout and its terms (module docstring).

    Implements: DESIGN.md sec. 5 cost, [COBRA] Eq. (6) constraints (2), (3) as exact penalties::

        J = w_e E + w_g (d_T / d_0)^2 + w_tau P_tau + w_q P_q
    """
    cp, w, T, dt = problem.cobra_parameters(), problem.weights, problem.duration, traj.dt
    # E = integral ||tau||^2 dt / (n tau_max^2 T)
    effort = dt * float(np.sum(traj.tau**2)) / (traj.tau.shape[1] * cp.tau_max**2 * T)
    # d_T = |p_box(T) - p_goal|, d_0 = |goal|
    d_T = float(np.linalg.norm(traj.box_pose[-1, :2] - problem.goal_world))
    goal = (d_T / float(np.hypot(*problem.goal))) ** 2
    # P = integral max(0, excess) dt / (limit T), excess = max_i |.| - limit per step
    p_tau = dt * float(np.sum(np.maximum(traj.steps["tau_excess"], 0.0))) / (cp.tau_max * T)
    p_q = dt * float(np.sum(np.maximum(traj.steps["q_excess"], 0.0))) / (cp.q_max * T)
    cost = w.effort * effort + w.goal * goal + w.tau * p_tau + w.q * p_q
    return {"cost": cost, "box_distance_to_goal": d_T,
            "terms": {"effort": effort, "goal": goal, "tau_limit": p_tau, "q_limit": p_q}}


def contact_report(traj: Trajectory, tau_max: float) -> dict:
    """How well every step's contact impulses met the QP's conditions, and the limits' record.

    Implements: the paper's "f_ext orthogonal to the gap functions and their derivative": the
    KKT conditions of eq. (6) per step (``contact_qp.kkt_residuals``): complementarity
    max_i |p_N,i w_N,i| [N s m/s] and the relative friction-cone violation, maxima over the
    rollout; plus the torque and joint-limit excess (``tau_excess``, ``q_excess``).
    """
    s = traj.steps
    n = max(len(traj.tau), 1)
    return {"max_complementarity": float(np.max(s["complementarity"], initial=0.0)),
            "max_cone_residual": float(np.max(s["cone_residual"], initial=0.0)),
            "max_penetration": float(np.max(s["max_penetration"], initial=0.0)),
            "steps_not_solved": int(np.sum(s["osqp_status"] != 1)),
            "max_tau_excess": float(np.max(s["tau_excess"], initial=-np.inf)),
            "steps_over_tau_max": int(np.sum(s["tau_excess"] > 0)),
            "fraction_over_tau_max": float(np.sum(s["tau_excess"] > 0)) / n,
            "rms_tau_over_tau_max": float(np.sqrt(np.mean(traj.tau**2))) / tau_max if len(traj.tau) else 0.0,
            "max_q_excess": float(np.max(s["q_excess"], initial=-np.inf))}


def evaluate(problem: ShootingProblem, x) -> dict:
    """One rollout's history entry: params, cost, box_distance_to_goal, the cost terms, the final
    box position, the contact and limit report, and the error if the simulation failed.

    Helper: what the executor runs (a module-level function: picklable for a process pool).
    """
    entry = {"params": {n: float(v) for n, v in zip(problem.names, x)}, "error": None}
    try:
        traj = rollout(problem, x)
    except SimulationError as exc:
        traj = exc.trajectory
        entry["error"] = str(exc)
    if traj is None or entry["error"]:
        entry.update(cost=FAILED_COST, box_distance_to_goal=None, terms=None)
    else:
        entry.update(shooting_cost(problem, traj))
    if traj is not None:
        entry["box_final"] = [float(v) for v in traj.box_pose[-1, :2]]
        entry["contact"] = contact_report(traj, problem.cobra_parameters().tau_max)
    return entry


class SerialExecutor(Executor):
    """An Executor that runs each call at once in this process (tests, debugging, a single core).

    Helper: same results as a process pool, one rollout at a time.
    """

    def submit(self, fn, /, *args, **kwargs):
        future = Future()
        try:
            future.set_result(fn(*args, **kwargs))
        except Exception as exc:  # KeyboardInterrupt is not caught: it stops the caller
            future.set_exception(exc)
        return future


def default_executor(workers: int | None = None) -> ProcessPoolExecutor:
    """A process pool on the local cores (``os.cpu_count()`` workers), one BLAS thread per worker,
    ignoring Ctrl-C (``optimize`` ends them).

    Helper: the default executor of ``optimize``.
    """
    return ProcessPoolExecutor(max_workers=workers or os.cpu_count() or 1, initializer=worker_init)


@dataclass
class ShootingResult:
    """The outcome of ``optimize``: the best rollout, every rollout, and how the run ended.

    Helper: written to JSON by ``result_to_dict`` / ``write_result``.
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

    @property
    def params(self) -> dict:
        """The full gait parameters of the optimum (``gait(problem.gait, **params)`` rebuilds it)."""
        x = [self.best["params"][n] for n in self.problem.names]
        return gait_params(self.problem.reference(x))


class _Evaluations:
    """Runs batches of rollouts on the executor, keeps the history and prints a line per batch."""

    def __init__(self, problem: ShootingProblem, executor: Executor, progress, maxiter: int):
        self.problem, self.executor, self.progress, self.maxiter = problem, executor, progress, maxiter
        self.history: list = []
        self.iteration, self.start = 0, time.perf_counter()

    def best(self) -> dict | None:
        return min(self.history, key=lambda e: e["cost"]) if self.history else None

    def __call__(self, xs) -> list:
        """Evaluate the batch xs in parallel; return the costs in order (a Ctrl-C keeps what finished)."""
        futures, done = [], []
        try:
            for x in xs:
                futures.append(self.executor.submit(evaluate, self.problem, np.asarray(x, dtype=float)))
            for f in futures:
                done.append(f.result())
        except KeyboardInterrupt:
            for f in futures:
                f.cancel()
            self._record([f.result() for f in futures if f.done() and not f.cancelled() and f.exception() is None])
            raise
        self._record(done)
        return [e["cost"] for e in done]

    def _record(self, entries) -> None:
        if not entries:
            return
        for e in entries:
            self.history.append({"rollout": len(self.history), "iteration": self.iteration, **e})
        if self.progress:
            self.progress(self._line(entries))
        self.iteration += 1

    def _line(self, entries) -> str:
        it, b, best = self.iteration, min(entries, key=lambda e: e["cost"]), self.best()
        return (f"iteration {it:>2}/{self.maxiter}: {len(entries)} rollouts, cost {b['cost']:.5g}, box to goal "
                f"{_distance_text(b)}; best so far {best['cost']:.5g} ({_distance_text(best)}), "
                f"{len(self.history)} rollouts, {time.perf_counter() - self.start:.0f} s")


def _distance_text(entry: dict) -> str:
    d = entry["box_distance_to_goal"]
    return "simulation failed" if d is None else f"{d:.4f} m"


def optimize(problem: ShootingProblem, method: str = "pattern", maxiter: int = DEFAULT_MAXITER,
             executor: Executor | None = None, seed: int = 0, progress=None, step: float = 0.25,
             min_step: float = 1 / 64, popsize: int = 2, workers: int | None = None) -> ShootingResult:
    """Minimise J(p) over the bounds from ``problem.x0``; every rollout goes through ``executor``.

    Implements: the single-shooting optimizer of DESIGN.md sec. 5 (derivative-free, bounded,
    deterministic).

    ``method="pattern"`` (default): a parallel compass search (Kolda, Lewis, Torczon 2003, "Optimization
    by direct search", sec. 3) in the box scaled to [0, 1]^n: each iteration polls the 2n points
    x +- step e_i (clipped to the bounds) in one parallel batch, moves to the best if it lowers J,
    else halves ``step``; it stops after ``maxiter`` polls or when step < ``min_step``. Why this
    default: a 1.5 s rollout costs 5-15 s on the 2-core machine, so the 5-minute budget buys a few
    dozen rollouts; the compass search starts from the known-good default gait, needs no gradient
    (J is non-smooth through the contacts), uses the 2n independent polls to fill the cores, never
    re-runs a point, and makes progress within a few dozen rollouts (C: cost 1.30 -> 0.17, box
    0.077 -> 0.015 m from the goal in 22 rollouts). It has no randomness (``seed`` is recorded only).
    ``method="de"``: ``scipy.optimize.differential_evolution`` (best1bin, Latin hypercube start
    with x0 as its first member, ``popsize`` * n members, ``updating="deferred"``, ``polish=False``,
    ``rng=seed``), whose ``workers`` map is our executor: a global search for users with an
    executor bigger than one machine (for example Dask's ``Client.get_executor()``).

    ``executor``: any ``concurrent.futures.Executor`` whose workers can import cobra_ref; default
    ``default_executor(workers)``, a process pool on the local cores, shut down at the end.
    ``progress``: a callable taking one line of text per iteration (the CLI prints it on stderr).
    Ctrl-C (KeyboardInterrupt) stops the search and returns the best rollout found so far with
    ``interrupted=True``. The result is the same for any executor (the rollouts are deterministic
    and each batch is collected in order).
    """
    if method not in ("pattern", "de"):
        raise ShootingError(f"method must be 'pattern' or 'de', got {method!r}")
    if int(maxiter) != maxiter or maxiter < 0:
        raise ShootingError(f"maxiter must be a non-negative integer, got {maxiter}")
    own = executor is None
    executor = default_executor(workers) if own else executor
    evals = _Evaluations(problem, executor, progress, maxiter)
    interrupted, message, options = False, "", {"step": step, "min_step": min_step, "popsize": popsize}
    try:
        search = _compass_search if method == "pattern" else _differential_evolution
        message = search(problem, evals, maxiter, seed=seed, **options)
    except KeyboardInterrupt:
        interrupted, message = True, "interrupted (Ctrl-C): the best rollout so far is kept"
    finally:
        if own:
            _shutdown(executor, interrupted)
    if not evals.history:
        raise ShootingError("interrupted before any rollout finished: nothing to keep")
    return ShootingResult(problem, method, seed, int(maxiter), options, evals.history, evals.best(),
                          max(evals.iteration - 1, 0), interrupted, message, time.perf_counter() - evals.start)


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


def _compass_search(problem, evals, maxiter, seed, step, min_step, popsize) -> str:
    """``compass_search`` on the shooting problem (see ``optimize``); returns why it stopped."""
    return compass_search(evals, problem.x0, problem.lower, problem.upper, maxiter, step, min_step)[2]


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


def _differential_evolution(problem, evals, maxiter, seed, step, min_step, popsize) -> str:
    """``differential_evolution_search`` on the shooting problem (see ``optimize``)."""
    return differential_evolution_search(evals, problem.x0, problem.lower, problem.upper, maxiter, seed, popsize)[2]


def _not_called(x):
    """The objective handed to scipy; the rollouts run through the workers map instead."""
    raise RuntimeError("the shooting objective is evaluated through the executor map")


def _shutdown(executor: Executor, interrupted: bool) -> None:
    """Shut down our own pool; after Ctrl-C, end its worker processes (they ignore SIGINT) at once."""
    if interrupted:
        # the pool's own worker processes (a private attribute of ProcessPoolExecutor)
        workers = dict(getattr(executor, "_processes", None) or {})
        executor.shutdown(wait=False, cancel_futures=True)
        for process in workers.values():
            process.terminate()
    else:
        executor.shutdown(wait=True)


# --- JSON: the params file ------------------------------------------------------------------------


def problem_to_dict(problem: ShootingProblem) -> dict:
    """The problem as JSON-ready settings (every input of a rollout).

    Helper: the ``settings`` part of the params JSON.
    """
    return {"gait": problem.gait, "goal": list(problem.goal), "goal_world": [float(v) for v in problem.goal_world],
            "duration": problem.duration, "dt": problem.dt, "step_settings": asdict(problem.settings()),
            "decision": {"names": list(problem.names), "lower": list(problem.lower), "upper": list(problem.upper),
                         "x0": list(problem.x0)},
            "fixed": dict(problem.fixed), "weights": asdict(problem.weights),
            "box_pose0": list(problem.box_pose0), "middle_pose0": list(problem.middle_pose0),
            "box_direction": None if problem.box_direction is None else list(problem.box_direction),
            "cobra_parameters": {k: list(v) if isinstance(v, tuple) else v for k, v in problem.cobra},
            "servo": problem.servo}


def problem_from_dict(d: dict) -> ShootingProblem:
    """The problem back from ``problem_to_dict``'s output; ShootingError if malformed.

    Helper: replay of a params JSON.
    """
    try:
        dec = d["decision"]
        problem = ShootingProblem(
            str(d["gait"]), _floats(d["goal"], 2), float(d["duration"]), float(d["dt"]), tuple(map(str, dec["names"])),
            _floats(dec["lower"]), _floats(dec["upper"]), _floats(dec["x0"]),
            tuple(sorted((str(k), float(v)) for k, v in d["fixed"].items())), Weights(**d["weights"]),
            _floats(d["box_pose0"], 7), _floats(d["middle_pose0"], 3),
            None if d["box_direction"] is None else _floats(d["box_direction"], 2),
            tuple((str(k), tuple(v) if isinstance(v, list) else v) for k, v in d["cobra_parameters"].items()),
            str(d.get("servo", "prescribed")))
        problem.reference(problem.x0)
        problem.settings()
        problem.cobra_parameters()
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise ShootingError(f"malformed settings in params JSON: {type(exc).__name__}: {exc}") from None
    if problem.gait not in DECISION or not (len(problem.names) == len(problem.lower) == len(problem.upper)):
        raise ShootingError(f"malformed settings in params JSON: gait {problem.gait!r} or decision sizes")
    return problem


def _floats(values, n: int | None = None) -> tuple:
    out = tuple(float(v) for v in values)
    if (n is not None and len(out) != n) or not all(np.isfinite(out)):
        raise ValueError(f"expected {n or 'some'} finite numbers, got {values!r}")
    return out


def code_version() -> dict:
    """The package version and a SHA-256 of the physics modules' source (as ``reproduce`` keys its cache).

    Helper: recorded in the params JSON; `cobra-ref simulate --params` notes a replay on other code.
    """
    from . import __version__
    from .reproduce import physics_hash

    return {"version": __version__, "physics_sha256": physics_hash(("shooting",))}


def result_to_dict(result: ShootingResult) -> dict:
    """The params JSON: ``params`` (the optimum), ``history``, and every setting to re-run it.

    Helper: the output of ``cobra-ref optimize``.
    """
    best = result.best
    return {"format": FORMAT, "gait": result.problem.gait, "params": result.params,
            "cost": best["cost"], "box_distance_to_goal": best["box_distance_to_goal"],
            "terms": best["terms"], "box_final": best.get("box_final"), "contact": best.get("contact"),
            "interrupted": result.interrupted, "message": result.message,
            "settings": problem_to_dict(result.problem),
            "optimizer": {"method": result.method, "seed": result.seed, "maxiter": result.maxiter,
                          "iterations": result.iterations, "rollouts": len(result.history), **result.options},
            "code": code_version(), "wall_time": result.wall_time, "history": result.history}


def write_result(result: ShootingResult, path: str) -> dict:
    """Write the params JSON atomically (temporary file + rename); return what was written.

    Helper: ``cobra-ref optimize --out``.
    """
    record = result_to_dict(result)

    def write(tmp: str) -> None:
        with open(tmp, "w") as f:
            json.dump(record, f, indent=1, allow_nan=False)
            f.write("\n")

    atomic_write(path, write)
    return record


def load_result(path: str) -> dict:
    """Read a params JSON with clear errors (missing, not JSON, not ours, malformed settings).

    Helper: ``cobra-ref simulate --params`` and the figures.
    """
    if not os.path.isfile(path):
        raise ShootingError(f"params file not found: {path}")
    try:
        with open(path) as f:
            record = json.load(f)
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ShootingError(f"{path}: not a readable JSON file ({exc})") from None
    if not isinstance(record, dict) or record.get("format") != FORMAT:
        raise ShootingError(f"{path}: not a params file of cobra-ref optimize (expected format {FORMAT!r})")
    for key in ("params", "settings", "cost"):
        if key not in record:
            raise ShootingError(f"{path}: malformed params file, missing {key!r}")
    problem = problem_from_dict(record["settings"])
    try:
        record["params"] = {str(k): float(v) for k, v in record["params"].items()}
        gait(problem.gait, **record["params"])
    except (AttributeError, TypeError, ValueError) as exc:
        raise ShootingError(f"{path}: malformed 'params': {exc}") from None
    record["problem"] = problem
    return record


def decision_vector(problem: ShootingProblem, params: dict) -> tuple:
    """x for the full gait parameters ``params`` (the decision parameters picked out).

    Helper: replay.
    """
    return tuple(float(params[n]) for n in problem.names)


def replay(path: str, progress=None) -> tuple[Trajectory, dict]:
    """Re-run the optimum of a params JSON; return the trajectory and its cost entry.

    Helper: the exact replay (the simulator is deterministic: the cost equals the recorded one).
    """
    record = load_result(path)
    problem = record["problem"]
    x = decision_vector(problem, record["params"])
    traj = rollout(problem, x, progress)
    return traj, shooting_cost(problem, traj)


def summary_lines(result: ShootingResult) -> list[str]:
    """The final summary of an optimization, a few lines of text.

    Helper: printed on stderr by ``cobra-ref optimize``.
    """
    p, b, x0 = result.problem, result.best, result.history[0]
    c = b.get("contact") or {}
    lines = [f"{'INTERRUPTED: ' if result.interrupted else ''}{result.message}",
             f"{p.gait}: {len(result.history)} rollouts in {result.wall_time:.0f} s, {result.iterations} iterations",
             "optimum: " + ", ".join(f"{n} = {b['params'][n]:.4f}" for n in p.names),
             f"cost {x0['cost']:.5g} (initial guess) -> {b['cost']:.5g}; terms "
             + ", ".join(f"{k} {v:.4g}" for k, v in (b["terms"] or {}).items())]
    if b["box_distance_to_goal"] is not None and x0["box_distance_to_goal"] is not None:
        lines.append(f"box to goal {float(np.hypot(*p.goal)):.4f} m at start, {x0['box_distance_to_goal']:.4f} m "
                     f"with the initial guess, {b['box_distance_to_goal']:.4f} m at the optimum")
    if c:
        lines.append(f"contact conditions over the rollout: max complementarity {c['max_complementarity']:.2e} "
                     f"N s m/s, max cone residual {c['max_cone_residual']:.2e}, {c['steps_not_solved']} steps "
                     f"not 'solved'; torque over tau_max in {c['steps_over_tau_max']} steps "
                     f"(max excess {c['max_tau_excess']:.2f} N m), max |q| - q_max {c['max_q_excess']:.3f} rad")
    return lines


def optimize_gait(name: str, goal=None, out: str | None = None, duration: float | None = None,
                  maxiter: int | None = None, executor: Executor | None = None, progress=None,
                  **options) -> ShootingResult:
    """Optimize one gait at its defaults (``DEFAULTS[name]``: goal, horizon, maxiter, unless given) and
    write the params JSON to ``out`` (default ``optimized/<name>.json``; "" = do not write).

    Helper: what ``cobra-ref figures --reoptimize`` runs per gait. ``progress`` defaults to
    lines on stderr; ``options`` go to ``make_problem`` (bounds, x0, ramp_time, ...) or
    ``optimize`` (method, seed, popsize, step, workers).
    """
    d_goal, d_duration, d_maxiter = DEFAULTS[name]
    run_keys = {"method", "seed", "popsize", "step", "min_step", "workers"}
    problem = make_problem(name, d_goal if goal is None else goal, duration=duration or d_duration,
                           **{k: v for k, v in options.items() if k not in run_keys})
    if progress is None:
        progress = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
    result = optimize(problem, maxiter=d_maxiter if maxiter is None else maxiter, executor=executor,
                      progress=progress, **{k: v for k, v in options.items() if k in run_keys})
    out = os.path.join("optimized", f"{name}.json") if out is None else out
    if out:
        os.makedirs(os.path.dirname(os.path.abspath(out)), exist_ok=True)
        write_result(result, out)
    return result
