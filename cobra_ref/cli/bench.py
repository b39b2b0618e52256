"""``cobra-ref bench``: time per step of the full model, broken down, against MuJoCo on the same MJCF.

Helper: the command-line side of :mod:`cobra_ref.reproduce.bench`.
"""

from __future__ import annotations

import json

import numpy as np

from ..progress import progress_printer
from .common import c_stdout_silenced, check_writable, finite_float, write_text_atomic


def cmd_bench(args) -> int:
    """Time per step of the full model while rolling with the box, and MuJoCo's on the same MJCF.

    Helper: the command line (cobra-ref bench).
    """
    from ..reproduce.bench import format_table, run_bench

    if args.json:
        check_writable(args.json)
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


def add_parsers(sub) -> None:
    """The ``bench`` subcommand.

    Helper: the command line (cobra-ref bench).
    """
    p = sub.add_parser("bench", help="time per step against MuJoCo on the same model (a benchmark)")
    p.add_argument("--duration", type=finite_float, default=2.0, help="simulated time [s] (default 2)")
    p.add_argument("--json", metavar="FILE", help="also write the record as JSON")
    p.add_argument("--no-mujoco", action="store_true", help="skip the MuJoCo comparison")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_bench)
