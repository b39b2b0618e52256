"""``cobra-ref push``: push the box to a point (and through waypoints), re-planning every period.

The command-line side of :mod:`cobra_ref.planning.receding` (conventions: :mod:`cobra_ref.cli.common`).
"""

from __future__ import annotations

import contextlib
import json
import os
import sys

from ..infra.executors import SerialExecutor, own_pool
from ..infra.validation import RULES
from ..mjcf import TIMESTEP
from .common import (add_model_options, c_stdout_silenced, check_out, fail, interrupted_exit, model_parameters,
                     say_interrupted, write_text_atomic)


def add_parsers(sub) -> None:
    """Add the ``push`` subcommand to ``sub``."""
    from ..planning.receding import PushOptions

    d = PushOptions()
    p = sub.add_parser(
        "push", help="push the box to a point, re-planning every period (receding horizon)",
        description="Push the box to a goal (through waypoints): every PERIOD seconds, from the state reached, "
                    "roll out candidate primitives (rolling shapes with amplitude, frequency and taper, a "
                    "stop, and turns where the robot stands while it faces away from the goal) over HORIZON "
                    "periods, apply the best for one period, repeat; see "
                    "cobra_ref/planning/receding.py and docs/planning.md. One progress line per period on stderr, "
                    "one JSON line on stdout. OUT holds the executed run (an NPZ like simulate's); PLAN the chosen "
                    "primitives (a JSON that replays to the same run, bit for bit). Ctrl-C keeps what was executed.")
    p.add_argument("--goal", type=RULES["goal_pair"].arg("--goal"), default=None, metavar="X,Y",
                   help="where to push the box, relative to its start [m], world axes (x = the robot's initial "
                        "heading, y = its left; a negative X needs --goal=-0.1,0.2)")
    p.add_argument("--via", type=RULES["goal_pair"].arg("--via"), action="append", default=[], metavar="X,Y",
                   help="a waypoint on the way, same axes (repeatable, in order)")
    p.add_argument("--budget", type=RULES["push_budget"].arg("--budget"), default=d.budget,
                   help=f"simulated time at most [s] (default {d.budget:g})")
    p.add_argument("--period", type=RULES["push_period"].arg("--period"), default=d.period,
                   help=f"one re-plan per period [s] (default {d.period:g})")
    p.add_argument("--horizon", type=RULES["push_horizon"].arg("--horizon"), default=d.horizon,
                   help=f"periods each rollout looks ahead (default {d.horizon})")
    p.add_argument("--samples", type=RULES["push_samples"].arg("--samples"), default=d.samples,
                   help=f"noisy copies of the last choice per re-plan (default {d.samples})")
    p.add_argument("--tolerance", type=RULES["push_tolerance"].arg("--tolerance"), default=d.tolerance,
                   help=f"the push ends with the box within this of the goal [m] (default {d.tolerance:g})")
    p.add_argument("--seed", type=RULES["seed"].arg("--seed"), default=0, help="seed of the sampling noise (default 0)")
    p.add_argument("--dt", type=RULES["dt"].arg("--dt"), default=d.settings.dt,
                   help=f"time step of the rollouts [s] (default {d.settings.dt * 1e3:g} ms)")
    p.add_argument("--plant", choices=("cobra_ref", "mujoco"), default="cobra_ref",
                   help="what executes the plan: cobra_ref (default) or MuJoCo on the exported model at its "
                        f"{TIMESTEP * 1e3:g} ms step (the planner still predicts with cobra_ref; the state is read back every period)")
    p.add_argument("--plant-dt", type=RULES["dt"].arg("--plant-dt"), default=d.plant_dt,
                   help=f"time step of the plant that executes the plan [s] (default {d.plant_dt * 1e3:g} ms, the "
                        "figures'), e.g. 0.0005: the plan then runs in a finer world than the one it was predicted in")
    add_model_options(p)
    p.add_argument("--workers", type=RULES["workers"].arg("--workers"), default=None,
                   help="worker processes for the rollouts (default: the cores; 1 = serial, in this process)")
    p.add_argument("--out", required=True, help="the executed run (NPZ, exactly this name)")
    p.add_argument("--plan", default=None, help="the plan JSON (default: OUT without its extension + .plan.json)")
    p.add_argument("--replay", metavar="PLAN", default=None,
                   help="replay a plan JSON of an earlier push (no planning): OUT is then its executed run, bit for "
                        "bit; the other planner options are the plan's")
    p.add_argument("--benchmark", action="store_true",
                   help="push to the benchmark's 16 goals and 2 waypoint paths (cobra_ref/planning/benchmark.py) "
                        "instead of --goal; OUT is then the JSON of the rows (rewritten after each task)")
    p.add_argument("--figure", default=None, help="--benchmark: also draw every box path with its goal (PNG)")
    p.add_argument("--task", action="append", default=[], metavar="NAME",
                   help="--benchmark: only this task (repeatable; e.g. 180deg-0.50m, path-left)")
    p.add_argument("--plans", default=None, metavar="DIR",
                   help="--benchmark: also write each task's plan JSON to DIR/NAME.plan.json (it replays with "
                        "--replay and holds every re-plan's candidates and costs)")
    p.add_argument("--travel-map", action="store_true",
                   help="no push: measure where each primitive takes the robot alone, per cycle (every rolling "
                        "shape at five tapers, sidewinding both ways; cobra_ref/planning/locomotion.py); OUT is the "
                        "JSON of the rows, the table goes to stdout")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_push)


def cmd_push(args) -> int:
    """Run the push, write the run and the plan, print one JSON line. Exit 0 when the box reached
    the goal, 1 when the budget ran out first, 130 after Ctrl-C and 143 after SIGTERM (what was
    executed is written)."""
    from ..planning.plan_file import push_record
    from ..planning.receding import push

    only = [name for name, given in (("--figure", args.figure), ("--task", args.task), ("--plans", args.plans)) if given]
    if only and not args.benchmark:
        raise fail(f"{only[0]} applies only with --benchmark")
    if args.replay is not None:
        return _replay(args)
    if args.benchmark:
        return _benchmark(args)
    if args.travel_map:
        return _travel_map(args)
    if args.goal is None:
        raise fail("give --goal X,Y (or --replay PLAN)")
    plan_path = args.plan or os.path.splitext(args.out)[0] + ".plan.json"
    check_out(args.out, "--out")
    check_out(plan_path, "--plan")
    options = _options(args)
    err = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    stop = None  # the interrupt (Ctrl-C or SIGTERM) that ended the push
    with c_stdout_silenced():
        try:
            with _executor(args.workers) as executor:
                result = push(options, executor, progress=err, plant=_plant_factory(options.plant))
        except KeyboardInterrupt as exc:
            result, stop = getattr(exc, "result", None), exc
            if result is None:
                raise interrupted_exit(exc, "nothing was executed") from None
    record = push_record(result, options)
    try:
        result.trajectory.to_npz(args.out)
    except OSError as exc:
        raise fail(f"{args.out}: {exc}") from None
    write_text_atomic(plan_path, json.dumps(record, indent=1) + "\n", "--plan")
    print(f"{result.reason}: box {100 * record['final_distance']:.2f} cm from the goal after "
          f"{record['simulated_time']:g} s; wrote {args.out} and {plan_path}", file=sys.stderr)
    print(json.dumps({k: record[k] for k in ("reached", "reason", "final_distance", "simulated_time",
                                             "impact_impulse_per_second", "rollouts", "wall_time")}))
    if stop is not None:
        return say_interrupted(stop, f"the {record['simulated_time']:g} s executed are in {args.out} and {plan_path}")
    return 0 if result.reached else 1


def _replay(args) -> int:
    """``push --replay PLAN --out OUT``: the executed run of a plan, written to OUT."""
    from ..planning.plan_file import load_push
    from ..planning.receding import replay

    check_out(args.out, "--out")
    try:
        with open(args.replay, encoding="utf-8") as f:
            plan, options = load_push(json.load(f))
    except (OSError, ValueError, KeyError, TypeError, RecursionError) as exc:
        raise fail(f"--replay {args.replay}: {exc}") from None
    with c_stdout_silenced():
        traj = replay(plan, options, plant=_plant_factory(options.plant))
    try:
        traj.to_npz(args.out)
    except OSError as exc:
        raise fail(f"{args.out}: {exc}") from None
    print(json.dumps(traj.summary()))
    return 0


def _options(args):
    """The ``PushOptions`` of the command line."""
    from ..planning.receding import PushOptions
    from ..step import StepSettings

    return PushOptions(goal=args.goal if args.goal is not None else (0.25, 0.0), via=tuple(args.via), budget=args.budget, period=args.period,
                       horizon=args.horizon, samples=args.samples, tolerance=args.tolerance, seed=args.seed,
                       settings=StepSettings(dt=args.dt), cobra=model_parameters(args), plant_dt=args.plant_dt,
                       plant=args.plant)


@contextlib.contextmanager
def _executor(workers):
    """The rollouts' executor: serial with ``--workers 1``, else a process pool of our own."""
    if workers == 1:
        yield SerialExecutor()
    else:
        with own_pool(workers) as executor:
            yield executor


def _benchmark(args) -> int:
    """``push --benchmark``: every benchmark task, the rows written to OUT after each one."""
    from ..planning.benchmark import run_benchmark, select, summary

    check_out(args.out, "--out")
    if args.figure:
        check_out(args.figure, "--figure")
    try:
        tasks = select(args.task)
    except ValueError as exc:
        raise fail(f"--task: {exc}") from None
    if args.plans:
        try:
            os.makedirs(args.plans, exist_ok=True)
        except OSError as exc:
            raise fail(f"--plans {args.plans}: {exc}") from None
    err = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))

    def keep(rows):
        write_text_atomic(args.out, json.dumps({"summary": summary(rows), "rows": rows}, indent=1) + "\n", "--out")

    def keep_plan(name, record):
        path = os.path.join(args.plans, f"{name}.plan.json")
        write_text_atomic(path, json.dumps(record, indent=1) + "\n", "--plans")

    with c_stdout_silenced():
        with _executor(args.workers) as executor:
            rows = run_benchmark(_options(args), executor, tasks=tasks, progress=err, keep=keep,
                                 plant=_plant_factory(args.plant), keep_plan=keep_plan if args.plans else None)
    if args.figure:
        from ..viz.push_paths import plot_pushes

        plot_pushes(rows, args.figure)
    print(json.dumps(summary(rows)))
    return 0


def _travel_map(args) -> int:
    """``push --travel-map``: the travel of every primitive (``planning.locomotion``), to OUT and stdout."""
    from ..planning.locomotion import locomotion_map, markdown

    check_out(args.out, "--out")
    err = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    with c_stdout_silenced():
        with _executor(args.workers) as executor:
            rows = locomotion_map(executor=executor, progress=err)
    write_text_atomic(args.out, json.dumps([r.to_dict() for r in rows], indent=1) + "\n", "--out")
    print(markdown(rows), end="")
    return 0


def _plant_factory(name: str):
    """The plant of ``--plant``: None (the planner's own ``simulate.Run``) or MuJoCo's."""
    if name != "mujoco":
        return None
    from ..reproduce.mujoco_check import mujoco_available
    from ..reproduce.mujoco_plant import MujocoPlant

    if not mujoco_available():
        raise fail("--plant mujoco needs MuJoCo: pip install mujoco (or the mujoco extra)")
    return MujocoPlant
