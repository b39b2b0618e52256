"""The verdict map's files (``claims_map``): ``claims_map.json``, ``claims_map.md`` and its figures.

``fig_claims_map.png`` draws the map, one panel per claim.

Each panel is a grid: a row per unknown of the paper (box size, box mass, robot-box mu, placement,
and the corner set-up), a column per value, the nominal set-up repeated in each row; a cell's colour
is the share of members (or scenarios) for which the claim held (red 0, green 1), its text the
value and the count. ``fig_claims_thresholds.png``: each threshold's share per set-up, a panel per
claim with thresholds.
"""

from __future__ import annotations

import json
import os

import numpy as np

from .claims_map import mapped, markdown, thresholds
from .stamps import clean

__all__ = ["draw_map", "grid", "write_map"]

ROWS = ("box size", "box mass", "robot-box mu", "placement", "corner")
_VALUE = {"box size": lambda r: f"{r['box_size']:g} m", "box mass": lambda r: f"{r['box_mass']:g} kg",
          "robot-box mu": lambda r: f"mu_rb {r['mu_robot_box']:g}", "placement": lambda r: r["placement"],
          "corner": lambda r: f"{r['box_size']:g} m, mu_rb {r['mu_robot_box']:g}"}
_ORDER = {"box size": "box_size", "box mass": "box_mass", "robot-box mu": "mu_robot_box"}


def grid(setups: list[dict]) -> list[tuple[str, list[dict]]]:
    """The set-ups arranged as the panels' rows: (unknown of ``ROWS``, its set-ups), each row the
    nominal set-up and the set-ups that change that unknown, ordered by value (the placement row:
    per gait, travel; the corner row: the corner alone)."""
    nominal = next((r for r in setups if r["unknown"] == "nominal"), None)
    out = []
    for unknown in ROWS:
        row = [r for r in setups if r["unknown"] == unknown]
        if unknown != "corner" and nominal is not None:
            row.append(nominal)
        if unknown in _ORDER:
            row.sort(key=lambda r: r[_ORDER[unknown]])
        elif unknown == "placement":
            row.sort(key=lambda r: r["placement"] != "per gait")
        if row:
            out.append((unknown, row))
    return out


def _panel(ax, rows: list[tuple[str, list[dict]]], value, title: str) -> None:
    """One claim's grid on ``ax``: ``value(set-up)`` -> (share or None, text)."""
    width = max(len(r) for _, r in rows)
    share = np.full((len(rows), width), np.nan)
    for i, (unknown, row) in enumerate(rows):
        for j, setup in enumerate(row):
            f, text = value(setup)
            if f is not None:
                share[i, j] = f
            ax.text(j, i, f"{_VALUE[unknown](setup)}\n{text}", ha="center", va="center", fontsize=5.5)
    ax.imshow(share, cmap="RdYlGn", vmin=0.0, vmax=1.0, aspect="auto")
    ax.set_yticks(range(len(rows)), [u for u, _ in rows], fontsize=6)
    ax.set_xticks([])
    ax.set_title(title, fontsize=8)


def draw_map(claims_map: dict, out_dir: str, note: str | None = None) -> list[str]:
    """Write ``fig_claims_map.png`` (and ``fig_claims_thresholds.png`` when a claim has thresholds)
    to ``out_dir``; return the paths."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..infra.output import atomic_write

    rows = grid(claims_map["setups"])
    cids = mapped(claims_map)
    paths = []

    def verdict_of(cid):
        def value(setup):
            c = setup["claims"].get(cid)
            if c is None or c["verdict"] == "not tested":
                return None, "not tested"
            return c["fraction"], f"{c['verdict']} ({c['held']}/{c['n']})"
        return value

    figures = [("fig_claims_map.png", "Where each claim holds over the paper's unknowns",
                [(cid, verdict_of(cid)) for cid in cids])]
    with_t = [(cid, t) for cid in cids for t in thresholds(claims_map, cid)]
    if with_t:
        figures.append(("fig_claims_thresholds.png", "Each claim's verdict at each of its thresholds, per set-up",
                        [(f"{cid} at {t}", _at(cid, t)) for cid, t in with_t]))
    for name, what, panels in figures:
        ncol = min(4, len(panels))
        nrow = -(-len(panels) // ncol)
        fig, axes = plt.subplots(nrow, ncol, figsize=(3.2 * ncol, 2.2 * nrow), squeeze=False)
        for ax, (title, value) in zip(axes.flat, panels):
            _panel(ax, rows, value, title)
        for ax in list(axes.flat)[len(panels):]:
            ax.axis("off")
        fig.suptitle((f"{note}\n" if note else "") + f"{what} ({claims_map['members']} members per gait, "
                     "colour: share holding)", fontsize=8)
        fig.tight_layout()
        path = os.path.join(out_dir, name)
        atomic_write(path, lambda tmp: fig.savefig(tmp, dpi=130, format="png"))
        plt.close(fig)
        paths.append(path)
    return paths


def _at(cid: str, t: str):
    def value(setup):
        s = ((setup["claims"].get(cid) or {}).get("sensitivity") or {}).get(t)
        if not s or not s.get("n"):
            return None, "not tested"
        return s["holds"] / s["n"], f"{s['verdict']} ({s['holds']}/{s['n']})"
    return value


def write_map(claims_map: dict, out_dir: str, note: str | None = None) -> list[str]:
    """Write ``claims_map.json``, ``claims_map.md`` and the map's figures (``map_figure``) to
    ``out_dir``, each marked with ``note`` (a smoke run's) when given; return the paths."""
    from ..infra.output import write_text

    body = ({"smoke run": note} if note else {}) | clean(claims_map)
    paths = {"claims_map.json": json.dumps(body, indent=1),
             "claims_map.md": (f"**{note}**\n\n" if note else "") + markdown(claims_map)}
    for name, text in paths.items():
        write_text(os.path.join(out_dir, name), text)
    return [os.path.join(out_dir, n) for n in paths] + draw_map(claims_map, out_dir, note)
