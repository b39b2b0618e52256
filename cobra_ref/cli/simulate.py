"""``cobra-ref simulate``: one simulation of COBRA and the box, written to an NPZ, summarized in JSON.

The command-line side of :func:`cobra_ref.simulate.simulate`; ``--params`` replays an
optimum of ``cobra-ref optimize`` (:mod:`cobra_ref.planning.results`). Every input is checked
before the run (:mod:`cobra_ref.infra.validation`): the options, the reference (angles within q_max,
rates against qd_max), the time grid, the output; each option is recorded in the NPZ's ``meta``
(``options``) so that a run can be repeated.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

from ..gaits import GAITS, gait_params
from ..planning.cost import shooting_cost
from ..planning.problem import ShootingError
from ..planning.results import ParamsRun, params_reference
from ..robots import cobra_model
from ..steppers import STEPPERS
from ..infra.validation import DEFAULT_DT, RULES, ValidationError, number_text, step_count
from .common import (Job, add_model_options, c_stdout_silenced, check_out, fail, gait_param, inputs_text,
                     model_parameters, run_and_write)

DEFAULT_DURATION = 10.0  # [s] (assumption A11)
# options that change the model or the start: an error with --params, which replays the optimum's own
MODEL_OPTIONS = (("mu", "--mu"), ("mu_robot_box", "--mu-robot-box"), ("mu_box_ground", "--mu-box-ground"),
                 ("box_mass", "--box-mass"),
                 ("box_offset", "--box-offset"), ("box_yaw", "--box-yaw"), ("box_gap", "--box-gap"),
                 ("param", "--param"))
# the step settings: with --params each one given wins over the optimum's (recorded in the run's meta)
STEP_OPTIONS = {"dt": DEFAULT_DT, "contact": "compliant", "servo": "position", "touchdown_substeps": None}


def cmd_simulate(args) -> int:
    """``cobra-ref simulate``: simulate COBRA and the box; write the trajectory NPZ; print a
    one-line JSON summary. Every input is checked before the run; ``--params`` hands over to
    ``cmd_simulate_params``."""
    if args.params is not None:
        return cmd_simulate_params(args)
    from ..infra.arguments import ArgumentTypeError
    from ..reference import ReferenceError, builtin_reference, check_reference, load_reference
    from ..step import StepSettings

    # check every input before the (long) run, so that bad input writes nothing
    check_out(args.out)
    params = _gait_params(args.param)
    if params and args.reference is not None:
        raise fail("--param sets the parameters of a built-in gait (--gait); a --reference file has none")
    if args.box_offset is not None and args.box_gap is not None:
        raise fail("--box-gap places the box beside the middle link, --box-offset places it at an offset from "
                   "the middle: give one of them")
    try:  # --dt is checked by its option's rule: trusted here
        settings = StepSettings(**{k: default if getattr(args, k) is None else getattr(args, k)
                                   for k, default in STEP_OPTIONS.items()})
        duration = DEFAULT_DURATION if args.duration is None else args.duration
        step_count(duration, settings.dt, exact=True, duration_field="--duration", dt_field="--dt")
        cobra = model_parameters(args)
    except ValueError as exc:  # ValidationError
        raise fail(exc) from None
    from_file = args.reference is not None
    source = args.reference if from_file else f"gait {args.gait}"
    try:
        reference = (load_reference(args.reference, cobra.q_max) if from_file
                     else builtin_reference(args.gait, params))
        warnings = check_reference(reference, duration, cobra.q_max, cobra.qd_max, source)
    except (ReferenceError, ArgumentTypeError) as exc:  # a bad file, or an empty --reference ''
        raise fail(exc) from None
    for line in warnings:
        print(f"warning: {line}", file=sys.stderr)
    if not args.out.endswith(".npz"):
        print(f"note: the NPZ is written under the exact name {args.out!r} (no .npz is added)", file=sys.stderr)
    model = cobra_model(cobra)
    inputs = inputs_text(settings, cobra, stepper=args.stepper, box_gap=args.box_gap, box_offset=args.box_offset,
                         box_yaw=args.box_yaw)
    q0, qd0 = _start(model, reference, settings, args, inputs)
    meta = {"options": _options(args, duration, settings), "cobra_parameters": dataclasses.asdict(cobra),
            "reference": args.reference, "gait": None if from_file else args.gait,
            "gait_params": None if from_file else gait_params(reference)}
    run_and_write(Job(model, reference, duration, settings, q0, qd0, args.stepper, inputs), args.out,
                  f"simulate {source}", args.quiet, meta)
    return 0


def _gait_params(items) -> dict:
    """{name: value} of the --param options (each name once)."""
    out = {}
    for name, value in items or ():
        if name in out:
            raise fail(f"--param {name} is given twice ({out[name]:g} and {value:g})")
        out[name] = value
    return out


def _start(model, reference, settings, args, inputs: str):
    """(q0, qd0): the placed and settled start with the box options (``start.initial_state``); a
    placement deep in the ground or the box is refused before it settles; a failure of the settling
    names the ``inputs``."""
    from ..simulate import check_start
    from ..start import BoxPlacement, initial_state, placed_state
    from ..step import SimulationError

    gap = 0.05 if args.box_gap is None else args.box_gap
    placement = BoxPlacement(offset=args.box_offset, gap=gap, yaw=args.box_yaw)
    try:
        check_start(model, placed_state(model, reference, placement))
    except SimulationError as exc:
        hint = "; place the box elsewhere with --box-offset DX,DY or --box-gap" if "robot-box" in str(exc) else ""
        raise fail(f"{exc}{hint}") from None
    try:
        with c_stdout_silenced():
            return initial_state(model, reference, settings, placement, stepper=args.stepper)
    except Exception as exc:  # noqa: BLE001 -- the settling steps can fail in any solver
        raise fail(f"the start could not be placed and settled: {type(exc).__name__}: {exc} ({inputs})") from None


def step_record(settings) -> dict:
    """The step options a run used, for its NPZ's meta: the touch-down substeps as taken (A33)."""
    return {k: getattr(settings, k) for k in STEP_OPTIONS} | {"touchdown_substeps": settings.substeps}


def _options(args, duration: float, settings) -> dict:
    """The options of the run, JSON-ready (recorded in the NPZ's meta), with the defaults it used."""
    skip = {"func", "command", "quiet"}
    out = {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(args).items() if k not in skip}
    out.update(duration=duration, **step_record(settings))
    out["param"] = dict(args.param or [])
    return out


def gait_name(text: str) -> str:
    """argparse type: a built-in gait's name (``gaits.GAITS``).
    """
    if text not in GAITS:
        raise argparse.ArgumentTypeError(f"unknown gait {text!r}; gaits: {', '.join(GAITS)}")
    return text


gait_name.allowed = ", ".join(GAITS)


def add_parsers(sub) -> None:
    """Add the ``simulate`` subcommand to ``sub``."""
    p = sub.add_parser("simulate", help="simulate COBRA pushing the box; write an NPZ, print a JSON summary",
                       description="Simulate COBRA and the box on flat ground for a joint reference. Writes every "
                                   "array (t, q, qd, tau, box_pose, per-step solver records, the contact log) to "
                                   "OUT (exactly that name) and prints a one-line JSON summary (box_displacement, "
                                   "max_penetration, max_cone_residual, real_time_factor, tau_beyond_limit, "
                                   "contact_force_beyond_bound). A run that left physics (joint torques beyond "
                                   "tau_max with --servo prescribed, or a contact force beyond the bound of A32) "
                                   "prints one warning line on stderr. A run that fails part-way, or is stopped by "
                                   "Ctrl-C or SIGTERM, keeps what was computed in OUT.failed.npz.")
    src = p.add_mutually_exclusive_group()
    src.add_argument("--gait", default="C", metavar="NAME", type=gait_name,
                     help="a gait with its default parameters: C (default), S, J, J-mirror (lateral rolling, "
                          "A = 0.5 rad, 0.5 Hz), sidewinding (A = 0.6 rad); 'rolling' = C")
    src.add_argument("--reference", metavar="FILE", help="reference file: .npz (t, q) or .csv (t,J0..J10); every "
                                                         "angle within |q| <= pi/2 rad")
    src.add_argument("--params", metavar="FILE", help="replay an optimum of 'cobra-ref optimize' (gait, parameters, "
                                                     "model and start state from the file; dt, contact, servo "
                                                     "and horizon too unless --dt, --contact, --servo or "
                                                     "--duration replaces them)")
    p.add_argument("--param", action="append", default=[], type=gait_param, metavar="NAME=VALUE",
                   help="a parameter of the --gait (repeatable), e.g. amplitude=0.4 (rad), frequency=0.7 (Hz); "
                        "the gait checks its range")
    p.add_argument("--duration", type=RULES["duration"].arg("--duration"), default=None,
                   help=f"simulated time [s], a whole number of steps (default {DEFAULT_DURATION:g}; with --params "
                        "the optimization's horizon)")
    p.add_argument("--dt", type=RULES["dt"].arg("--dt"), default=None,
                   help=f"time step [s] (default {number_text(DEFAULT_DT)}; with --params the optimization's, "
                        "which --dt replaces)")
    p.add_argument("--contact", choices=("compliant", "rigid"), default=None,
                   help="contact law: compliant (the paper's spring-damper contact) or rigid (eq. (2)-(6) as "
                        "written) (default compliant; with --params the optimization's, which --contact replaces)")
    p.add_argument("--servo", choices=("position", "prescribed"), default=None,
                   help="joints: position (the paper's position control within tau_max) or prescribed (the joints "
                        "follow the reference exactly, torques recovered) (default position; with --params the "
                        "optimization's, which --servo replaces)")
    p.add_argument("--touchdown-substeps", type=RULES["touchdown_substeps"].arg("--touchdown-substeps"), default=None,
                   metavar="N", help="take the steps around a contact's touch-down as N steps of dt / N (A33; "
                                     "default: 2 for the compliant law, 1 for the rigid law; 1: whole steps)")
    p.add_argument("--stepper", choices=STEPPERS, default="fast",
                   help="fast (default) or reference (the readable step, slow; the same physics)")
    add_model_options(p)
    p.add_argument("--box-offset", type=RULES["box_offset_pair"].arg("--box-offset"), default=None, metavar="DX,DY",
                   help="the box's centre relative to the middle of the robot [m], world axes (x = the robot's "
                        "heading, y = its left; a negative DX needs --box-offset=-0.1,0.2); default: beside the "
                        "middle link (A9)")
    p.add_argument("--box-yaw", type=RULES["box_yaw"].arg("--box-yaw"), default=None,
                   help="the box's heading about the vertical [rad], world axes (default: a face towards the robot; "
                        "0 with --box-offset)")
    p.add_argument("--box-gap", type=RULES["box_gap"].arg("--box-gap"), default=None,
                   help="gap between the box and the middle link at the start [m] (default 0.05; A9)")
    p.add_argument("--out", default="run.npz", help="output NPZ, written under exactly this name (default run.npz)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_simulate)


def cmd_simulate_params(args) -> int:
    """``cobra-ref simulate --params FILE``: replay the optimum (its gait, parameters, model and
    start state); write the NPZ; print the JSON summary with the replayed and the recorded cost.
    ``cmd_simulate`` hands over when ``args.params`` is set; this uses ``args.params``,
    ``args.duration`` (None = the JSON's), ``args.out``, ``args.quiet``, ``args.stepper`` and, when
    present, the step options and ``MODEL_OPTIONS``. ``--duration``, ``--dt``, ``--contact`` and
    ``--servo``, when given, replace the optimization's (recorded in the meta's ``options`` and
    ``overrides``; the costs are then not compared); an option of ``MODEL_OPTIONS`` is an error.
    """
    from ..reference import ReferenceError, check_reference
    from ..step import SimulationError

    check_out(args.out)
    for name, option in MODEL_OPTIONS:
        if getattr(args, name, None) not in (None, []):
            raise fail(f"--params replays the optimum with its own model and start: {option} cannot be combined "
                       "with it (the step options --dt, --contact, --servo, --touchdown-substeps and --duration can)")
    step = {k: getattr(args, k) for k in STEP_OPTIONS if getattr(args, k, None) is not None}
    try:
        run = params_reference(args.params, duration=args.duration, step=step)
        cobra = run.problem.cobra
        for line in check_reference(run.reference, run.duration, cobra.q_max, cobra.qd_max, f"gait {run.gait}"):
            print(f"warning: {line}", file=sys.stderr)
    except (ShootingError, ReferenceError, ValidationError, SimulationError) as exc:
        raise fail(exc) from None
    overrides = {**step, **({} if args.duration is None else {"duration": args.duration})}
    meta = {"gait": run.gait, "gait_params": gait_params(run.reference), "params_file": args.params,
            "options": {"params": args.params, "duration": run.duration, "stepper": args.stepper,
                        **step_record(run.settings), "overrides": overrides}}
    job = Job(run.model, run.reference, run.duration, run.settings, run.q0, run.qd0, args.stepper,
              inputs_text(run.settings, run.problem.cobra, stepper=args.stepper, params=args.params))
    run_and_write(job, args.out, f"simulate {args.params}", args.quiet, meta, lambda traj: params_summary(run, traj))
    return 0


def params_summary(run: ParamsRun, traj) -> dict:
    """The replayed cost next to the recorded one (when the horizon is the optimization's).

    Extra keys for the JSON line of ``cobra-ref simulate --params``.
    """
    if run.duration != run.problem.duration or run.settings != run.problem.settings:
        return {"params_cost": None, "note": "horizon or step settings differ from the optimization's: cost not "
                                             "comparable"}
    c = shooting_cost(run.problem, traj)
    out = {"params_cost": c["cost"], "recorded_cost": run.recorded_cost,
           "cost_matches": c["cost"] == run.recorded_cost, "box_distance_to_goal": c["box_distance_to_goal"]}
    if not run.same_code:
        out["note"] = "the physics code changed since this optimum was found: the costs need not match"
    return out
