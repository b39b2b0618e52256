"""Which of the paper's claims hold, and under which of its unknowns: the verdict map.

[COBRA] gives the box's mass (0.5 kg) and one coefficient of friction (1.0) for every pair, and no
box size, no robot-box friction of its own, no box placement; our claims report rests on
assumptions for each (A8 box 0.10 m, A22 mu_rb = 0.5, A9 / A31 placement). The map judges every
claim of ``claims.ensemble_claims`` again at other values of those unknowns (``SETUPS``, fixed
here before any run):

* the nominal set-up of the figures (0.10 m, 0.5 kg, mu_rb = 0.5, the per-gait placement);
* three slices through it, one unknown changed at a time: box size 0.20 and 0.30 m, box mass 0.25
  and 2 kg, robot-box mu 0.3 and 1.0 (the paper's single mu); and the other placement rule, every
  gait's box in the direction it travels (A31 for every gait, ``runs.PLACEMENTS``);
* one corner: the 0.30 m box with the paper's single mu = 1.0 (a box the robot cannot tip, pushed
  with the paper's friction).

The full grid (3 x 3 x 3 x 2 = 54 set-ups) would cost about seven times the slices (about an hour and
a half on two cores); the slices cost ``len(SETUPS) - 1`` ensembles, about 12 minutes on two cores.

Every set-up is an ensemble of ``MAP_MEMBERS`` = 4 members per gait (``ensemble.members``, the
figures' perturbations), each judged on the figures' window (``regenerate.ENSEMBLE_DURATION`` =
6 s) by the same rules as the figures' report. Gaits: C, S, J and sidewinding; J-mirror is J
reflected by construction and adds no set-up's evidence. Gait parameters: the committed optima of
the nominal set-up (``cobra_ref/optimized``) at every set-up; re-optimizing each gait at each
set-up (about 4 minutes of rollouts per gait and set-up) is not afforded. The nominal set-up's
ensembles are the figures' own first ``MAP_MEMBERS`` members.

Thresholds: each claim with one reports its verdict at a fixed list of thresholds
(``entry["details"]["sensitivity"]`` of ``claims``); the map keeps them per set-up.

Each cell of the map is a dict {"verdict", "holds", "n", "held", "fraction"} of one claim at one
set-up; the map is written to ``claims_map.json`` and ``claims_map.md`` and drawn as
``fig_claims_map.png`` (one panel per claim), and its cells are entries of ``claims.json`` (id
``map:<set-up>:<claim>``, kind "map") so that ``figures --check`` compares them with the
committed ones like every other verdict.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from ..params import CobraParameters
from .ensemble import members

__all__ = ["MAP_GAITS", "MAP_MEMBERS", "SETUPS", "SetUp", "all_hold", "check_entries", "judge", "map_specs",
           "mapped", "markdown", "thresholds", "where_claims_hold", "where_lines"]

MAP_MEMBERS = 4  # members per gait and set-up (member 0 nominal)
MAP_GAITS = ("C", "S", "J", "sidewinding")
DEFAULTS = CobraParameters()


@dataclass(frozen=True)
class SetUp:
    """One point of the map: a value for each unknown of the paper (module docstring)."""

    name: str
    box_size: float = 0.10  # [m] A8
    box_mass: float = 0.5  # [kg] the paper
    mu_robot_box: float = 0.5  # [-] A22
    placement: str = "per gait"  # A9 / A31, ``runs.PLACEMENTS``
    unknown: str = "nominal"  # the unknown this set-up changes ("nominal", "corner")

    @property
    def nominal(self) -> bool:
        return self.unknown == "nominal"

    def as_dict(self) -> dict:
        return {"name": self.name, "unknown": self.unknown, "box_size": self.box_size, "box_mass": self.box_mass,
                "mu_robot_box": self.mu_robot_box, "placement": self.placement}


NOMINAL = SetUp("nominal")
SETUPS = (
    NOMINAL,
    SetUp("box 0.20 m", box_size=0.20, unknown="box size"),
    SetUp("box 0.30 m", box_size=0.30, unknown="box size"),
    SetUp("box 0.25 kg", box_mass=0.25, unknown="box mass"),
    SetUp("box 2 kg", box_mass=2.0, unknown="box mass"),
    SetUp("mu_rb 0.3", mu_robot_box=0.3, unknown="robot-box mu"),
    SetUp("mu_rb 1.0", mu_robot_box=1.0, unknown="robot-box mu"),
    SetUp("travel placement", placement="travel", unknown="placement"),
    SetUp("box 0.30 m with mu_rb 1.0", box_size=0.30, mu_robot_box=1.0, unknown="corner"),
)


def map_specs(figure_specs: dict, setups=SETUPS, n_members: int = MAP_MEMBERS, duration: float | None = None) -> dict:
    """{set-up name: {gait: [RunSpec per member]}} of the map: the nominal set-up's are the figures'
    own specs (``figure_specs`` {gait: [RunSpec]}, their first ``n_members``), every other set-up's
    are the same runs with the set-up's box, friction and placement, each ``duration`` seconds
    (default: the figures' members' duration)."""
    gaits = [g for g in MAP_GAITS if g in figure_specs]
    out = {}
    for setup in setups:
        out[setup.name] = {}
        for g in gaits:
            own = figure_specs[g][:n_members]
            if setup.nominal:
                out[setup.name][g] = own
                continue
            length = duration if duration is not None else own[-1].duration
            ms = members(g, n_members)
            # a value at the model's default is left unset, so that the same run has one cache entry
            box = {name: (None if getattr(setup, name) == getattr(DEFAULTS, name) else getattr(setup, name))
                   for name in ("box_size", "box_mass", "mu_robot_box")}
            out[setup.name][g] = [replace(own[0], duration=length, member=None if m.nominal else m,
                                          placement=setup.placement, **box) for m in ms]
    return out


def judge(specs: dict, runs: dict, window: float) -> dict:
    """The map: {"setups": [set-up dict with "claims": {claim id: cell}], ...} from ``map_specs``'
    ``specs`` and their trajectories ``runs`` {RunSpec: Trajectory}, each member judged on its
    first ``window`` seconds by ``claims.ensemble_claims`` (module docstring)."""
    from .claims import ensemble_claims, gait_summaries

    rows = []
    for setup in SETUPS:
        if setup.name not in specs:
            continue
        ensemble = {g: [gait_summaries({g: runs[s].truncated(window)})[g] for s in ms]
                    for g, ms in specs[setup.name].items()}
        entries = ensemble_claims(ensemble)
        cells = {e["id"]: _cell(e) for e in entries if e.get("kind", "claim") == "claim"}
        rows.append({**setup.as_dict(), "claims": cells,
                     "failed runs": sorted({k for e in entries for k in e["ensemble"]["left_out"]})})
    n = {len(ms) for per in specs.values() for ms in per.values()}
    return {"setups": rows, "members": max(n, default=0), "window (s)": window,
            "gaits": list(MAP_GAITS), "gait parameters": "the committed optima of the nominal set-up "
                                                        "(cobra_ref/optimized) at every set-up"}


def _cell(entry: dict) -> dict:
    """One claim's verdict at one set-up (module docstring), with its threshold sensitivity if any."""
    e = entry["ensemble"]
    cell = {"verdict": entry["verdict"], "holds": entry["holds"], "n": e["n"], "held": e["holds"],
            "fraction": e["fraction"]}
    sensitivity = (entry.get("details") or {}).get("sensitivity")
    if sensitivity:
        cell["sensitivity"] = {t: {k: v.get(k) for k in ("threshold", "verdict", "holds", "n")}
                               for t, v in sensitivity.items()}
    return cell


def check_entries(claims_map: dict) -> list[dict]:
    """The map's cells as entries of ``claims.json`` (id ``map:<set-up>:<claim>``, kind "map"), each
    with its fraction (and its threshold verdicts' fractions) as ``statistics``: what ``--check``
    compares (``check.compare_claims``)."""
    out = []
    for row in claims_map["setups"]:
        for cid, c in row["claims"].items():
            stats = {"fraction": c["fraction"]}
            for t, s in (c.get("sensitivity") or {}).items():
                stats[f"at {t}"] = (s["holds"] / s["n"]) if s.get("n") else None
            out.append({"id": f"map:{row['name']}:{cid}", "kind": "map", "claim": f"{cid} at {row['name']}",
                        "holds": c["holds"], "verdict": c["verdict"],
                        "ensemble": {"n": c["n"], "holds": c["held"], "fraction": c["fraction"]},
                        "statistics": {k: {"mean": v, "min": v, "max": v, "n": c["n"]}
                                       for k, v in stats.items() if v is not None}})
    return out


def mapped(claims_map: dict) -> list[str]:
    """The claims the map shows: those tested at some set-up (in the report's order)."""
    cells = [(cid, c) for r in claims_map["setups"] for cid, c in r["claims"].items()]
    return list(dict.fromkeys(cid for cid, c in cells if c["verdict"] != "not tested"))


def thresholds(claims_map: dict, cid: str) -> list[str]:
    """The thresholds (as the claim's rule writes them) at which claim ``cid`` was judged in the map."""
    return list(dict.fromkeys(t for r in claims_map["setups"]
                              for t in (r["claims"].get(cid, {}).get("sensitivity") or {})))


def where_claims_hold(claims_map: dict) -> dict:
    """{claim id: {verdict: [set-up names]}}: where in the map each claim holds, fails, is undecided."""
    out: dict = {}
    shown = mapped(claims_map)
    for row in claims_map["setups"]:
        for cid, c in row["claims"].items():
            if cid in shown:
                out.setdefault(cid, {}).setdefault(c["verdict"], []).append(row["name"])
    return out


def all_hold(claims_map: dict) -> list[str]:
    """The set-ups at which every claim tested holds."""
    return [row["name"] for row in claims_map["setups"]
            if row["claims"] and all(c["verdict"] == "holds" for c in row["claims"].values()
                                     if c["verdict"] != "not tested")]


def _mark(c: dict) -> str:
    short = {"holds": "holds", "does not hold": "fails", "undecided": "undecided", "ties": "ties"}
    if c["verdict"] == "not tested":
        return "-"
    return f"{short.get(c['verdict'], c['verdict'])} {c['held']}/{c['n']}"


def markdown(claims_map: dict) -> str:
    """``claims_map.md``: the map as a table (set-ups x claims), where each claim holds, and each
    threshold's verdicts per set-up."""
    rows = claims_map["setups"]
    cids = mapped(claims_map)
    lines = ["# Where the paper's claims hold: the verdict map over its unknowns", "",
             f"Each cell: the claim's verdict over {claims_map['members']} members per gait "
             f"({', '.join(claims_map['gaits'])}), each judged on its first {claims_map['window (s)']:g} s, and "
             f"the members (or scenarios) for which it held. Gait parameters: {claims_map['gait parameters']}. "
             "Set-ups and rules: `cobra_ref/reproduce/claims_map.py`.", "",
             "| set-up | box (m) | box (kg) | mu_rb | placement | " + " | ".join(cids) + " |",
             "|---|---|---|---|---|" + "---|" * len(cids)]
    for r in rows:
        lines.append(f"| {r['name']} | {r['box_size']:g} | {r['box_mass']:g} | {r['mu_robot_box']:g} | "
                     f"{r['placement']} | " + " | ".join(_mark(r["claims"][c]) if c in r["claims"] else ""
                                                         for c in cids) + " |")
    lines += [""] + where_lines(claims_map)
    with_thresholds = [cid for cid in cids if thresholds(claims_map, cid)]
    lines += ["", "## Each threshold's verdict, per set-up", ""] if with_thresholds else []
    for cid in with_thresholds:
        ts = thresholds(claims_map, cid)
        lines += [f"### {cid}", "", "| set-up | " + " | ".join(ts) + " |", "|---|" + "---|" * len(ts)]
        for r in rows:
            sens = r["claims"].get(cid, {}).get("sensitivity") or {}
            lines.append(f"| {r['name']} | " + " | ".join(_mark({**sens[t], "held": sens[t]["holds"]})
                                                          if t in sens else "" for t in ts) + " |")
        lines.append("")
    return "\n".join(lines) + "\n"


def where_lines(claims_map: dict) -> list[str]:
    """Markdown lines: per claim the set-ups where it holds, fails and is undecided, and the set-ups
    (if any) where every claim holds (the section of ``claims.md`` and ``claims_map.md``)."""
    every = all_hold(claims_map)
    lines = ["## Where each claim holds over the paper's unknowns (the verdict map)", ""]
    for cid, by in where_claims_hold(claims_map).items():
        parts = [f"{v}: {', '.join(names)}" for v, names in by.items()]
        lines.append(f"- **{cid}**: " + "; ".join(parts))
    lines += ["", "Every claim holds together at: " + (", ".join(every) if every else
                                                       "no set-up of the map") + "."]
    return lines
