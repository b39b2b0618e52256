"""``cobra-ref bench``: time per step of the full model, broken down, against MuJoCo on the same MJCF.

The command-line side of :mod:`cobra_ref.reproduce.bench`.
"""

from __future__ import annotations

import json

from ..infra.progress import progress_printer
from ..infra.validation import DEFAULT_DT, RULES, ValidationError, step_count
from .common import c_stdout_silenced, check_out, fail, write_text_atomic


def cmd_bench(args) -> int:
    """``cobra-ref bench``: time per step of the full model while rolling with the box, at
    ``DEFAULT_DT``, and MuJoCo's on the same MJCF."""
    from ..reproduce.bench import format_table, run_bench

    if args.json is not None:
        check_out(args.json, "--json")
    try:
        step_count(args.duration, DEFAULT_DT, exact=True, duration_field="--duration", dt_field="the benchmark's dt")
    except ValidationError as exc:
        raise fail(exc) from None
    with c_stdout_silenced():
        record = run_bench(args.duration, DEFAULT_DT, with_mujoco=not args.no_mujoco,
                           progress=None if args.quiet else progress_printer("bench"))
    print(format_table(record))
    if args.json is not None:
        write_text_atomic(args.json, json.dumps(record, indent=2) + "\n", "--json")
        print(f"wrote {args.json}")
    return 0


def add_parsers(sub) -> None:
    """Add the ``bench`` subcommand to ``sub``."""
    p = sub.add_parser("bench", help="time per step against MuJoCo on the same model (a benchmark)")
    p.add_argument("--duration", type=RULES["bench_duration"].arg("--duration"), default=2.0,
                   help=f"simulated time [s] at dt = {DEFAULT_DT * 1e3:g} ms, a whole number of steps (default 2)")
    p.add_argument("--json", metavar="FILE", help="also write the record as JSON (exactly this name)")
    p.add_argument("--no-mujoco", action="store_true", help="skip the MuJoCo comparison")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_bench)
