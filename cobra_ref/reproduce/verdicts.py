"""The bookkeeping of the claims over an ensemble: which members count, their numbers, the verdict.

``ensemble[gait][i]`` is member i's summary (``claims.gait_summaries``); a member whose run has an
error, or lacks a statistic (absent or nan), is left out. Of the n members (or scenarios)
evaluated, a claim **holds** when it holds for >= ``HOLDS_AT`` = 80 %, **does not hold** when
for <= ``FAILS_AT`` = 20 %, and is **undecided** between; **not tested** when none was evaluated.
A gait that is a mirrored copy of another present (``ensemble.MIRRORED``: J-mirror of J) is never
counted in a verdict over several gaits (``distinct``); its numbers may be shown, marked as a copy.
A threshold's sensitivity is the verdict by the same rule at each of a fixed list of thresholds
(``sensitivity``).
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np

from .ensemble import MIRRORED

HOLDS_AT = 0.8  # fraction of members for "holds"
FAILS_AT = 0.2  # fraction of members at or below which it "does not hold"


def distinct(gaits) -> list:
    """The gaits of ``gaits`` (names, or an ensemble's keys) that are not a mirrored copy
    (``ensemble.MIRRORED``) of another gait among them: the gaits a pooled verdict counts."""
    gaits = list(gaits)
    return [g for g in gaits if MIRRORED.get(g) not in gaits]


def copies(gaits) -> dict:
    """{gait: why it is not counted} of the gaits of ``gaits`` that ``distinct`` leaves out."""
    gaits = list(gaits)
    return {g: f"a copy of {MIRRORED[g]} (ensemble.MIRRORED), shown, not counted"
            for g in gaits if g not in distinct(gaits)}


def sensitivity(thresholds: dict, results) -> dict:
    """{label: {"threshold", "holds", "n", "verdict"}}: the verdict (``verdict``) at each threshold
    of ``thresholds`` {label as the rule writes it: value}, ``results(value)`` the per-member
    booleans of the claim at that threshold."""
    out = {}
    for label, value in thresholds.items():
        held = [bool(r) for r in results(value)]
        out[label] = {"threshold": value, "holds": sum(held), "n": len(held),
                      "verdict": verdict(len(held), sum(held))[1]}
    return out


def usable(s: dict, keys) -> bool:
    """Whether summary ``s`` has every statistic of ``keys`` (present, not nan)."""
    for k in keys:
        v = s.get(k)
        if v is None:
            return False
        if isinstance(v, float) and math.isnan(v):
            return False
    return True


def failed_runs(ensemble: dict, gaits) -> dict:
    """{"gait[i]": error} of the runs with an error among ``gaits``."""
    return {f"{g}[{i}]": s["error"] for g in gaits if g in ensemble
            for i, s in enumerate(ensemble[g]) if s.get("error")}


def ok(s: dict, keys) -> bool:
    """Whether summary ``s`` is of a run without error and has every statistic of ``keys``."""
    return not s.get("error") and usable(s, keys)


def scenarios(ensemble: dict, gaits, keys) -> list[int]:
    """The scenarios i at which every gait of ``gaits`` has a member without error and with ``keys``."""
    if not gaits or any(g not in ensemble for g in gaits):
        return []
    n = min(len(ensemble[g]) for g in gaits)
    return [i for i in range(n) if all(ok(ensemble[g][i], keys) for g in gaits)]


def own_values(ensemble: dict, gaits, key: str, statistic=None) -> dict:
    """{gait: mean and spread} of ``statistic(summary)`` (default ``summary[key]``) over each gait's
    own usable members: the numbers shown when no scenario has every gait."""
    statistic = statistic or (lambda s: s[key])
    out = {}
    for g in gaits:
        v = [statistic(s) for s in ensemble.get(g, []) if ok(s, [key])]
        if v:
            out[g] = stats(v)
    return out


def stats(values) -> dict:
    """{"mean", "spread": [min, max]} of the numbers in ``values``, nan left out (nan if none is left)."""
    v = [float(x) for x in values if not (isinstance(x, float) and math.isnan(x))]
    if not v:
        return {"mean": float("nan"), "spread": [float("nan"), float("nan")]}
    return {"mean": float(np.mean(v)), "spread": [float(min(v)), float(max(v))]}


def verdict(n: int, n_holds: int) -> tuple:
    """(holds, verdict) of a claim that held for ``n_holds`` of ``n`` members by the 80/20 rule:
    holds when n_holds >= 0.8 n, does not hold when n_holds <= 0.2 n (``HOLDS_AT``, ``FAILS_AT``;
    compared as exact fractions, so 4 of 5 is 80 %), undecided between, not tested when n = 0.
    """
    if n == 0:
        return None, "not tested"
    share = Fraction(n_holds, n)
    if share >= Fraction(HOLDS_AT).limit_denominator(100):
        return True, "holds"
    if share <= Fraction(FAILS_AT).limit_denominator(100):
        return False, "does not hold"
    return None, "undecided"


def claim_entry(cid, text, values, results, failed, details=None, reason="", kind="claim"):
    """A claim dict (``claims`` module docstring) from per-member booleans ``results``: ``values``
    its numbers per gait, ``failed`` the runs left out, ``reason`` why it is not tested if no
    member was evaluated, ``kind`` "claim" (of the paper) or "check" (of the model)."""
    n, k = len(results), int(sum(bool(r) for r in results))
    holds, word = verdict(n, k)
    details = dict(details or {})
    if n == 0:
        details["not tested because"] = reason or "no member could be evaluated"
    return {"id": cid, "kind": kind, "claim": text, "values": values, "holds": holds, "verdict": word,
            "ensemble": {"n": n, "holds": k, "fraction": (k / n) if n else None, "left_out": failed},
            "details": details}
