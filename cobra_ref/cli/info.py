"""``cobra-ref info`` and ``cobra-ref export-mjcf``: the model as a table with its sources, and as MJCF.

The command-line side of :mod:`cobra_ref.params`, :mod:`cobra_ref.robots` and :mod:`cobra_ref.mjcf`.
"""

from __future__ import annotations

import sys

import numpy as np

from ..mjcf import TIMESTEP
from ..params import CobraParameters, parameter_table
from ..robots import cobra_model
from ..infra.validation import RULES
from .common import check_out, write_text_atomic

_AXIS_NAME = {"Rx": "roll (x)", "Ry": "pitch (y)", "Rz": "yaw (z)", "free": "free (6 DoF)"}


def cmd_info(args) -> int:
    """Print the model: bodies, masses, inertias, joints, limits, length, each with its source.
    """
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
    """Write the COBRA + box scene as MJCF with a keyframe ``start`` (atomically: nothing
    half-written on failure; through a symbolic link to its target; a directory or a device is
    refused, see :mod:`cobra_ref.infra.output`).
    """
    from ..mjcf import playable_mjcf

    check_out(args.out, "OUT.xml")  # before any work: exact name, a regular file (or a link to one)
    model = cobra_model(with_box=not args.no_box)
    q, source = start_pose(args, model)
    xml = playable_mjcf(model, q, timestep=args.timestep)
    write_text_atomic(args.out, xml, "OUT.xml")
    print(f"wrote {args.out} ({len(xml)} bytes; keyframe 'start': {source})")
    return 0


def start_pose(args, model) -> tuple[np.ndarray, str]:
    """(q, what it is) of the export's keyframe: the state of ``--from`` at ``--at`` (the robot's
    part of it with ``--no-box``), or the settled start of the C gait (A25).
    """
    if args.source is None:
        if args.at is not None:
            raise SystemExit("error: --at needs --from RUN.npz")
        from ..gaits import gait
        from ..start import initial_state

        return initial_state(model, gait("C"))[0], "the settled start of the C gait"
    from ..viz.scene import state_indices
    from .view import read_run

    traj = read_run(args.source)
    at = 0.0 if args.at is None else args.at
    if at > traj.duration:
        raise SystemExit(f"error: --at {at:g} s is outside the run (0 to {traj.duration:g} s)")
    k = int(state_indices(traj, [traj.t[0] + at])[0])
    return traj.q[k][:model.nq], f"{args.source} at t = {traj.t[k] - traj.t[0]:.4f} s"


def add_parsers(sub) -> None:
    """The ``info`` and ``export-mjcf`` subcommands.
    """
    p = sub.add_parser("info", help="print the model with the source of every number")
    p.set_defaults(func=cmd_info)
    p = sub.add_parser("export-mjcf", help="write the model as MuJoCo MJCF XML, with a keyframe to start from",
                       description="Write COBRA and the box as MJCF for MuJoCo (the same bodies, contact law and "
                                   "servo, A27), with a checker ground and a keyframe 'start': qpos = a state at "
                                   "rest on the ground, ctrl = its joint angles (the servo holds them), qvel = 0. "
                                   "The state is the settled start of the C gait (A25: the start every "
                                   "'cobra-ref simulate' run of C begins from), or the state of --from RUN.npz at "
                                   "--at. Open it with: python -m mujoco.viewer --mjcf=OUT.xml, then load the key "
                                   "(the Simulation panel's Load key, with Key on 0).")
    p.add_argument("out", metavar="OUT.xml", help="output file, written under exactly this name (a symbolic link: "
                                                  "its target; never a directory or a device)")
    p.add_argument("--timestep", type=RULES["timestep"].arg("--timestep"), default=TIMESTEP,
                   help=f"MuJoCo timestep [s] (default {TIMESTEP:g}: the exported stiff contact needs it, A27)")
    p.add_argument("--no-box", action="store_true", help="export the robot alone")
    p.add_argument("--from", dest="source", metavar="RUN.npz", default=None,
                   help="take the keyframe from this run (of cobra-ref simulate --out) instead of the C gait's start")
    p.add_argument("--at", type=RULES["at"].arg("--at"), default=None,
                   help="time [s] from the run's start of the --from state (default 0; the nearest state)")
    p.set_defaults(func=cmd_export_mjcf)
