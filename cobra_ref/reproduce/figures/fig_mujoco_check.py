"""The MuJoCo comparison as a picture: the robot's travel without the box, and the box ensembles.

The figure of ``reproduce.mujoco_check``. Top: for each gait, the travel of the robot's centre of
mass (no box) in cobra_ref and in MuJoCo, as bars of its length with the relative difference
|d_MuJoCo - d_ours| / |d_ours| and the verdict against the 10 % band written above them. Bottom: one
panel per gait of the box ensembles, each member's box displacement as a dot (cobra_ref and MuJoCo),
three panels to a row, with the length and direction ranges of the overlap rule and its verdict. The
rules are stated in words above the panels.
"""

from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Wedge

from .common import TWO_COLUMN, new_figure, ordered, paper_style, save

STEM = "fig_mujoco_check"
BOX_COLUMNS = 3  # box panels per row
OURS, MUJOCO = "tab:blue", "tab:orange"


@paper_style
def make(rows: list[dict], out_dir: str) -> list[str]:
    """Write ``fig_mujoco_check.png`` / ``.pdf`` from the rows of ``robot_travel_rows`` and
    ``box_ensemble_rows`` (either may be missing); return the paths.
    """
    travel = [r for r in rows if r["kind"] == "travel"]
    boxes = dict(ordered({r["gait"]: r for r in rows if r["kind"] == "box"}))
    # the box panels three to a row, under the travel panel that spans the width
    n_cols = min(len(boxes), BOX_COLUMNS) or 1
    n_rows = -(-len(boxes) // BOX_COLUMNS)
    heights = ([1.0] if travel else []) + [1.0] * n_rows or [1.0]  # one empty row when there is nothing
    fig = new_figure(TWO_COLUMN, 2.3 * len(heights) + 0.3)
    grid = fig.add_gridspec(len(heights), n_cols, height_ratios=heights)
    if travel:
        _travel_panel(fig.add_subplot(grid[0, :]), travel)
    first = 1 if travel else 0
    for k, row in enumerate(boxes.values()):
        _box_panel(fig.add_subplot(grid[first + k // n_cols, k % n_cols]), row)
    if boxes:  # one key for the box panels, under them
        fig.legend(handles=[Line2D([], [], marker="o", ls="none", ms=3, color=OURS, label="cobra_ref member"),
                            Line2D([], [], marker="x", ls="none", ms=4, color=MUJOCO, label="MuJoCo member"),
                            Patch(color="0.5", alpha=0.3, lw=0, label="range of length x direction (overlap rule)")],
                   loc="outside lower center", ncol=3, fontsize=6)
    fig.suptitle(_caption(travel, list(boxes.values())), fontsize=6.5)
    return save(fig, out_dir, STEM)


def _caption(travel: list[dict], boxes: list[dict]) -> str:
    """The two rules in words, one line each."""
    lines = []
    if travel:
        r = travel[0]
        lines.append(f"Robot alone, {r['duration']:g} s from the same settled start: holds when "
                     f"|d_MuJoCo - d_ours| <= {100 * r['band']:g} % of |d_ours| (centre-of-mass travel).")
    if boxes:
        r = boxes[0]
        lines.append(f"Box ensembles, {r['duration']:g} s: overlap when the ranges of length and of direction "
                     f"meet, each member's end point widened by {1e3 * r['resolution']:g} mm.")
    return "\n".join(lines)


def _travel_panel(ax, rows: list[dict]) -> None:
    """Grouped bars of the travel length per gait, with the relative difference and the verdict above."""
    rows = [r for _, r in ordered({r["gait"]: r for r in rows})]
    x = np.arange(len(rows))
    ax.bar(x - 0.18, [r["ours_length"] for r in rows], 0.36, color=OURS, label="cobra_ref")
    ax.bar(x + 0.18, [r["mujoco_length"] for r in rows], 0.36, color=MUJOCO, label="MuJoCo")
    top = max(max(r["ours_length"], r["mujoco_length"]) for r in rows)
    for xi, r in zip(x, rows):
        verdict = "holds" if r["holds"] else "FAILS"
        ax.text(xi, max(r["ours_length"], r["mujoco_length"]) + 0.03 * top,
                f"{100 * r['relative']:.1f} %, {r['angle_deg']:.1f} deg\n{verdict}", ha="center", va="bottom",
                fontsize=6)
    ax.set_xticks(x, [r["gait"] for r in rows])
    ax.set_ylim(0, 1.3 * top)
    ax.set_ylabel("travel of the centre of mass [m]")
    ax.legend(loc="upper left", ncol=2)


def _box_panel(ax, row: dict) -> None:
    """The members' box displacements (marks), zoomed on their end points, with the ranges of the
    overlap rule (shaded ring sectors: length interval x arc of directions) and their numbers."""
    d_o, d_m = np.array(row["ours"]).reshape(-1, 2), np.array(row["mujoco"]).reshape(-1, 2)
    for (lo, hi), (centre, half), color in ((row["ours_length"], row["ours_direction_deg"], OURS),
                                            (row["mujoco_length"], row["mujoco_direction_deg"], MUJOCO)):
        ax.add_patch(Wedge((0, 0), 1e3 * hi, centre - half, centre + half, width=1e3 * (hi - lo), color=color,
                           alpha=0.15, lw=0))
    ax.plot(*(1e3 * d_o.T), "o", color=OURS, ms=3)
    ax.plot(*(1e3 * d_m.T), "x", color=MUJOCO, ms=4)
    # a square window around every end point, 3 resolutions wide at least
    ends = 1e3 * np.vstack([d_o, d_m])
    centre, half = (ends.max(axis=0) + ends.min(axis=0)) / 2, max(np.ptp(ends, axis=0).max() / 2, 0.0)
    half += 3e3 * row["resolution"]
    ax.set_xlim(centre[0] - half, centre[0] + half)
    ax.set_ylim(centre[1] - half, centre[1] + half)
    ax.set_aspect("equal")
    ax.set_xlabel("box dx from its start [mm]")
    ax.set_ylabel("box dy [mm]")
    ax.text(0.98, 0.03, "\n".join(_ranges(row)), transform=ax.transAxes, ha="right", va="bottom", fontsize=6)
    verdict = {True: "overlap", False: "DO NOT overlap", None: "box barely moves, not tested"}[row["holds"]]
    ax.set_title(f"{row['gait']}, {row['n_members']} members: {verdict}", fontsize=7)


def _ranges(row: dict) -> list[str]:
    """One line per simulator: its length interval [mm] and arc of directions (centre +- half) [deg]."""
    lines = []
    for who, key in (("ours", "ours"), ("MuJoCo", "mujoco")):
        (lo, hi), (centre, half) = row[f"{key}_length"], row[f"{key}_direction_deg"]
        lines.append(f"{who} {1e3 * lo:.0f}-{1e3 * hi:.0f} mm, {centre:.0f}\u00b1{half:.0f}\u00b0")
    return lines
