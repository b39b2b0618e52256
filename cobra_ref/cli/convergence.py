"""``cobra-ref convergence``: one gait at dt = 2, 1, 0.5, 0.25 ms, for both contact models.
"""

from __future__ import annotations

import json
import sys

from ..infra.validation import RULES, ValidationError, check_choice, step_count
from .common import c_stdout_silenced, check_out, fail, write_text_atomic


def cmd_convergence(args) -> int:
    """Run the study (of the figures' members with ``--members``), print its table, write it as JSON.
    """
    from ..reproduce.convergence import DTS, SETTINGS, changes, check_restart, format_table, richardson, study

    if args.json is not None:
        check_out(args.json, "--json")
    settings = tuple(s.strip() for s in (args.settings or ",".join(SETTINGS)).split(","))
    try:
        for name in settings:
            check_choice("--settings", name, SETTINGS)
        for dt in DTS:  # every run of the study covers the same time: whole steps of each dt
            step_count(args.duration, dt, exact=True, duration_field="--duration", dt_field="dt")
        check_restart(args.restart, args.duration, DTS)
        if args.members is not None and (args.settings is not None or args.restart > 0):
            raise ValidationError("--members studies the figures' runs with their setting (high-fidelity) from "
                                  "their starts: it takes neither --settings nor --restart")
    except ValidationError as exc:
        raise fail(exc) from None
    say = None if args.quiet else (lambda line: print(line, file=sys.stderr, flush=True))
    if args.members is not None:
        return _members(args, say)
    with c_stdout_silenced():
        result = study(args.gait, args.duration, settings=settings, progress=say, restart=args.restart)
    print(format_table(result, args.gait, args.restart))
    if args.json is not None:
        record = {"gait": args.gait, "duration": args.duration, "restart": args.restart,
                  "results": {name: {str(dt): row for dt, row in rows.items()} for name, rows in result.items()},
                  "changes": {name: changes(rows) for name, rows in result.items()},
                  "richardson": {name: {k: {"order": p, "limit": lim} for k, (p, lim) in richardson(rows).items()}
                                 for name, rows in result.items()}}
        _write_json(args.json, record)
    return 0


def _members(args, say) -> int:
    """``--members``: the figures' first N runs of the gait at every dt (``convergence_members``)."""
    from ..reproduce.convergence_members import format_members, member_changes, members_study

    with c_stdout_silenced():
        result = members_study(args.gait, args.members, args.duration, progress=say)
    print(format_members(result, args.gait))
    if args.json is not None:
        record = {"gait": args.gait, "duration": args.duration, "members": args.members,
                  "results": {str(dt): rows for dt, rows in result.items()}, "changes": member_changes(result)}
        _write_json(args.json, record)
    return 0


def _write_json(path: str, record: dict) -> None:
    """``--json``: the study's record written atomically to exactly ``path``, and said so."""
    write_text_atomic(path, json.dumps(record, indent=1) + "\n", "--json")
    print(f"wrote {path}")


def add_parsers(sub) -> None:
    """The ``convergence`` subcommand.
    """
    from ..gaits import GAITS

    p = sub.add_parser("convergence", help="one gait at dt = 2, 1, 0.5, 0.25 ms: do forces, torques, power converge?",
                       description="Simulates one gait at dt = 2, 1, 0.5 and 0.25 ms with the high-fidelity "
                                   "setting (compliant contact, position servo) and the rigid one (rigid contact, "
                                   "prescribed joints), and prints per dt: contact force peaks (raw, 2 ms mean, "
                                   "99th percentile), torque and power peaks, the box's displacement and impacts "
                                   "per second; then each one's observed order of convergence and Richardson limit "
                                   "from the three finest dt ('-' where they do not approach one).")
    p.add_argument("--gait", default="J", choices=tuple(GAITS), help="the gait (default J)")
    p.add_argument("--duration", type=RULES["study_duration"].arg("--duration"), default=2.0,
                   help="simulated time per run [s] (default 2)")
    p.add_argument("--settings", default=None, help="comma separated: high-fidelity, rigid (default both)")
    p.add_argument("--restart", type=RULES["restart"].arg("--restart"), default=0.0, metavar="T",
                   help="start every dt at T [s] from the state the finest dt reached there, so that the table "
                        "measures the steps after T apart from the error carried to T (default 0: every run from "
                        "the start; T must be a whole number of 0.25 ms steps, below --duration)")
    p.add_argument("--members", type=RULES["members"].arg("--members"), default=None, metavar="N",
                   help="study the figures' runs instead: the gait with the figures' parameters, its first N "
                        "ensemble members (member 0 the figure run), each from its figure start at every dt, "
                        "high-fidelity, the members of a dt advanced as one batch; a table row per member")
    p.add_argument("--json", metavar="FILE", help="also write the table as JSON (exactly this name)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_convergence)
