"""The ``cobra-ref`` command: subcommands for every user-facing job (``cobra-ref --help``)."""

from __future__ import annotations

import argparse
import os
import sys
import tempfile

import numpy as np

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
    """Write to a temporary file in the target directory, then rename: no partial file."""
    directory = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(directory):
        raise SystemExit(f"error: output directory does not exist: {directory}")
    if not os.access(directory, os.W_OK):
        raise SystemExit(f"error: output directory is not writable: {directory}")
    fd, tmp = tempfile.mkstemp(dir=directory, prefix=".tmp_", suffix=os.path.basename(path))
    try:
        with os.fdopen(fd, "w") as f:
            f.write(text)
        os.replace(tmp, path)
    except BaseException:
        if os.path.exists(tmp):
            os.unlink(tmp)
        raise


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
    return parser


def main(argv=None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    return args.func(args)
