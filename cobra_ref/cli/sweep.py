"""``cobra-ref sweep``: the contact solve's reliability over randomized scenarios.
"""

from __future__ import annotations

import json
import time

from ..infra.validation import RULES, ValidationError, check_choice
from .common import c_stdout_silenced, check_out, fail, write_text_atomic


def cmd_sweep(args) -> int:
    """Run the sweep on the local cores, print the summary, write every record as JSON; exit status 1
    when a physical scenario fails a check or a scenario raises (``reproduce.sweep.summarize``).
    """
    from ..infra.executors import own_pool
    from ..infra.progress import end_line, rewrite
    from ..reproduce.sweep import format_summary, run_scenario, scenarios, summarize
    from ..step import LAWS

    if args.json is not None:
        check_out(args.json, "--json")
    laws = tuple(s.strip() for s in args.contact.split(","))
    try:
        for law in laws:
            check_choice("--contact", law, LAWS)
    except ValidationError as exc:
        raise fail(exc) from None
    todo = scenarios(args.n, args.seed, laws)
    start, records = time.perf_counter(), []
    # own_pool: on Ctrl-C or SIGTERM the workers end at once
    with c_stdout_silenced(), own_pool(args.jobs) as pool:
        futures = [pool.submit(run_scenario, s, args.duration) for s in todo]
        for k, future in enumerate(futures):
            records.append(future.result())
            if not args.quiet:
                rewrite(f"sweep: {k + 1}/{len(todo)} scenarios, {time.perf_counter() - start:.0f} s ")
    end_line()
    summary = summarize(records)
    summary.update(seed=args.seed, duration=args.duration, contact=list(laws), seconds=time.perf_counter() - start)
    print(format_summary(summary))
    if args.json is not None:
        write_text_atomic(args.json, json.dumps({"summary": summary, "runs": records}, indent=1) + "\n", "--json")
        print(f"wrote {args.json}")
    return 0 if not any(c["failing"] for c in summary["checks"].values()) and not summary["errors"] else 1


def add_parsers(sub) -> None:
    """The ``sweep`` subcommand.
    """
    p = sub.add_parser("sweep", help="reliability of the contact solve over randomized scenarios",
                       description="Draws N scenarios from a seed (gait parameters within the optimizer's bounds, "
                                   "mu 0.3-1.5, box mass 0.1-2 kg, dt 0.5-2 ms, both servos), simulates each and "
                                   "checks the friction fixed point's convergence, Coulomb's circle, the solver's "
                                   "penetration error (penetration minus the compliant spring's deflection F/k) and "
                                   "the energy ledger. Scenarios that left physics (prescribed joints needing torques "
                                   "beyond tau_max, or a contact force beyond the bound of A32) are reported apart. "
                                   "Exit status 1 when a physical scenario fails a check or a scenario fails.")
    p.add_argument("--n", type=RULES["count"].arg("--n"), default=100, help="number of scenarios (default 100)")
    p.add_argument("--seed", type=RULES["seed"].arg("--seed"), default=0, help="random seed (default 0)")
    p.add_argument("--duration", type=RULES["scenario_duration"].arg("--duration"), default=2.0,
                   help="simulated time per scenario [s] (default 2)")
    p.add_argument("--contact", default="compliant", help="contact law(s), comma separated: compliant (default), rigid")
    p.add_argument("--jobs", type=RULES["workers"].arg("--jobs"), default=None,
                   help="worker processes (default: the cores)")
    p.add_argument("--json", metavar="FILE", help="also write the summary and every scenario's record as JSON "
                                                  "(exactly this name)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_sweep)
