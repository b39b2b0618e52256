"""``claims.md``: the claims report of ``cobra-ref figures`` in Markdown (``to_markdown``).

The claims with their per-gait numbers, the members evaluated and holding, the verdicts and
their sensitivity to the thresholds (``claims``), the checks of the model apart; then per gait
the mean [min, max] over the members of the summary's numbers
(``TABLE``) and the runs' health, the failed runs, and the settings.
"""

from __future__ import annotations

import numpy as np

from .verdicts import stats

def _fmt(v) -> str:
    """A value as the report shows it: 4 significant digits, lists in parentheses, dicts as "k: v"."""
    if isinstance(v, bool) or v is None:
        return str(v)
    if isinstance(v, (float, np.floating)):
        v = float(v)
        return "nan" if v != v else ("inf" if np.isinf(v) else f"{v:.4g}")
    if isinstance(v, (list, tuple)):
        return "(" + ", ".join(_fmt(x) for x in v) + ")"
    if isinstance(v, dict):
        return "; ".join(f"{k}: {_fmt(x)}" for k, x in v.items())
    return str(v)


def _cell(text: str) -> str:
    """``text`` safe inside a Markdown table cell (its | escaped)."""
    return str(text).replace("|", "\\|")


def _mean_spread(st: dict) -> str:
    """"mean [min, max]" of ``verdicts.stats``' numbers, or the mean alone when they are all alike."""
    lo, hi = st["spread"]
    if lo == hi:
        return _fmt(st["mean"])  # one member, or all alike
    return f"{_fmt(st['mean'])} [{_fmt(lo)}, {_fmt(hi)}]"


TABLE = (("duration", "T (s)", 1.0), ("locomotion_work", "W_loc (J)", 1.0), ("box_work", "W_box (J)", 1.0),
         ("efficiency_slope", "slope", 1.0), ("peak_abs_power", "peak abs(P) (W)", 1.0),
         ("power_cv", "CV of abs(P)", 1.0), ("box_distance", "box moved (m)", 1.0),
         ("impact_impulse_per_second", "impact impulse/s (N)", 1.0),
         ("fixed_point_converged", "fixed point converged (%)", 100.0),
         ("steps_over_torque_limit", "steps over tau_max (%)", 100.0),
         ("max_tracking_error", "largest joint error (rad)", 1.0), ("rms_tracking_error", "RMS joint error (rad)", 1.0),
         ("ledger_residual", "energy ledger residual (%)", 100.0), ("max_penetration", "max penetration (m)", 1.0),
         ("max_force_across_gap", "normal force across a positive gap (N)", 1.0))


HEADER = ["| id | claim | per gait: mean [min, max] | n | members holding | verdict | sensitivity: threshold, "
          "holding / n, verdict |", "|---|---|---|---|---|---|---|"]
CHECKS = ("These hold by construction or test our own machinery, so they are not evidence for the paper: TL "
          "checks the servo, which clamps the torque at tau_max (assumption A7); MJ-sym checks that J-mirror is "
          "J reflected, which its members are by construction (assumption A29); GT-own checks that the optimizer "
          "moved the box towards the goal it was given, set where the unoptimized gait already pushed; the "
          "MuJoCo rows compare our model with MuJoCo's.")


def _sensitivity(details: dict) -> str:
    """The sensitivity entries of a claim's ``details`` compactly: "1 %: 16/32 undecided; ..."."""
    parts = []
    for key, table in details.items():
        if key.startswith("sensitivity") and isinstance(table, dict):
            what = key[len("sensitivity"):].strip("_ ")
            parts += [f"{what + ' ' if what else ''}{label}: {row['holds']}/{row['n']} {row['verdict']}"
                      for label, row in table.items()]
    return "; ".join(parts)


def _row(c: dict) -> str:
    """One claim entry as a row of ``HEADER``."""
    word = c.get("verdict") or {True: "holds", False: "does not hold", None: "not tested"}[c["holds"]]
    e = c.get("ensemble") or {}
    vals = c.get("values") or {}
    if vals and all(isinstance(v, dict) and "mean" in v for v in vals.values()):
        shown = "; ".join(f"{g}: {_mean_spread(v)}" for g, v in vals.items())
    else:
        shown = _fmt(vals)
    details = c.get("details") or {}
    notes = [f"{k}: {_fmt(v)}" for k, v in details.items()
             if v not in ([], {}, None) and not k.startswith("sensitivity")]
    if e.get("left_out"):
        notes.append("left out: " + _fmt(e["left_out"]))
    if notes:
        shown += " (" + "; ".join(notes) + ")"
    return (f"| {c['id']} | {_cell(c['claim'])} | {_cell(shown)} | {e.get('n', '')} | {e.get('holds', '')} | "
            f"**{word}** | {_cell(_sensitivity(details))} |")


def to_markdown(claims: list[dict], summaries: dict, settings: dict, where: list[str] | None = None) -> str:
    """``claims.md``: the claims of the paper with their per-gait numbers, the members evaluated
    and holding, the verdicts and their thresholds' sensitivity; the checks of the model (entries
    of ``kind`` "check") in a section of their own; then per gait the mean [min, max] over the
    members of the summary's numbers and the runs' health (fixed-point convergence, torque
    limit, penetration), the failed runs, and the settings: the human-readable claims report.
    ``summaries`` is {gait: [summary, ...]} or {gait: summary}; ``where``: Markdown lines put after
    the claims' table (where in the verdict map each claim holds, ``claims_map.where_lines``).
    """
    ens = {g: (list(v) if isinstance(v, (list, tuple)) else [v]) for g, v in summaries.items()}
    lines = ["# Claims of [COBRA] checked in cobra_ref", "",
             "Generated by `cobra-ref figures`; every number is computed from the simulations in this run "
             "(definitions: `cobra_ref/reproduce/analysis.py`, assumption A18; the claims and their thresholds: "
             "`cobra_ref/reproduce/claims.py`). A claim is evaluated per ensemble member (per scenario when it "
             "compares gaits); it holds when it holds for >= 80 % of them, does not hold when for <= 20 %, and is "
             "undecided between. J-mirror, a mirrored copy of J, is shown but never counted in a verdict over "
             "several gaits. The last column gives the verdict at other thresholds.", ""] + HEADER
    lines += [_row(c) for c in claims if c.get("kind", "claim") != "check"]
    lines += [""] + where if where else []
    checks = [_row(c) for c in claims if c.get("kind", "claim") == "check"]
    if checks:
        lines += ["", "## Checks of the model, not claims of the paper", "", CHECKS, ""] + HEADER + checks
    one = all(len(m) == 1 for m in ens.values())
    lines += ["", "## Per gait (the figure runs)" if one else "## Per gait (mean [min, max] over the members that completed)", "",
              "| gait | members (completed / all) | " + " | ".join(h for _, h, _ in TABLE) + " |",
              "|---|---|" + "---|" * len(TABLE)]
    failed = []
    for g, members in ens.items():
        ok = [s for s in members if not s.get("error")]
        failed += [f"{g}[{i}]: {_cell(s['error'])}" for i, s in enumerate(members) if s.get("error")]
        cells = []
        for key, _, scale in TABLE:
            v = [scale * float(s[key]) for s in ok if s.get(key) is not None]
            cells.append(_mean_spread(stats(v)) if v else "")
        lines.append(f"| {g} | {len(ok)} / {len(members)} | " + " | ".join(cells) + " |")
    if failed:
        lines += ["", "Failed runs (left out of every claim):", ""] + [f"- {f}" for f in failed]
    lines += ["", "## Settings", ""] + [f"- {k}: {_fmt(v)}" for k, v in settings.items()]
    lines += ["", "Model choices that change these outcomes (the verdict map, claims_map.md, judges the claims at "
              "other values of the first three): the box's size 0.10 m (assumption A8), the robot-box "
              "friction mu_rb = 0.5 (assumption A22; at mu_rb = 1 the rolling push self-locks), the box "
              "placement per gait (assumption A9, cobra_ref/start.py), and the joints, position servos whose "
              "torque is clamped at tau_max (assumption A7: 'steps over tau_max' counts the steps where the "
              "clamp was exceeded)."]
    return "\n".join(lines) + "\n"
