"""``cobra-ref convergence --members N``: the figures' own runs when dt halves, member by member.

``convergence.study`` runs one gait with its default parameters from one start. The figures run
each gait with its optimum and an ensemble of members (box shift and turn, phase, friction scale:
:mod:`cobra_ref.reproduce.ensemble`), and a quantity as sensitive as the box's displacement after a
strike can converge for one member and not for another. ``members_study`` runs the first ``n``
members of the figures' ensemble of one gait (``regenerate.ensemble_specs`` with the figures'
parameters; member 0 is the figure run) for ``duration`` at each dt with the figures' setting
(compliant contact, position servo), every dt from the member's figure start (placed and settled
as the figure runs are, ``runs.figure_starts``), so that only the step differs. The members of one dt are
advanced as one batch (:mod:`cobra_ref.batch`; each its single run, bit for bit) and measured by
``convergence.metrics``.
"""

from __future__ import annotations

import time
from dataclasses import replace

from ..batch import simulate_batch
from ..step import StepSettings
from .convergence import DTS, changes, metrics
from .runs import figure_starts


def figure_members(gait_name: str, n_members: int, duration: float) -> list:
    """The first ``n_members`` RunSpecs of the figures' ensemble of ``gait_name`` (member 0: the
    figure run), with the figures' parameters (the committed optimum, else A10's defaults), each
    ``duration`` seconds long."""
    from .optima import OPTIMIZED_DIR, optimized_files, optimized_params
    from .regenerate import ensemble_specs

    params = optimized_params(optimized_files(OPTIMIZED_DIR, (gait_name,)))
    specs = ensemble_specs((gait_name,), n_members, params=params)[gait_name][:n_members]
    return [replace(spec, duration=duration) for spec in specs]


def members_study(gait_name: str, n_members: int, duration: float = 2.0, dts=DTS, progress=None) -> dict:
    """{dt: [metrics of each member]} of the figures' first ``n_members`` runs of ``gait_name``
    (module docstring); a member whose run fails has its ``error`` in its row (its metrics are of
    the steps it took)."""
    models, references, initial, _ = zip(*figure_starts(figure_members(gait_name, n_members, duration)))
    out = {}
    for dt in dts:
        clock = time.perf_counter()
        out[dt] = [{**metrics(traj, model), "error": traj.error} for traj, model in
                   zip(simulate_batch(list(models), references, duration, StepSettings(dt=dt), initial), models)]
        if progress:
            progress(f"{gait_name}, {n_members} members, dt = {dt * 1e3:g} ms: {time.perf_counter() - clock:.0f} s")
    return out


def member_changes(result: dict) -> list:
    """``convergence.changes`` of each member's rows of ``members_study``'s ``result``."""
    n = len(next(iter(result.values())))
    return [changes({dt: {k: v for k, v in rows[i].items() if k != "error"} for dt, rows in result.items()})
            for i in range(n)]


def format_members(result: dict, gait_name: str) -> str:
    """``members_study``'s result as text: a block per metric, a row per member with its value at
    each dt and its relative change at each halving."""
    dts = sorted(result, reverse=True)
    moved = member_changes(result)
    halvings = [f"{a * 1e3:g}->{b * 1e3:g}" for a, b in zip(dts, dts[1:])]
    lines = [f"{gait_name}, the figures' runs ({len(moved)} members; member 0 the figure run), compliant contact + "
             f"position servo, every dt from the member's figure start",
             f"  {'dt [ms]':<14}" + "".join(f"{dt * 1e3:>10g}" for dt in dts) + "   change " + "".join(
                 f"{h:>11}" for h in halvings)]
    for key in moved[0]:
        lines.append(f"{key}")
        for i, change in enumerate(moved):
            lines.append(f"  member {i:<7}" + "".join(f"{result[dt][i][key]:>10.4g}" for dt in dts) + "          "
                         + "".join(f"{100 * c:>+10.1f}%" for c in change[key]))
    failed = [f"member {i} at dt = {dt * 1e3:g} ms: {row['error']}" for dt in dts for i, row in
              enumerate(result[dt]) if row["error"]]
    return "\n".join(lines + [f"failed: {line}" for line in failed])
