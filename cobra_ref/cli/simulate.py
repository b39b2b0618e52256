"""``cobra-ref simulate``: one simulation of COBRA and the box, written to an NPZ, summarized in JSON.

Helper: the command-line side of :func:`cobra_ref.simulate.simulate`; ``--params`` replays an
optimum of ``cobra-ref optimize`` (:mod:`cobra_ref.planning.results`).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..gaits import gait_params
from ..params import CobraParameters
from ..planning.cost import shooting_cost
from ..planning.problem import ShootingError
from ..planning.results import ParamsRun, params_reference
from ..robots import cobra_model
from .common import check_writable, finite_float, run_and_write


def cmd_simulate(args) -> int:
    """Simulate COBRA and the box; write the trajectory NPZ; print a one-line JSON summary.

    Helper: the command line (cobra-ref simulate).
    """
    if args.params:
        return cmd_simulate_params(args)
    from ..reference import ReferenceError, builtin_reference, load_reference
    from ..step import StepSettings

    # check every input before the (long) run, so that bad input writes nothing
    check_writable(args.out)
    try:
        reference = load_reference(args.reference) if args.reference else builtin_reference(args.gait)
        settings = StepSettings(dt=args.dt, contact=args.contact, servo=args.servo)
    except (ReferenceError, ValueError) as exc:
        raise SystemExit(f"error: {exc}") from None
    params = CobraParameters()
    if args.mu_robot_box is not None:
        params = dataclasses.replace(params, mu_robot_box=args.mu_robot_box)
    try:
        model = cobra_model(params)
    except ValueError as exc:
        raise SystemExit(f"error: {exc}") from None
    run_and_write(model, reference, 10.0 if args.duration is None else args.duration, settings, args.out,
                  f"simulate {args.reference or args.gait}", args.quiet, stepper=args.stepper)
    return 0


def add_parsers(sub) -> None:
    """The ``simulate`` subcommand.

    Helper: the command line (cobra-ref simulate).
    """
    p = sub.add_parser("simulate", help="simulate COBRA pushing the box; write an NPZ, print a JSON summary",
                       description="Simulate COBRA and the box on flat ground for a joint reference. Writes every "
                                   "array (t, q, qd, tau, box_pose, per-step solver records, the contact log) to "
                                   "OUT.npz and prints a one-line JSON summary (box_displacement, "
                                   "max_penetration, max_cone_residual, real_time_factor).")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--gait", default="C", metavar="NAME",
                     help="a gait with its default parameters: C (default), S, J, J-mirror (lateral rolling, "
                          "A = 0.5 rad, 0.5 Hz), sidewinding (A = 0.6 rad); 'rolling' = C")
    src.add_argument("--reference", metavar="FILE", help="reference file: .npz (t, q) or .csv (t,J0..J10)")
    src.add_argument("--params", metavar="FILE", help="replay an optimum of 'cobra-ref optimize' (gait, parameters, "
                                                     "start state, dt, horizon)")
    p.add_argument("--duration", type=finite_float, default=None,
                   help="simulated time [s] (default 10; with --params the optimization's horizon)")
    p.add_argument("--dt", type=finite_float, default=1e-3, help="time step [s] (default 1e-3)")
    p.add_argument("--contact", choices=("compliant", "rigid"), default="compliant",
                   help="contact law: compliant (default, the paper's spring-damper contact) or rigid "
                        "(eq. (2)-(6) as written)")
    p.add_argument("--servo", choices=("position", "prescribed"), default="position",
                   help="joints: position (default, the paper's position control within tau_max) or prescribed "
                        "(the joints follow the reference exactly, torques recovered)")
    p.add_argument("--stepper", choices=("fast", "reference"), default="fast",
                   help="fast (default) or reference (the readable step, slow; the same physics)")
    p.add_argument("--mu-robot-box", type=finite_float, default=None,
                   help="friction coefficient of robot-box contacts (default 0.5, assumption A22)")
    p.add_argument("--out", default="run.npz", help="output NPZ (default run.npz)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_simulate)


def cmd_simulate_params(args) -> int:
    """``cobra-ref simulate --params FILE``: replay the optimum (its gait, parameters, start state,
    dt and, unless ``--duration`` is given, horizon); write the NPZ; print the JSON summary with the
    replayed and the recorded cost.

    Helper: ``cobra_ref.cli.cmd_simulate`` hands over when ``args.params`` is set (uses
    ``args.params``, ``args.duration`` (None = the JSON's), ``args.out``, ``args.quiet``).
    """
    check_writable(args.out)
    try:
        run = params_reference(args.params, duration=args.duration)
    except ShootingError as exc:
        raise SystemExit(f"error: {exc}") from None
    meta = {"gait": run.gait, "gait_params": gait_params(run.reference), "params_file": args.params}
    run_and_write(run.model, run.reference, run.duration, run.settings, args.out, f"simulate {args.params}",
                  args.quiet, run.q0, run.qd0, meta, lambda traj: params_summary(run, traj), stepper=args.stepper)
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
