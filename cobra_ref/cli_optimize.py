"""``cobra-ref optimize`` (single shooting) and the ``--params`` replay of ``cobra-ref simulate``.

Helper: the command-line side of :mod:`cobra_ref.shooting` (DESIGN.md sec. 5). Conventions of
``cobra_ref.cli``: every input is checked before the long run, progress and the final summary
go to stderr, stdout carries one JSON line, files are written atomically.
"""

from __future__ import annotations

import argparse
import json
import sys
from typing import NamedTuple

import numpy as np

from .gaits import gait_params
from .shooting import (DECISION, DEFAULTS, RAMP_TIME, SerialExecutor, ShootingError, ShootingProblem,
                       code_version, decision_vector, load_result, make_problem, optimize, shooting_cost,
                       start_state, summary_lines, write_result)


def _goal(text: str) -> tuple:
    """argparse type: 'X,Y', two finite numbers [m]."""
    parts = text.split(",")
    if len(parts) != 2:
        raise argparse.ArgumentTypeError(f"expected X,Y (two numbers in metres), got {text!r}")
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number in {text!r}: expected X,Y in metres") from None
    if not np.all(np.isfinite(values)):
        raise argparse.ArgumentTypeError(f"goal must be finite, got {text!r}")
    return values


def _count(text: str) -> int:
    """argparse type: a non-negative integer."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
    if value < 0:
        raise argparse.ArgumentTypeError(f"must be >= 0, got {value}")
    return value


def _assignments(items, n_values: int, what: str) -> dict:
    """['name=a,b', ...] -> {name: (a, b)} (n_values = 2) or {name: a} (n_values = 1)."""
    out = {}
    for item in items or ():
        name, sep, rest = item.partition("=")
        try:
            values = tuple(float(v) for v in rest.split(","))
        except ValueError:
            values = ()
        if not sep or not name or len(values) != n_values:
            form = "NAME=LO,HI" if n_values == 2 else "NAME=VALUE"
            raise ShootingError(f"{what} must look like {form}, got {item!r}")
        out[name.strip()] = values if n_values == 2 else values[0]
    return out


def add_parsers(sub) -> None:
    """Add the ``optimize`` subcommand to an argparse subparsers object.

    Helper: ``cobra_ref.cli.build_parser`` calls it.
    """
    from .cli import _finite_float

    goals = "; ".join(f"{g} {x:g},{y:g} in {T:g} s, {n} iterations" for g, ((x, y), T, n) in DEFAULTS.items())
    p = sub.add_parser(
        "optimize", help="single shooting: gait parameters that push the box to a goal with least torque",
        description="Single shooting ([COBRA] 'shooting method to find optimal u_ref'): optimise a gait's "
                    "parameters so that a rollout of DURATION seconds pushes the box to the goal with the least "
                    "joint torque (cost = mean squared torque / tau_max^2 + 10 (distance to goal / start "
                    "distance)^2 + torque and joint-limit penalties; see cobra_ref/shooting.py). One progress "
                    "line per iteration and a summary on stderr, one JSON line on stdout; OUT holds the optimum "
                    "('params'), every rollout ('history') and every setting; 'cobra-ref simulate --params OUT' "
                    "replays it. Ctrl-C stops and writes the best rollout so far (with \"interrupted\": true).")
    p.add_argument("--gait", required=True, choices=list(DECISION), help="the gait family")
    p.add_argument("--goal", type=_goal, default=None, metavar="X,Y",
                   help="where to push the box, relative to its start [m], world axes (x = the robot's initial "
                        f"heading, y = its left; a negative X needs --goal=-0.1,0.2); defaults (goal, --duration, "
                        f"--maxiter) per gait: {goals}")
    p.add_argument("--duration", type=_finite_float, default=None,
                   help="horizon of each rollout [s] (default per gait: 1.5, sidewinding 3)")
    p.add_argument("--dt", type=_finite_float, default=1e-3, help="time step [s] (default 1e-3)")
    p.add_argument("--ramp-time", type=_finite_float, default=RAMP_TIME,
                   help=f"ramp-in of the gait's phase rate [s] (default {RAMP_TIME})")
    p.add_argument("--servo", choices=("prescribed", "pd"), default="prescribed",
                   help="joint servo of the rollouts: prescribed (default; the paper's motion provided, impact "
                        "torques above tau_max penalised) or pd (torques saturated at tau_max at every step)")
    p.add_argument("--box-gap", type=_finite_float, default=0.05,
                   help="gap between the box and the middle link at the start [m] (default 0.05, assumption C9)")
    p.add_argument("--maxiter", type=_count, default=None,
                   help="iterations: polls of the compass search, generations of DE (default 6)")
    p.add_argument("--method", choices=("pattern", "de"), default="pattern",
                   help="parallel compass search (default) or scipy differential evolution")
    p.add_argument("--seed", type=int, default=0, help="random seed of --method de (default 0)")
    p.add_argument("--popsize", type=int, default=2,
                   help="--method de: population = max(5, POPSIZE x parameters) (default 2)")
    p.add_argument("--bound", action="append", default=[], metavar="NAME=LO,HI",
                   help="bounds of a gait parameter (repeatable; adds it to the decision vector)")
    p.add_argument("--start", action="append", default=[], metavar="NAME=VALUE",
                   help="initial guess of a gait parameter (repeatable; default: the gait's defaults)")
    p.add_argument("--workers", type=int, default=None,
                   help="worker processes (default: the cores; 1 = serial, in this process)")
    p.add_argument("--out", required=True, help="output params JSON")
    p.add_argument("--quiet", action="store_true", help="no progress lines (the summary is still printed)")
    p.set_defaults(func=cmd_optimize)


def cmd_optimize(args) -> int:
    """Run the optimization, write the params JSON, print the summary (stderr) and one JSON line.

    Helper: ``cobra-ref optimize``. Exit status 0, or 130 after Ctrl-C (the file is still written).
    """
    from .cli import _check_writable

    _check_writable(args.out)
    if args.workers is not None and args.workers < 1:
        raise SystemExit(f"error: --workers must be >= 1, got {args.workers}")
    d_goal, d_duration, d_maxiter = DEFAULTS[args.gait]
    goal = d_goal if args.goal is None else args.goal
    duration = d_duration if args.duration is None else args.duration
    maxiter = d_maxiter if args.maxiter is None else args.maxiter
    err = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
    from .cli import c_stdout_silenced

    with c_stdout_silenced():  # OSQP's "Polishing not needed" lines (workers: parallel.worker_init)
        try:
            problem = make_problem(args.gait, goal, duration=duration, dt=args.dt, ramp_time=args.ramp_time,
                                   box_gap=args.box_gap, servo=args.servo,
                                   bounds=_assignments(args.bound, 2, "--bound"),
                                   x0=_assignments(args.start, 1, "--start"))
        except ShootingError as exc:
            raise SystemExit(f"error: {exc}") from None
        err(f"optimize {args.gait}: goal {goal} m from the box's start {np.round(problem.box_pose0[:2], 4)}, "
            f"{len(problem.names)} parameters ({', '.join(problem.names)}), {duration} s rollouts, maxiter {maxiter}")
        result = optimize(problem, method=args.method, maxiter=maxiter, seed=args.seed,
                          popsize=args.popsize, progress=None if args.quiet else err,
                          executor=SerialExecutor() if args.workers == 1 else None, workers=args.workers)
    record = write_result(result, args.out)
    for line in summary_lines(result):
        err(line)
    err(f"wrote {args.out}")
    contact = record["contact"] or {}
    print(json.dumps({"out": args.out, "gait": args.gait, "params": record["params"], "cost": record["cost"],
                      "initial_cost": result.history[0]["cost"],
                      "box_distance_to_goal": record["box_distance_to_goal"], "rollouts": len(result.history),
                      "max_complementarity": contact.get("max_complementarity"),
                      "max_cone_residual": contact.get("max_cone_residual"),
                      "interrupted": result.interrupted, "wall_time": round(result.wall_time, 1)}))
    return 130 if result.interrupted else 0


class ParamsRun(NamedTuple):
    """What ``cobra-ref simulate --params FILE`` needs to replay an optimum exactly."""

    gait: str
    reference: object  # the optimal gait: gait(gait, **params)
    settings: object  # StepSettings of the optimization
    duration: float  # the optimization's horizon, or the override
    q0: np.ndarray  # the common initial state of the optimization
    qd0: np.ndarray
    model: object  # cobra_model with the recorded CobraParameters
    problem: ShootingProblem
    recorded_cost: float
    same_code: bool = True  # the physics modules' SHA-256 equals the one the optimum was found with


def params_reference(path: str, duration: float | None = None) -> ParamsRun:
    """Read a params JSON and return everything to replay its optimum with ``simulate``.

    Helper: ``cobra-ref simulate --params``. ``duration`` None = the optimization's horizon (then
    ``params_summary`` checks that the replayed cost equals the recorded one). Raises
    ``ShootingError`` for a missing or malformed file.
    """
    from .robots import cobra_model

    record = load_result(path)
    problem: ShootingProblem = record["problem"]
    if duration is not None and not (np.isfinite(duration) and duration > 0):
        raise ShootingError(f"duration must be positive and finite, got {duration}")
    x = decision_vector(problem, record["params"])
    model = cobra_model(problem.cobra_parameters())
    q0, qd0 = start_state(problem, x, model)
    return ParamsRun(problem.gait, problem.reference(x), problem.settings(),
                     problem.duration if duration is None else float(duration), q0, qd0, model, problem,
                     float(record["cost"]), record.get("code", {}).get("physics_sha256") == code_version()["physics_sha256"])


def cmd_simulate_params(args) -> int:
    """``cobra-ref simulate --params FILE``: replay the optimum (its gait, parameters, start state,
    dt and, unless ``--duration`` is given, horizon); write the NPZ; print the JSON summary with the
    replayed and the recorded cost.

    Helper: ``cobra_ref.cli.cmd_simulate`` hands over when ``args.params`` is set (uses
    ``args.params``, ``args.duration`` (None = the JSON's), ``args.out``, ``args.quiet``).
    """
    from .cli import _check_writable, run_and_write

    _check_writable(args.out)
    try:
        run = params_reference(args.params, duration=args.duration)
    except ShootingError as exc:
        raise SystemExit(f"error: {exc}") from None
    meta = {"gait": run.gait, "gait_params": gait_params(run.reference), "params_file": args.params}
    run_and_write(run.model, run.reference, run.duration, run.settings, args.out, f"simulate {args.params}",
                  args.quiet, run.q0, run.qd0, meta, lambda traj: params_summary(run, traj))
    return 0


def params_summary(run: ParamsRun, traj) -> dict:
    """The replayed cost next to the recorded one (when the horizon is the optimization's).

    Helper: extra keys for the JSON line of ``cobra-ref simulate --params``.
    """
    if run.duration != run.problem.duration or len(traj.tau) != round(run.problem.duration / run.problem.dt):
        return {"params_cost": None, "note": "horizon differs from the optimization's: cost not comparable"}
    c = shooting_cost(run.problem, traj)
    out = {"params_cost": c["cost"], "recorded_cost": run.recorded_cost,
           "cost_matches": c["cost"] == run.recorded_cost, "box_distance_to_goal": c["box_distance_to_goal"]}
    if not run.same_code:
        out["note"] = "the physics code changed since this optimum was found: the costs need not match"
    return out
