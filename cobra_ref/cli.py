"""The ``cobra-ref`` command: subcommands for every user-facing job (``cobra-ref --help``)."""

from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import sys

import numpy as np

from .parallel import limit_blas_threads
from .progress import progress_printer
from .params import CobraParameters, parameter_table
from .robots import cobra_model

_AXIS_NAME = {"Rx": "roll (x)", "Ry": "pitch (y)", "Rz": "yaw (z)", "free": "free (6 DoF)"}


def cmd_info(args) -> int:
    """Print the model: bodies, masses, inertias, joints, limits, length, each with its source."""
    params = CobraParameters()
    model = cobra_model(params)
    out = sys.stdout
    out.write(f"COBRA + box scene '{model.name}': {model.nb} bodies, nq = {model.nq}, nv = {model.nv}\n")
    out.write(f"robot alone: nq = {model.nq - 7}, nv = {model.nv - 6} (the paper's M is 17 x 17)\n\n")
    out.write(f"{'body':<6}{'parent':<8}{'joint':<10}{'axis':<14}{'mass kg':>8}  "
              f"{'Ixx, Iyy, Izz at COM [kg m^2]':<34}{'COM in body frame [m]'}\n")
    for i in range(model.nb):
        parent = "world" if model.parent[i] < 0 else model.body_names[model.parent[i]]
        Id = np.diag(model.I_com[i])
        out.write(f"{model.body_names[i]:<6}{parent:<8}{model.joint_names[i]:<10}"
                  f"{_AXIS_NAME[model.joint_type[i]]:<14}{model.mass[i]:>8.3f}  "
                  f"{Id[0]:.4e} {Id[1]:.4e} {Id[2]:.4e}    {np.round(model.com[i], 4)}\n")
    out.write(f"\njoint limits |q| <= {params.q_max:.4f} rad, |tau| <= {params.tau_max} N m, "
              f"|qd| <= {params.qd_max} rad/s (J0..J10; even = yaw, odd = pitch)\n")
    out.write(f"total length {params.total_length:.3f} m (head + 10 links + tail + 11 gaps)\n")
    out.write(f"contact spheres: {len(model.spheres.radius)} (radius, body): "
              + ", ".join(f"{r * 1000:.1f} mm on {model.body_names[b]}"
                          for b, r in zip(model.spheres.body, model.spheres.radius)) + "\n")
    out.write(f"robot mass {sum(model.mass[:-1]):.2f} kg, box {params.box_size} m cube of "
              f"{params.box_mass} kg (I = {params.box_inertia:.3e} kg m^2)\n\n")
    out.write("parameters and their sources:\n")
    for name, value, unit, source in parameter_table(params):
        out.write(f"  {name:<24}{str(value):<34}{unit:<8}{source}\n")
    return 0


def cmd_export_mjcf(args) -> int:
    """Write the COBRA + box scene as MJCF (atomically: nothing half-written on failure)."""
    from .mjcf import to_mjcf

    xml = to_mjcf(cobra_model(with_box=not args.no_box), timestep=args.timestep)
    write_text_atomic(args.out, xml)
    print(f"wrote {args.out} ({len(xml)} bytes)")
    return 0


def write_text_atomic(path: str, text: str) -> None:
    """Check the directory (a clear error), then write through a temporary file and a rename."""
    from .atomic import write_text

    _check_writable(path)
    write_text(path, text)


@contextlib.contextmanager
def c_stdout_silenced():
    """Discard what C libraries print on file descriptor 1 while the block runs: OSQP prints
    "Polishing not needed ..." once per solve even with verbose off, thousands of lines per run.
    stdout then carries only the command's own output (its JSON line, printed after the block);
    progress goes to stderr."""
    sys.stdout.flush()
    saved, devnull = os.dup(1), os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(devnull, 1)
        yield
    finally:
        sys.stdout.flush()
        os.dup2(saved, 1)
        os.close(saved)
        os.close(devnull)


def _check_writable(path: str) -> None:
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise SystemExit(f"error: output directory does not exist: {directory}")
    if not os.access(directory, os.W_OK):
        raise SystemExit(f"error: output directory is not writable: {directory}")


def cmd_simulate(args) -> int:
    """Simulate COBRA and the box; write the trajectory NPZ; print a one-line JSON summary."""
    if args.params:
        from .cli_optimize import cmd_simulate_params

        return cmd_simulate_params(args)
    from .reference import ReferenceError, builtin_reference, load_reference
    from .stepper import StepSettings

    # check every input before the (long) run, so that bad input writes nothing
    _check_writable(args.out)
    try:
        reference = load_reference(args.reference) if args.reference else builtin_reference(args.gait)
        settings = StepSettings(dt=args.dt, servo=args.servo, osqp=args.osqp)
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
                  f"simulate {args.reference or args.gait}", args.quiet)
    return 0


def run_and_write(model, reference, duration, settings, out, label, quiet=False, q0=None, qd0=None,
                  meta=None, summary=None):
    """Simulate, write the NPZ and print the one-line JSON summary (plus ``summary(traj)``'s keys);
    a failure mid-run writes what was computed to OUT.failed.npz and exits with the error."""
    from .simulate import simulate
    from .stepper import SimulationError

    progress = None if quiet else progress_printer(label)
    try:
        with c_stdout_silenced():
            traj = simulate(model, reference, duration, settings, q0, qd0, progress=progress)
    except SimulationError as exc:
        if exc.trajectory is None:  # bad input: nothing was computed, nothing is written
            raise SystemExit(f"error: {exc}") from None
        failed = os.path.splitext(out)[0] + ".failed.npz"
        exc.trajectory.to_npz(failed)
        print(json.dumps(exc.trajectory.summary()))
        raise SystemExit(f"error: {exc}\nwhat was computed up to the failure is in {failed}") from None
    traj.meta.update(meta or {})
    traj.to_npz(out)
    print(json.dumps({**traj.summary(), **(summary(traj) if summary else {})}))
    return traj


def cmd_bench(args) -> int:
    """Time per step of the full model while rolling with the box, and MuJoCo's on the same MJCF."""
    from .bench import format_table, run_bench

    if args.json:
        _check_writable(args.json)
    if not (np.isfinite(args.duration) and args.duration > 0):
        raise SystemExit(f"error: duration must be positive and finite, got {args.duration}")
    with c_stdout_silenced():
        record = run_bench(args.duration, with_mujoco=not args.no_mujoco,
                           progress=None if args.quiet else progress_printer("bench"))
    print(format_table(record))
    if args.json:
        write_text_atomic(args.json, json.dumps(record, indent=2) + "\n")
        print(f"wrote {args.json}")
    return 0


def cmd_figures(args) -> int:
    """Regenerate figures 3-9, the GIFs and the claims report (``regenerate`` module)."""
    from .reproduce import PAPER_GAITS
    from .regenerate import OPTIMIZED_DIR, check_output_dir, regenerate

    gaits = PAPER_GAITS if args.gaits is None else tuple(g.strip() for g in args.gaits.split(","))
    unknown = [g for g in gaits if g not in PAPER_GAITS]
    if unknown:
        raise SystemExit(f"error: unknown gait(s) {', '.join(unknown)}; gaits: {', '.join(PAPER_GAITS)}")
    try:
        check_output_dir(args.out)
    except OSError as exc:
        raise SystemExit(f"error: {exc}")
    with c_stdout_silenced():
        result = regenerate(args.out, quick=args.quick, force=args.force, cache_dir=args.cache,
                            workers=args.jobs, mujoco=not args.no_mujoco, progress=not args.quiet, gaits=gaits,
                            optimized_dir=None if args.defaults else OPTIMIZED_DIR,
                            reoptimize_all=args.reoptimize)
    print(json.dumps({"out": args.out, "files": len(result["files"]),
                      "claims": {c["id"]: c["holds"] for c in result["claims"]},
                      "seconds": round(result["seconds"], 1)}))
    return 0


def _finite_float(text: str) -> float:
    """argparse type: a float, rejected if not finite (the message names the value)."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"not a number: {text!r}") from None
    if not np.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be finite, got {text}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="cobra-ref",
        description="Reference implementation of COBRA's non-impulsive contact-implicit "
                    "loco-manipulation (arXiv 2404.08714).",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    p = sub.add_parser("info", help="print the model with the source of every number")
    p.set_defaults(func=cmd_info)
    p = sub.add_parser("export-mjcf", help="write the model as MuJoCo MJCF XML")
    p.add_argument("out", metavar="OUT.xml", help="output file")
    p.add_argument("--timestep", type=float, default=1e-3, help="MuJoCo timestep [s] (default 1e-3)")
    p.add_argument("--no-box", action="store_true", help="export the robot alone")
    p.set_defaults(func=cmd_export_mjcf)

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
    p.add_argument("--duration", type=_finite_float, default=None,
                   help="simulated time [s] (default 10; with --params the optimization's horizon)")
    p.add_argument("--dt", type=_finite_float, default=1e-3, help="time step [s] (default 1e-3)")
    p.add_argument("--servo", choices=("prescribed", "pd"), default="prescribed",
                   help="joint servo (default prescribed: the joints follow the reference exactly)")
    p.add_argument("--osqp", choices=("every-step", "fallback"), default="every-step",
                   help="OSQP solves every step's contact problem (default), or only those the certified "
                        "active-set path cannot (faster, same answers to OSQP's tolerance)")
    p.add_argument("--mu-robot-box", type=_finite_float, default=None,
                   help="friction coefficient of robot-box contacts (default 0.5, assumption C22)")
    p.add_argument("--out", default="run.npz", help="output NPZ (default run.npz)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_simulate)

    p = sub.add_parser("bench", help="time per step against MuJoCo on the same model (a benchmark)")
    p.add_argument("--duration", type=_finite_float, default=2.0, help="simulated time [s] (default 2)")
    p.add_argument("--json", metavar="FILE", help="also write the record as JSON")
    p.add_argument("--no-mujoco", action="store_true", help="skip the MuJoCo comparison")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_bench)

    p = sub.add_parser("figures", help="regenerate the paper's figures 3-9, GIFs and the claims report",
                       description="Simulate the five gaits (10 s each; 1 s with --quick; with the optimized "
                                   "parameters of cobra_ref/optimized/ where present) on all cores, or read "
                                   "them from the cache, and write fig03_snapshots.png ... fig09_box_distance.png "
                                   "(+ PDF), anim_<gait>.gif, claims.json, claims.md and summary.json to --out. "
                                   "Prints a one-line JSON summary.")
    p.add_argument("--out", default="figures", help="output directory (default figures)")
    p.add_argument("--quick", action="store_true", help="1 s simulations instead of 10 s (for tests)")
    p.add_argument("--force", action="store_true", help="ignore the cache: simulate and draw everything again")
    p.add_argument("--cache", default=None, help="simulation cache directory (default OUT/.cache)")
    p.add_argument("--jobs", type=int, default=None, help="worker processes (default: the number of cores)")
    p.add_argument("--gaits", default=None, help="comma-separated subset of C,S,J,J-mirror,sidewinding")
    p.add_argument("--no-mujoco", action="store_true", help="skip the MuJoCo rollout cross-check")
    p.add_argument("--defaults", action="store_true",
                   help="simulate every gait with its default parameters (notes C10) instead of the optimized "
                        "ones committed in cobra_ref/optimized/")
    p.add_argument("--reoptimize", action="store_true",
                   help="first re-run 'cobra-ref optimize' for every gait and the three direction goals, into "
                        "OUT/optimized/, and use those (about 20 min)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_figures)

    from .cli_optimize import add_parsers as add_optimize_parsers

    add_optimize_parsers(sub)
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    # one BLAS thread: the matrices are 23 x 23, where threads cost more than they save
    # (parallel.limit_blas_threads; 4x on a loaded machine, bit-identical results)
    limit_blas_threads(1)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    return args.func(args)
