"""``cobra-ref figures``: every result of the paper (figures 3-9, GIFs, claims) in one command.
"""

from __future__ import annotations

import json
import os
import sys

from .common import c_stdout_silenced, fail, interrupted_exit
from ..infra.output import OutputError
from ..infra.signals import interrupted
from ..infra.validation import RULES

FULL_OUT, QUICK_OUT = "figures", "figures-quick"  # the default output directories


def cmd_figures(args) -> int:
    """Regenerate figures 3-9, the GIFs and the claims report; Ctrl-C or SIGTERM ends the workers
    and says what was kept (exit status 130 or 143).
    """
    from ..reproduce.regenerate import CACHE_PROBE, OPTIMIZED_DIR, FiguresOptions, check_output_dir, regenerate
    from ..reproduce.runs import PAPER_GAITS

    gaits = PAPER_GAITS if args.gaits is None else tuple(g.strip() for g in args.gaits.split(","))
    unknown = [g for g in gaits if g not in PAPER_GAITS]
    if unknown:
        raise SystemExit(f"error: unknown gait(s) {', '.join(unknown)}; gaits: {', '.join(PAPER_GAITS)}")
    if args.quick and args.check:
        sys.stderr.write("error: --check compares a full run with the committed full results; a --quick run is a "
                         "smoke run and cannot be compared (drop --quick, or --check)\n")
        raise SystemExit(2)
    out = (QUICK_OUT if args.quick else FULL_OUT) if args.out is None else args.out
    committed = _committed_claims(out) if args.check else None
    try:
        check_output_dir(out)
        check_output_dir(os.path.join(out, ".cache") if args.cache is None else args.cache, "--cache directory",
                         CACHE_PROBE)
    except OSError as exc:
        raise fail(exc) from None
    with c_stdout_silenced():
        mujoco = True if args.mujoco else (False if args.no_mujoco else None)
        claims_map = True if args.map else (False if args.no_map else None)
        options = FiguresOptions(quick=args.quick, force=args.force, mujoco=mujoco, gaits=gaits,
                                 n_members=args.members, optimized_dir=None if args.defaults else OPTIMIZED_DIR,
                                 reoptimize_all=args.reoptimize, claims_map=claims_map)
        try:
            result = regenerate(out, options, cache_dir=args.cache, workers=args.jobs, progress=not args.quiet)
        except OutputError as exc:  # a write that failed late (a full disk): the runs stored so far are kept
            cache = args.cache or os.path.join(out, ".cache")
            raise fail(f"{exc}; the runs finished before are kept in the cache {cache} (the next run reads "
                       "them)") from None
        except BaseException as exc:
            if not interrupted(exc):
                raise
            raise interrupted_exit(exc, _kept(exc, out, args.cache or os.path.join(out, ".cache"))) from None
    summary = {"smoke run": True} if args.quick else {}
    summary |= {"out": out, "files": len(result["files"]),
                "claims": {c["id"]: c.get("verdict", c["holds"]) for c in result["claims"] if c.get("kind") != "map"},
                "seconds": round(result["seconds"], 1)}
    status = 0
    if committed is not None:
        status = check_report(committed, result["claims"])
        summary["check"] = "agrees" if status == 0 else "mismatch"
    print(json.dumps(summary))
    return status


def _kept(exc: BaseException, out: str, cache_dir: str) -> str:
    """What an interrupted ``figures`` kept, in words: the simulations it finished (``runs.run_all``
    names them on the interrupt), each in the cache that the next run reads, and the files written
    before the interrupt."""
    kept = getattr(exc, "kept", None)
    if kept is None:  # interrupted before or after the simulations
        return (f"the simulations finished are in the cache {cache_dir}, the figures and reports written "
                f"before the interrupt in {out}; the next run reads the cache")
    return (f"{len(kept['stored'])} of the {kept['todo']} simulations to run finished, kept in the cache "
            f"{kept['cache_dir']} (the next run reads them); no figure was drawn")


def _committed_claims(out_dir: str) -> list:
    """The committed claims of ``out_dir/claims.json``, read before anything is regenerated;
    exit status 2 with a message when there is none or it is not a claims report."""
    from ..reproduce.check import read_committed

    path = os.path.join(out_dir, "claims.json")
    if not os.path.isfile(path):
        sys.stderr.write(f"error: --check compares with the committed claims report, but {path} does not exist; "
                         "run 'cobra-ref figures' without --check first\n")
        raise SystemExit(2)
    try:
        return read_committed(path)
    except (OSError, ValueError) as exc:
        sys.stderr.write(f"error: --check: {exc}\n")
        raise SystemExit(2) from None


def check_report(committed: list, regenerated: list) -> int:
    """Exit status of ``--check``: 0 when the regenerated claims agree with the committed ones
    (``reproduce.check.compare_claims``), 1 otherwise, with the table of mismatches on stderr.

    The command line (cobra-ref figures --check). When this run made no MuJoCo comparison (mujoco is
    an optional extra, or ``--no-mujoco``), the committed MuJoCo claims are left out of the
    comparison and a note says so.
    """
    from ..reproduce.check import compare_claims, mismatch_table

    mujoco = ("MJ-travel-", "MJ-box-")
    if not any(e["id"].startswith(mujoco) for e in regenerated):
        left_out = [e for e in committed if e["id"].startswith(mujoco)]
        if left_out:
            sys.stderr.write(f"--check: no MuJoCo comparison in this run (pip install mujoco, or without "
                             f"--no-mujoco): its {len(left_out)} committed claims are not compared\n")
        committed = [e for e in committed if not e["id"].startswith(mujoco)]
    mismatches = compare_claims(committed, regenerated)
    if mismatches:
        sys.stderr.write(f"--check: {len(mismatches)} mismatch(es) with the committed claims.json:\n"
                         + mismatch_table(mismatches))
        return 1
    sys.stderr.write("--check: the regenerated claims agree with the committed claims.json\n")
    return 0


def add_parsers(sub) -> None:
    """The ``figures`` subcommand.
    """
    p = sub.add_parser("figures", help="regenerate the paper's figures 3-9, GIFs and the claims report",
                       description="Simulate the five gaits, each as an ensemble of --members runs (member 0: 10 s, "
                                   "the others 6 s; with the optimized "
                                   "parameters of cobra_ref/optimized/ where present) on all cores, or read "
                                   "them from the cache, and write fig03_snapshots.png ... fig09_box_distance.png "
                                   "(+ PDF), anim_<gait>.gif, claims.json, claims.md and summary.json to --out, "
                                   "with the MuJoCo comparison and the verdict map over the paper's unknowns "
                                   "(claims_map.md, fig_claims_map.png). --quick is a smoke run of the same pipeline in "
                                   "about a minute: 1 s runs, 1 member per gait, no MuJoCo comparison and no map, PNG only, "
                                   "every output marked as a smoke run on its first line. "
                                   "Prints a one-line JSON summary.")
    p.add_argument("--out", default=None, help=f"output directory (default {FULL_OUT}, {QUICK_OUT} with --quick)")
    p.add_argument("--quick", action="store_true",
                   help="a smoke run: 1 s simulations, 1 member per gait (unless --members), no MuJoCo comparison "
                        "(unless --mujoco), PNG only, outputs marked as a smoke run; never compared by --check")
    p.add_argument("--force", action="store_true", help="ignore the cache: simulate and draw everything again")
    p.add_argument("--cache", default=None, help="simulation cache directory (default OUT/.cache)")
    p.add_argument("--jobs", type=RULES["workers"].arg("--jobs"), default=None,
                   help="worker processes (default: the number of cores)")
    p.add_argument("--gaits", default=None, help="comma-separated subset of C,S,J,J-mirror,sidewinding")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--no-mujoco", action="store_true", help="skip the MuJoCo rollout cross-check")
    where.add_argument("--mujoco", action="store_true",
                       help="make the MuJoCo rollout cross-check with --quick too (a full run makes it anyway)")
    mapping = p.add_mutually_exclusive_group()
    mapping.add_argument("--no-map", action="store_true",
                         help="skip the verdict map over the paper's unknowns (claims_map.md, fig_claims_map.png; "
                              "8 set-ups x 4 gaits x 4 members of 6 s, about 12 minutes on 2 cores)")
    mapping.add_argument("--map", action="store_true",
                         help="make the verdict map with --quick too (a full run makes it anyway)")
    p.add_argument("--defaults", action="store_true",
                   help="simulate every gait with its default parameters instead of the optimized ones "
                        "committed in cobra_ref/optimized/")
    p.add_argument("--reoptimize", action="store_true",
                   help="first re-run 'cobra-ref optimize' for every gait and the three direction goals, into "
                        "OUT/optimized/, and use those")
    p.add_argument("--members", type=RULES["members"].arg("--members"), default=None,
                   help="ensemble members per gait: member 0 is the figure run, the others are perturbed "
                        "starts, phases and frictions judged over the first 6 s (default 8, 1 with --quick)")
    p.add_argument("--check", action="store_true",
                   help="compare the regenerated claims with OUT/claims.json as it was before the run: "
                        "exit 1 with a table of mismatches when a verdict differs or a statistic leaves the "
                        "committed ensemble's spread, 2 when there is no claims.json, when it is a smoke run's "
                        "or with --quick (a full run only)")
    p.add_argument("--quiet", action="store_true", help="no progress lines")
    p.set_defaults(func=cmd_figures)
