"""Push the box to a point: a receding-horizon planner that re-plans every period from the state reached.

Implements: [COBRA] sec. "Results", "the goal is to move the box on the flat ground towards a
specified point, and corresponding suitable joint commands are derived", closed loop. Every
period T_p (``PushOptions.period``), from the state the run has reached (the plant's q, qd, its
stepper's memory and the plan so far):

1. candidates (:mod:`cobra_ref.planning.choices`, ``choose_candidates``): while the robot faces
   away from the target (|phi| above ``facing.FACE_TOL``), turns where it stands (a pair of
   periods, forwards and backwards, run whole, ``committed``, unless the first already faced the
   robot towards the target); otherwise pushes: sequences of primitives
   (:mod:`cobra_ref.planning.primitives`), one per period, the last for the rest of the horizon,
   sampled around the rolling primitive the last plan goes on with (``choices.warm_start``: the
   plan shifted by a period), with the noise from a generator seeded by ``seed`` and the period's
   index. When the push has stalled (``reasons.stalled_over``: the box came less than 3 mm nearer its
   target in 3 periods), or the robot faces away from the target (``reasons.recovery_periods``: not
   within 3 periods of a re-plan that offered them or of a recovery), within ``choices.RECOVER_WITHIN``
   of the target with the box off its line (|phi| above ``facing.STEER_TOL``), recoveries are compared with those
   (``facing.recovery_candidates``: back off, turn, roll back, push gently; one primitive per
   period, each rolled out over its whole length; one starts only if it ends within the budget);
   a chosen recovery's back-off and turns then run without re-planning, and its roll back and push
   are re-planned as they come. A committed period (a turn's second half, a recovery's back-off
   and turns) runs only while the box lies within ``reasons.DEPARTED`` of where the chosen rollout
   put it (``reasons.departed``); else the next period is re-planned from the state reached;
2. each candidate is rolled out over the horizon from that state (through the executor, the
   candidates in batches advanced together: ``replan_batched``), and costs, in metres
   (``candidate_cost``)::

       J = m(t + H T_p) (1 + w_f (1 - cos phi)) + d(t + T_p) / 2 + w_a a(t + H T_p)
           + w_e E + w_I I + w_tau P_tau

   d: the box centre's horizontal distance to the current target; m: that distance with its part
   across the robot's push direction weighted by ``w_lateral`` at the horizon's end
   (``facing.miss``: a straight push cannot remove it); phi: the robot's facing error there
   (:mod:`cobra_ref.planning.facing`; the factor, weight ``w_face``, 0 by default, counts the
   distance a robot facing away cannot push off, and vanishes with d); a: the distance from the robot's nearest
   body centre to the pushing point, behind the box on the line from the target through the box's
   centre, a box half-size plus a link radius out (where a pusher must be to push the box towards
   the target, as in pusher-slider planning; weight ``w_approach``, and ``facing.W_APPROACH`` for a
   turn, which must end with the box in reach); E, I, P_tau the shooting cost's effort, impact and torque-limit
   terms (:mod:`cobra_ref.planning.cost`) over the horizon. A rollout whose box ends within ``tolerance``
   of the target needs no next push: its m is d and its a 0;
3. the best candidate's first primitive is appended to the plan and the plant runs one period.

The plant runs at another time step than the rollouts: by default the figures' 1 ms
(``PLANT_DT``), the rollouts 2 ms (``ROLLOUT_DT``, half the cost of a re-plan; the plan must not be
tuned to its own model). The target is the next waypoint until the box passes within ``via_tolerance`` of it
(anywhere on its way during a period: ``advance_watching``), then the goal.
The push ends when the box is within ``tolerance`` of the goal at the end of a period in which
the robot stopped (the box at rest), when the robot has stopped for ``STALL_PERIODS`` periods in
a row (``resting``: nothing the planner has brings the box nearer), or when the budget of
simulated time is spent. The plant is
one ``simulate.Run`` advanced period by period: replaying the plan (``replay``) takes the same
steps, bit for bit.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field, replace

import numpy as np

from ..infra import arguments
from ..infra.executors import SerialExecutor
from ..infra.validation import DEFAULT_DT, RULES
from ..params import CobraParameters
from ..robots import cobra_model
from ..batch import BatchRun
from ..simulate import Run
from ..start import initial_state
from ..step import StepSettings
from .cost import effort_term, excess_term, impact_term, robot_weight
from .choices import choose_candidates, warm_start
from .facing import FACE_TOL, RECOVERY_TAIL, TURN_PAIR, W_APPROACH, W_LATERAL, away, facing, miss
from .locomotion import link_centres
from .primitives import SIDEWINDING, PlanReference, Primitive
from .reasons import STALL_PERIODS, calm_after, departed, gave_up, outlook, recovery_periods

FAILED = 1e3  # [m] the cost of a rollout whose simulation failed
ROLLOUT_BATCHES = 2  # a re-plan's candidates go to the executor as this many batches (``replan_batched``)
PLANTS = ("cobra_ref", "mujoco")
ROLLOUT_DT = 2 * DEFAULT_DT  # [s] the rollouts' time step: the planner predicts in a coarser world than it acts in
PLANT_DT = DEFAULT_DT  # [s] the plant's: the figures' time step
WATCH = 0.05  # [s] the box's way to a waypoint is sampled this often (``advance_watching``)


@dataclass(frozen=True)
class PushOptions:
    """A push task and the planner's settings (module docstring); distances in metres, times in seconds."""

    goal: tuple = (0.25, 0.0)  # (dx, dy) from the box's start, world axes (x: the robot's initial heading)
    via: tuple = ()  # waypoints ((dx, dy), ...) on the way, same axes
    period: float = 1.0  # T_p: one re-plan per period
    horizon: int = 3  # H: periods each rollout looks ahead
    budget: float = 30.0  # simulated time at most
    tolerance: float = 0.01  # done within this of the goal
    via_tolerance: float = 0.03  # a waypoint is passed within this
    samples: int = 6  # noisy copies of the last choice per re-plan
    seed: int = 0
    start: Primitive = Primitive("C", 0.5, 0.5)  # the start shape (the box on its concave side) and first guess
    settings: StepSettings = field(default_factory=lambda: StepSettings(dt=ROLLOUT_DT))  # the rollouts'
    cobra: CobraParameters = field(default_factory=CobraParameters)
    w_effort: float = 0.005  # [m] per unit of E
    w_impact: float = 1.0  # [m] per unit of I: claim NI's 1 % of the robot's weight costs 1 cm
    w_tau: float = 0.1  # [m] per unit of P_tau
    w_approach: float = 0.5  # per metre of a (docs/planning.md, "Turning before pushing")
    w_face: float = 0.0  # the facing factor's weight: the end distance counts m (1 + w_face (1 - cos phi))
    w_lateral: float = W_LATERAL  # the weight of the end distance's part across the push direction (``facing.miss``)
    plant_dt: float | None = PLANT_DT  # [s] the plant's time step (None: the rollouts' settings.dt)
    plant: str = "cobra_ref"  # the plant's simulator: "cobra_ref" (``simulate.Run``) or "mujoco" (``push``'s plant=)

    def __post_init__(self):
        """Each field by the command line's rule (``infra.validation``): an ``infra.arguments``
        error naming the field, its value and what is allowed."""
        put = lambda name, value: object.__setattr__(self, name, value)  # noqa: E731  (a frozen dataclass)
        put("goal", arguments.numbers("goal", self.goal, 2, RULES["goal"], ("X", "Y")))
        if not isinstance(self.via, (list, tuple)):
            raise arguments.ArgumentTypeError(f"via = {arguments.shown(self.via)} is not a list of waypoints "
                                              "(allowed: ((dx, dy), ...) in metres)")
        put("via", tuple(arguments.numbers(f"via[{i}]", w, 2, RULES["goal"], ("X", "Y")) for i, w in enumerate(self.via)))
        for name, rule in (("period", "push_period"), ("horizon", "push_horizon"), ("budget", "push_budget"),
                           ("tolerance", "push_tolerance"), ("via_tolerance", "push_tolerance"),
                           ("samples", "push_samples"), ("seed", "seed"), ("w_effort", "weight"),
                           ("w_impact", "weight"), ("w_tau", "weight"), ("w_approach", "weight"),
                           ("w_face", "weight"), ("w_lateral", "weight")):
            put(name, arguments.number(name, getattr(self, name), RULES[rule]))
        arguments.instance("start", self.start, Primitive, "Primitive('C', 0.5, 0.5)")
        arguments.instance("settings", self.settings, StepSettings, "StepSettings(dt=0.001)")
        arguments.instance("cobra", self.cobra, CobraParameters, "CobraParameters()")
        if self.plant_dt is not None:
            put("plant_dt", arguments.number("plant_dt", self.plant_dt, RULES["dt"]))
        arguments.choice("plant", self.plant, PLANTS)

    @property
    def plant_settings(self) -> StepSettings:
        """The plant's ``StepSettings``: the rollouts' with ``plant_dt`` (another world than the one
        the planner predicts with, when it differs)."""
        return self.settings if self.plant_dt is None else replace(self.settings, dt=self.plant_dt)


@dataclass(frozen=True)
class Rollout:
    """What a worker needs for one candidate: the plant's state and plan, the candidate, the target."""

    plan: dict  # PlanReference.to_dict() so far
    pair: tuple  # (Primitive, ...): one per period, the last for the rest of the horizon
    t: float
    q: np.ndarray
    qd: np.ndarray
    memory: dict | None
    target: tuple  # world (x, y)
    options: PushOptions
    turning: bool = False  # a turning re-plan's rollout: its cost adds the pushing distance a


def candidate_cost(job: Rollout) -> dict:
    """One candidate's rollout and its cost J (module docstring): {"cost", "distance", "boxes"
    (the box at each period's end, the last at the rollout's)}.
    What the executor runs (module level: picklable)."""
    return candidate_costs([job])[0]


def candidate_costs(jobs: list) -> list:
    """``candidate_cost`` of each of ``jobs``, which start from one state (one re-plan's), their
    rollouts advanced together as one batch (:mod:`cobra_ref.batch`: each the same steps, bit for
    bit, as its own run). What the executor runs (module level: picklable)."""
    o, first = jobs[0].options, jobs[0]
    plans = []
    for job in jobs:
        plan = PlanReference.from_dict(job.plan)
        for i, p in enumerate(job.pair):  # one primitive per period, the last for the rest of the horizon
            plan.extend(p, job.t + i * o.period)
        plans.append(plan)
    model = cobra_model(o.cobra)
    n_period = int(round(o.period / o.settings.dt))
    n = n_period * max([o.horizon] + [len(job.pair) for job in jobs])
    run = BatchRun(model, o.settings, [(first.q, first.qd)] * len(jobs), n, t0=first.t, memory=first.memory)
    run.advance(plans, n)
    return [_rollout_cost(job, traj, model, n_period) for job, traj in zip(jobs, run.finish())]


def _rollout_cost(job: Rollout, traj, model, n_period: int) -> dict:
    """The cost J of one candidate's rollout ``traj`` (module docstring), or ``FAILED`` if it failed."""
    o = job.options
    if traj.error:
        return {"cost": FAILED, "distance": None, "boxes": None, "error": traj.error}
    target = np.asarray(job.target)
    d_mid = float(np.linalg.norm(traj.box_pose[n_period, :2] - target))
    d_end = float(np.linalg.norm(traj.box_pose[-1, :2] - target))
    duration = traj.duration
    effort = effort_term(traj, o.cobra.tau_max, duration)
    impact = impact_term(traj, robot_weight(model), duration)
    p_tau = excess_term(traj, "tau_excess", o.cobra.tau_max, duration)
    w_a = W_APPROACH if job.turning else o.w_approach
    ready = d_end > o.tolerance  # the terms that prepare a next push count only while one is needed
    approach = pushing_distance(model, traj.q[-1], target, o.cobra) if w_a and ready else 0.0
    # the distance with its lateral part weighted, times the facing factor: m (1 + w_face (1 - cos phi))
    faced = miss(model, traj.q[-1], target, o.w_lateral) if ready else d_end
    if o.w_face:
        faced *= 1 + o.w_face * (1 - np.cos(facing(model, traj.q[-1], target)))
    cost = (faced + 0.5 * d_mid + w_a * approach + o.w_effort * effort + o.w_impact * impact
            + o.w_tau * p_tau)
    boxes = traj.box_pose[n_period::n_period, :2].tolist()  # the box at each period's end, the rollout's last
    return {"cost": cost, "distance": d_end, "boxes": boxes, "error": None}


def pushing_distance(model, q, target, cobra: CobraParameters) -> float:
    """a [m]: the robot's nearest body centre to the pushing point behind the box (module docstring)."""
    points, box = link_centres(model, q), model.boxes[0].body
    away = points[box] - np.asarray(target, dtype=float)
    u = away / max(float(np.linalg.norm(away)), 1e-9)  # from the target through the box
    point = points[box] + u * (cobra.box_size / 2 + cobra.radius_link)
    return float(np.min(np.linalg.norm(np.delete(points, box, axis=0) - point, axis=1)))


@dataclass
class PushResult:
    """The executed run, its plan and one record per period (``push``)."""

    trajectory: object
    plan: PlanReference
    cycles: list
    goal_world: tuple
    reached: bool
    reason: str
    wall_time: float
    outlook: list = field(default_factory=list)  # what made the task hard or out of reach, said up front (``outlook``)


def push(options: PushOptions, executor=None, progress=None, plant=None) -> PushResult:
    """Push the box to ``options.goal`` (module docstring); ``progress(line)`` gets one line per period.

    ``executor``: a ``concurrent.futures.Executor`` for the rollouts (None: in this process).
    ``plant(model, settings, q0, qd0, capacity)``: what executes the plan (default a
    ``simulate.Run``; for ``options.plant`` = "mujoco", ``reproduce.mujoco_plant.MujocoPlant``). A
    Ctrl-C ends the push and keeps what was executed.
    """
    o, settings = options, options.plant_settings
    model = cobra_model(o.cobra)
    plan = PlanReference(o.start)
    q0, qd0 = initial_state(model, plan, settings)
    box = model.q_idx[model.boxes[0].body].start
    box0 = q0[box:box + 2].copy()
    targets = [tuple(box0 + np.asarray(w, dtype=float)) for w in tuple(o.via) + (o.goal,)]
    n_period = int(round(o.period / settings.dt))
    n_budget = int(round(o.budget / o.period))
    run = _plant(o, plant)(model, settings, q0, qd0, n_period * n_budget)
    cycles, last, moving, aim, mode = [], o.start, o.start, 0, "push"
    # the box, its distance at each period's start; periods run without re-planning; re-plans since
    # recoveries; where the chosen rollout put the box at the end of each of its periods still to run
    boxes, ds, queue, calm, predicted = [], [], [], 0, []
    start, reason, reached = time.perf_counter(), None, False
    notes = outlook(model, q0, targets, o.budget)
    for note in notes if progress is not None else ():
        progress(f"note: {note}")

    def distance() -> float:  # the box centre to the current target [m]
        return float(np.linalg.norm(run.q[box:box + 2] - np.asarray(targets[aim])))

    try:
        for k in range(n_budget):
            t, phi, d0 = run.t, facing(model, run.q, targets[aim]), distance()
            boxes.append(run.q[box:box + 2].copy())
            ds.append(d0)
            if mode == "turn" and abs(phi) <= FACE_TOL:
                queue = []  # a turn pair's first half already faced the robot towards the target
            if queue:  # the rest of a chosen recovery's back-off and turns, or of a turn pair: no re-plan
                modes, pairs, results, best = (), (), [{"cost": None}], 0
                last = queue.pop(0)
            else:
                recover = recovery_periods(calm, ds, phi, n_budget - k)  # the periods a recovery may take, or None
                modes, pairs = zip(*choose_candidates(phi, d0, moving, np.random.default_rng([o.seed, k]), o.samples,
                                                      recover, lambda: away(model, run.q), o.horizon))
                best, results = replan_batched(_jobs(plan, run, pairs, targets[aim], o, "turn" in modes), executor)
                mode, last = modes[best], pairs[best][0]
                queue, predicted = committed(mode, pairs[best]), list(results[best]["boxes"] or ())
            calm = calm_after(calm, mode, modes)
            moving = warm_start(pairs[best], moving) if pairs and mode != "recover" else moving
            plan.extend(last, t)
            closest = advance_watching(run, plan, n_period, box, targets[aim])
            d, expected = distance(), predicted.pop(0) if predicted else None
            # a box that is not where the committed periods' rollout put it: re-plan from here
            queue = [] if departed(run.q[box:box + 2], expected) else queue
            cycles.append({"t": t, "facing": float(np.degrees(phi)), "mode": mode,
                           "chosen": last.to_dict(), "predicted_cost": results[best]["cost"],
                           "distance": d, "target": list(targets[aim]), "rollouts": len(pairs),
                           "predicted_box": expected, "wall_time": time.perf_counter() - start,
                           "candidates": [{"mode": m, "pair": [_name(p) for p in pair], "cost": r["cost"],
                                           "distance": r["distance"]} for m, pair, r in zip(modes, pairs, results)]})
            if progress is not None:
                progress(f"t = {run.t:5.1f} s  phi {np.degrees(phi):+6.1f} deg  {_name(last):<41} box {100 * d:6.2f} cm from "
                         f"{'the goal' if aim == len(targets) - 1 else f'waypoint {aim + 1}'}")
            if aim < len(targets) - 1 and closest <= o.via_tolerance:  # passed during the period
                aim, calm = aim + 1, 0  # a new target: its stall is measured from here
            elif aim == len(targets) - 1 and (reason := ending(plan, d, o.tolerance)):
                reached = d <= o.tolerance
                break
        reason = reason or gave_up(boxes + [run.q[box:box + 2].copy()], ds + [distance()])
    except KeyboardInterrupt as exc:
        exc.result = PushResult(run.finish("interrupted"), plan, cycles, targets[-1], False, "interrupted",
                                time.perf_counter() - start, notes)
        raise
    return PushResult(run.finish(), plan, cycles, targets[-1], reached, reason, time.perf_counter() - start, notes)


def advance_watching(run, plan: PlanReference, n_steps: int, box: int, target) -> float:
    """Advance the plant ``run`` by ``n_steps`` steps of ``plan`` and return the box centre's
    closest distance [m] to ``target`` on its way, sampled every ``WATCH`` seconds and at the end:
    a waypoint the box passes between two re-plans is passed. The steps are those of one
    ``advance`` of ``n_steps`` (a run's step depends on its state, not on how it is called)."""
    every = max(1, int(round(WATCH / run.settings.dt)))
    target, closest, done = np.asarray(target, dtype=float), np.inf, 0
    while done < n_steps:
        n = min(every, n_steps - done)
        run.advance(plan, n)
        done += n
        closest = min(closest, float(np.linalg.norm(run.q[box:box + 2] - target)))
    return closest


def ending(plan: PlanReference, d: float, tolerance: float) -> str | None:
    """Why the push ends after a period that left the box ``d`` [m] from the goal, or None: the
    robot stopped with the box within ``tolerance``, or it has rested (``resting``)."""
    if plan.primitives[-1].family != "stop":
        return None
    if d <= tolerance:
        return "the box is at the goal"
    if resting(plan):
        return f"the robot rests {100 * d:.2f} cm from the goal: {STALL_PERIODS} re-plans in a row chose to stop"
    return None


def resting(plan: PlanReference) -> bool:
    """Whether the last ``STALL_PERIODS`` periods of ``plan`` all stopped: every re-plan predicted
    that no candidate brings the box nearer than where it lies, and the push ends there."""
    last = plan.primitives[-STALL_PERIODS:]
    return len(last) == STALL_PERIODS and all(p.family == "stop" for p in last)


def committed(mode: str, sequence: tuple) -> list:
    """The periods after the first of a chosen ``sequence`` that the plant runs without re-planning:
    a recovery's back-off and turns (all but its last ``facing.RECOVERY_TAIL``), a turn's second half
    (``facing.TURN_PAIR``: sidewinding forwards and backwards in turn), nothing of a push."""
    if mode == "recover":
        return list(sequence[1:-RECOVERY_TAIL])
    if mode == "turn" and sequence[0].family in SIDEWINDING:
        return list(sequence[1:TURN_PAIR])
    return []


def replan(jobs: list, predict, executor=None) -> tuple[int, list]:
    """Steps 2-3 of a re-plan (module docstring): ``predict(job)`` -> {"cost": J, ...} of every
    candidate's rollout, through ``executor`` (``predict`` at module level: picklable), and the index
    of the cheapest (the first of equal costs). The plant then applies that candidate's first period."""
    results = list((executor or SerialExecutor()).map(predict, jobs))
    return int(np.argmin([r["cost"] for r in results])), results


def replan_batched(jobs: list, executor=None) -> tuple[int, list]:
    """``replan`` with ``candidate_costs``: the candidates of each rollout length (a recovery's
    periods, or the horizon) in ``ROLLOUT_BATCHES`` batches (one per worker of a two-core machine),
    each batch one executor task; the same costs, bit for bit, as one task per candidate (a batch
    rolls every member out as long as its longest: lengths are not mixed)."""
    lengths = [max(job.options.horizon, len(job.pair)) for job in jobs]
    batches = []
    for n in sorted(set(lengths)):
        group = [i for i, m in enumerate(lengths) if m == n]
        size = -(-len(group) // ROLLOUT_BATCHES)
        batches += [group[i:i + size] for i in range(0, len(group), size)]
    costs = (executor or SerialExecutor()).map(candidate_costs, [[jobs[i] for i in batch] for batch in batches])
    by_index = dict(zip((i for batch in batches for i in batch), (r for batch in costs for r in batch)))
    results = [by_index[i] for i in range(len(jobs))]
    return int(np.argmin([r["cost"] for r in results])), results


def _jobs(plan: PlanReference, run: Run, pairs: list, target, options: PushOptions, turning: bool = False) -> list:
    """The ``Rollout`` of every pair from the state ``run`` has reached, in order (``turning``: a
    turning re-plan's, its candidates all costed alike)."""
    # the plant's stepper memory (its last velocity, its impulses) holds for rollouts at its own dt only
    memory = run.stepping.memory if run.settings.dt == options.settings.dt else None
    plan_so_far, q, qd = plan.to_dict(), run.q, run.qd  # the same for every candidate
    return [Rollout(plan_so_far, pair, run.t, q, qd, memory, target, options, turning) for pair in pairs]


def _name(p: Primitive) -> str:
    """A primitive in a few words: family, amplitude, frequency, taper."""
    if p.family == "stop":
        return "stop"
    return f"{p.family} A {p.amplitude:.2f} f {p.frequency:.2f} b {p.taper:+.2f}"


def _plant(options: PushOptions, factory):
    """The plant factory of ``push`` and ``replay``: ``factory``, or a ``simulate.Run`` for the cobra_ref plant."""
    if factory is not None:
        return factory
    if options.plant != "cobra_ref":
        raise arguments.ArgumentError(f"plant = {options.plant!r} needs its factory: push(..., plant=MujocoPlant) "
                                      "with cobra_ref.reproduce.mujoco_plant.MujocoPlant")
    return lambda model, settings, q0, qd0, capacity: Run(model, settings, q0, qd0, "fast", capacity)


def replay(plan_dict: dict, options: PushOptions, plant=None):
    """The executed run of a plan (``PushResult.plan.to_dict()``) replayed from the same start: the
    same steps as ``push`` took, bit for bit (``plant``: as ``push``'s)."""
    o = options
    model = cobra_model(o.cobra)
    plan = PlanReference.from_dict(plan_dict)
    plant_settings = o.plant_settings
    q0, qd0 = initial_state(model, PlanReference(plan.start), plant_settings)
    n_period = int(round(o.period / plant_settings.dt))
    n = n_period * len(plan.primitives)
    run = _plant(o, plant)(model, plant_settings, q0, qd0, n)
    # period by period, as the plant ran (the reference is the whole plan: it gives the same values)
    for _ in range(len(plan.primitives)):
        run.advance(plan, n_period)
    return run.finish()
