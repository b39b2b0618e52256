"""Does a regenerated claims report agree with the committed one? (``cobra-ref figures --check``)

Implements: the agreement rule of ``--check``, stated before any run. Two reports (the lists of
claim entries of ``claims.json``) agree when

* they hold the same claims (by ``id``);
* every claim's verdict is equal (``verdict`` when the entry has one, else ``holds``), and so is
  its ``kind`` ("claim" of the paper or "check" of the model; an entry without one is a claim);
* every statistic of a claim agrees: each claim of the paper carries ``statistics`` =
  {name: {"mean", "min", "max"}} over the ensemble's members (``claim_statistics``), and the
  new mean must lie within the committed [min, max], widened by ``TOLERANCE`` = 1 % of the
  larger of |min|, |max| and their spread, and never by less than ``ABSOLUTE`` = 1e-9 (the
  same inputs give the same numbers; the widening absorbs floating-point differences between
  machines, not physics changes). A statistic that is not finite must be equal.

The statistics are the numbers each claim is judged on (``claims.paper_claims``' ``values``),
computed per member (member i of every gait together) and named by their path in ``values``
(e.g. ``J`` or ``J-mirror[1]``).
"""

from __future__ import annotations

import json
import math

TOLERANCE = 0.01  # the committed spread is widened by this share of its magnitude
ABSOLUTE = 1e-9  # and by at least this much


def _flatten(values, prefix: str = "") -> dict:
    """{path: float} of every number in a claim's ``values`` (nested dicts and lists)."""
    out = {}
    if isinstance(values, dict):
        for k, v in values.items():
            out.update(_flatten(v, f"{prefix}.{k}" if prefix else str(k)))
    elif isinstance(values, (list, tuple)):
        for i, v in enumerate(values):
            out.update(_flatten(v, f"{prefix}[{i}]"))
    elif isinstance(values, (int, float)) and not isinstance(values, bool):
        out[prefix] = float(values)
    return out


def claim_statistics(ensemble: dict, paper_claims) -> dict:
    """{claim id: {name: {"mean", "min", "max", "n"}}}: each number of each claim over the members.

    ``paper_claims`` (``claims.paper_claims``) is applied to member i of every gait of ``ensemble``
    ({gait: [summary per member]}) for each i the gaits share; a number's mean, min and max are over
    those members (module docstring).
    """
    n = min((len(v) for v in ensemble.values()), default=0)
    per_claim: dict = {}
    for i in range(n):
        for entry in paper_claims({g: members[i] for g, members in ensemble.items()}):
            for name, x in _flatten(entry["values"]).items():
                per_claim.setdefault(entry["id"], {}).setdefault(name, []).append(x)
    out = {}
    for cid, numbers in per_claim.items():
        out[cid] = {}
        for name, xs in numbers.items():
            finite = all(math.isfinite(x) for x in xs)
            out[cid][name] = {"mean": sum(xs) / len(xs) if finite else _nonfinite(xs),
                              "min": min(xs), "max": max(xs), "n": len(xs)}
    return out


def _nonfinite(xs):
    """The common value of numbers some of which are not finite, or None when they differ."""
    return xs[0] if all(x == xs[0] for x in xs) else None


def verdict(entry: dict):
    """A claim entry's verdict (``verdict`` if present, else ``holds``)."""
    return entry.get("verdict", entry.get("holds"))


def _within(mean, old: dict) -> tuple[bool, float]:
    lo, hi = old.get("min"), old.get("max")
    if mean is None or lo is None or hi is None:
        return mean == old.get("mean"), 0.0
    if not all(math.isfinite(x) for x in (mean, lo, hi)):
        return mean == old.get("mean"), 0.0
    tol = max(TOLERANCE * max(abs(lo), abs(hi), hi - lo), ABSOLUTE)
    return lo - tol <= mean <= hi + tol, tol


def compare_claims(old: list[dict], new: list[dict]) -> list[str]:
    """The mismatches between the committed report ``old`` and the regenerated ``new`` (empty: they agree).

    Implements: the agreement rule of the module docstring. Each mismatch is one line naming
    the claim, what differs, the committed and the new value.
    """
    for name, report in (("committed", old), ("regenerated", new)):
        if not isinstance(report, list) or not all(isinstance(e, dict) and "id" in e for e in report):
            raise ValueError(f"the {name} claims must be a list of entries with an 'id', got {type(report).__name__}")
    before, after = {e["id"]: e for e in old}, {e["id"]: e for e in new}
    out = [f"{cid}: committed, missing from the regenerated report" for cid in before if cid not in after]
    out += [f"{cid}: regenerated, not in the committed report" for cid in after if cid not in before]
    for cid in (c for c in before if c in after):
        a, b = before[cid], after[cid]
        if verdict(a) != verdict(b):
            out.append(f"{cid}: verdict {verdict(a)!r} committed, {verdict(b)!r} now")
        if a.get("kind", "claim") != b.get("kind", "claim"):
            out.append(f"{cid}: kind {a.get('kind', 'claim')!r} committed, {b.get('kind', 'claim')!r} now")
        stats_a, stats_b = a.get("statistics") or {}, b.get("statistics") or {}
        for name in stats_a:
            if name not in stats_b:
                out.append(f"{cid} {name}: statistic committed, missing now")
                continue
            ok, tol = _within(stats_b[name].get("mean"), stats_a[name])
            if not ok:
                out.append(f"{cid} {name}: mean {stats_b[name].get('mean')!r} now, outside the committed "
                           f"[{stats_a[name].get('min')!r}, {stats_a[name].get('max')!r}] +- {tol:.3g}")
    return out


def read_committed(path: str) -> list[dict]:
    """The claim entries of the committed ``claims.json`` at ``path``.

    ``--check`` reads them before regenerating. Raises FileNotFoundError when there is no such file
    and ValueError naming the file when it is not a list of claim entries, or when it is a smoke
    run's report (``cobra-ref figures --quick``: an object whose first key is "smoke run"), which is
    never compared.
    """
    with open(path, encoding="utf-8") as f:
        try:
            report = json.load(f)
        except ValueError as exc:
            raise ValueError(f"{path} is not JSON: {exc}") from None
    if isinstance(report, dict) and "smoke run" in report:
        raise ValueError(f"{path} is a smoke run's report (cobra-ref figures --quick), which cannot be compared: "
                         "--check compares a full run with the committed full results; write those with "
                         "'cobra-ref figures' (without --quick) first")
    if not isinstance(report, list) or not all(isinstance(e, dict) and "id" in e for e in report):
        raise ValueError(f"{path} is not a claims report (a list of entries with an 'id')")
    return report


def mismatch_table(mismatches: list[str]) -> str:
    """The mismatches as a markdown table (one row each) for stderr."""
    rows = ["| # | mismatch |", "|---|---|"] + [f"| {i + 1} | {m.replace('|', '/')} |" for i, m in enumerate(mismatches)]
    return "\n".join(rows) + "\n"
