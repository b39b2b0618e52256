"""``cobra-ref optimize`` (single shooting) and the ``--params`` replay of ``cobra-ref simulate``.

The command-line side of :mod:`cobra_ref.planning` (conventions: :mod:`cobra_ref.cli.common`).
"""

from __future__ import annotations

import json
import sys

import numpy as np

from ..infra.executors import SerialExecutor
from ..planning.problem import DECISION, DEFAULTS, RAMP_TIME, DecisionSpace, ShootingError, Weights, make_problem
from ..infra.output import OutputError
from ..planning.checkpoint import Checkpoint
from ..planning.results import summary_lines
from ..planning.search import SearchOptions, optimize
from ..step import StepSettings
from ..infra.validation import DEFAULT_DT, RULES, ValidationError
from .common import add_model_options, c_stdout_silenced, check_writable, fail, model_parameters, say_interrupted


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
    """Add the ``optimize`` subcommand to ``sub``."""
    w = Weights()
    goals = "; ".join(f"{g} {x:g},{y:g} in {T:g} s, {n} iterations" for g, ((x, y), T, n) in DEFAULTS.items())
    p = sub.add_parser(
        "optimize", help="single shooting: gait parameters that push the box to a goal with least torque",
        description="Single shooting ([COBRA] 'shooting method to find optimal u_ref'): optimise a gait's "
                    "parameters so that a rollout of DURATION seconds pushes the box to the goal with the least "
                    "joint torque and the fewest impacts (cost = mean squared torque / tau_max^2 + "
                    f"{w.goal:g} (distance to goal / start distance)^2 + {w.impact:g} impact impulse / (robot weight "
                    "x DURATION) + torque and "
                    "joint-limit penalties; see cobra_ref/planning/). One progress "
                    "line per iteration and a summary on stderr, one JSON line on stdout; OUT holds the optimum "
                    "('params'), every rollout ('history') and every setting; 'cobra-ref simulate --params OUT' "
                    "replays it. OUT is rewritten after every batch of rollouts (with \"checkpoint\": true until "
                    "the search ends), so a run stopped by force keeps what it computed; when OUT cannot be "
                    "written at the end, the result goes to a file in the temporary directory, named in the "
                    "error. Ctrl-C or SIGTERM stops it and writes the best rollout so far (with \"interrupted\": "
                    "true; exit status 130 or 143).")
    p.add_argument("--gait", required=True, choices=list(DECISION), help="the gait family")
    p.add_argument("--goal", type=RULES["goal_pair"].arg("--goal"), default=None, metavar="X,Y",
                   help="where to push the box, relative to its start [m], world axes (x = the robot's initial "
                        f"heading, y = its left; a negative X needs --goal=-0.1,0.2); defaults (goal, --duration, "
                        f"--maxiter) per gait: {goals}")
    p.add_argument("--duration", type=RULES["horizon"].arg("--duration"), default=None,
                   help="horizon of each rollout [s] (default per gait: 1.5, sidewinding 3)")
    p.add_argument("--dt", type=RULES["dt"].arg("--dt"), default=DEFAULT_DT,
                   help=f"time step [s] (default {DEFAULT_DT * 1e3:g} ms)")
    p.add_argument("--ramp-time", type=RULES["ramp_time"].arg("--ramp-time"), default=RAMP_TIME,
                   help=f"ramp-in of the gait's phase rate [s] (default {RAMP_TIME})")
    p.add_argument("--servo", choices=("position", "prescribed"), default="position",
                   help="joints of the rollouts: position (default, the paper's position control within tau_max) "
                        "or prescribed (the joints follow the reference exactly, torques recovered and penalised "
                        "above tau_max)")
    p.add_argument("--contact", choices=("compliant", "rigid"), default="compliant",
                   help="contact law of the rollouts (default compliant)")
    p.add_argument("--box-gap", type=RULES["box_gap"].arg("--box-gap"), default=0.05,
                   help="gap between the box and the middle link at the start [m] (default 0.05, assumption A9)")
    add_model_options(p)
    p.add_argument("--maxiter", type=RULES["maxiter"].arg("--maxiter"), default=None,
                   help="iterations: polls of the compass search, generations of DE (default 6)")
    p.add_argument("--method", choices=("pattern", "de"), default="pattern",
                   help="parallel compass search (default) or scipy differential evolution")
    p.add_argument("--seed", type=RULES["seed"].arg("--seed"), default=0, help="random seed of --method de (default 0)")
    p.add_argument("--popsize", type=RULES["popsize"].arg("--popsize"), default=2,
                   help="--method de: population = max(5, POPSIZE x parameters) (default 2)")
    p.add_argument("--bound", action="append", default=[], metavar="NAME=LO,HI",
                   help="bounds of a gait parameter (repeatable; adds it to the decision vector)")
    p.add_argument("--start", action="append", default=[], metavar="NAME=VALUE",
                   help="initial guess of a gait parameter (repeatable; default: the gait's defaults)")
    p.add_argument("--workers", type=RULES["workers"].arg("--workers"), default=None,
                   help="worker processes (default: the cores; 1 = serial, in this process)")
    p.add_argument("--out", required=True, help="output params JSON")
    p.add_argument("--no-companion", dest="companion", action="store_false",
                   help="skip the companion search without the impact term (fewer rollouts; OUT then has no "
                        "'impacts' comparison of the optimum with the unpenalized optimum)")
    p.add_argument("--quiet", action="store_true", help="no progress lines (the summary is still printed)")
    p.set_defaults(func=cmd_optimize)


def cmd_optimize(args) -> int:
    """Run the optimization, writing the params JSON after every batch (``planning.checkpoint``),
    print the summary (stderr), write the result, print one JSON line.

    ``cobra-ref optimize``. Exit status 0, or 130 after Ctrl-C and 143 after SIGTERM (the file is
    still written, with the best rollout so far); 1 with one line naming the file and where the
    result is when the final write fails.
    """
    check_writable(args.out)
    if args.workers is not None and args.workers < 1:
        raise SystemExit(f"error: --workers must be >= 1, got {args.workers}")
    d_goal, d_duration, d_maxiter = DEFAULTS[args.gait]
    goal = d_goal if args.goal is None else args.goal
    duration = d_duration if args.duration is None else args.duration
    maxiter = d_maxiter if args.maxiter is None else args.maxiter
    err = lambda line: print(line, file=sys.stderr, flush=True)  # noqa: E731
    with c_stdout_silenced():  # OSQP's "Polishing not needed" lines (workers: parallel.worker_init)
        try:
            space = DecisionSpace(bounds=_assignments(args.bound, 2, "--bound"),
                                  x0=_assignments(args.start, 1, "--start"), ramp_time=args.ramp_time)
            settings = StepSettings(dt=args.dt, contact=args.contact, servo=args.servo)
            problem = make_problem(args.gait, goal, duration, settings, space, box_gap=args.box_gap,
                                   cobra=model_parameters(args))
        except (ShootingError, ValidationError) as exc:
            raise SystemExit(f"error: {exc}") from None
        two = args.companion and problem.weights.impact > 0
        err(f"optimize {args.gait}: goal {goal} m from the box's start {np.round(problem.box_pose0[:2], 4)}, "
            f"{len(problem.names)} parameters ({', '.join(problem.names)}), {duration} s rollouts, maxiter {maxiter}; "
            + ("two searches: J, then the companion without the impact term (--no-companion skips it)" if two
               else "one search: J"))
        search = SearchOptions(method=args.method, maxiter=maxiter, seed=args.seed, popsize=args.popsize,
                               companion=args.companion)
        keeper = Checkpoint(args.out, err)
        result = optimize(problem, search, progress=None if args.quiet else err,
                          executor=SerialExecutor() if args.workers == 1 else None, workers=args.workers,
                          checkpoint=keeper)
    for line in summary_lines(result):
        err(line)
    try:
        record = keeper.final(result)
    except OutputError as exc:
        raise fail(exc) from None
    if not result.interrupted:
        err(f"wrote {args.out}")
    contact = record["contact"] or {}
    print(json.dumps({"out": args.out, "gait": args.gait, "params": record["params"], "cost": record["cost"],
                      "initial_cost": result.history[0]["cost"],
                      "box_distance_to_goal": record["box_distance_to_goal"], "rollouts": len(result.history),
                      "max_complementarity": contact.get("max_complementarity"),
                      "max_cone_residual": contact.get("max_cone_residual"),
                      "interrupted": result.interrupted, "wall_time": round(result.wall_time, 1)}))
    if result.interrupted:  # Ctrl-C or SIGTERM: the last line says what was kept
        return say_interrupted(None, f"the best of {len(result.history)} rollouts is kept in {args.out}")
    return 0
