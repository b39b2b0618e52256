"""Fig. 9: how far each gait moved the box in the same time: net displacement and path length.

The paper's fig. 9 "depicts the total distance the robot moves the box for each gait in the
same amount of time". "Total distance" can mean the box's net displacement or the length of its
path; they differ where the box wanders (sidewinding: 0.10 against 0.14 m), so both are shown,
each under its own name:

* net displacement d_box(t) = |x_box(t) - x_box(0)| (horizontal; ``analysis.box_distance``),
* path length s_box(t) = sum over the steps of |x_box,k+1 - x_box,k| (horizontal; ``path_length``).

Panels: d_box(t) of every gait's nominal run; the final d_box (bar) and s_box (hatched bar) per
gait, labelled with their values; the box's horizontal path x_box(t) - x_box(0) (top view, equal
scale), which shows the direction as well (the mirrored J gait moves the box the other way). Each
gait has its own colour and line style (``common.gait_line``): J-mirror's d_box is J's (its
mirror image), so its dashed line lies on J's solid one, as the title says. Every panel is in
metres, or in millimetres when no gait moved the box 0.1 m (``distance_unit``).

With an ``ensemble`` ({gait: [``analysis.summary`` per member]}), a panel of its own shows each
member's net displacement over the members' window (``box_distance`` of each summary: one dot
per member and their 10-90 % range, ``common.draw_spread``): the members' shorter runs never
share an axis with the nominal runs.
"""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from ..analysis import box_distance
from . import common

BAR_WIDTH = 0.4  # [bar slots] each of a gait's two bars
MM_BELOW = 0.1  # [m] distances all below this are shown in millimetres
NET_NAME, PATH_NAME = "net displacement", "path length"


def path_length(traj) -> np.ndarray:
    """(N+1,) length of the box's horizontal path from its start, sum_k |x_box,k+1 - x_box,k| [m]."""
    steps = np.linalg.norm(np.diff(traj.box_pose[:, :2], axis=0), axis=1)
    return np.concatenate([[0.0], np.cumsum(steps)])


def distance_unit(finals: list[float]) -> tuple[float, str]:
    """(scale, unit) of the figure's distances: (1, "m"), or (1000, "mm") when every final
    distance is below ``MM_BELOW``.

    Fig. 9's unit; a value in metres times scale is in unit.
    """
    return (1e3, "mm") if max((abs(d) for d in finals), default=0.0) < MM_BELOW else (1.0, "m")


def distance_labels(values: list[float], unit: str) -> list[str]:
    """Bar labels "<value> <unit>", in the axis's unit, with three significant digits of the
    largest value (2.56 m and 0.33 m; 6.92 mm and 2.15 mm), never in powers of ten.

    Fig. 9's bar labels; the decimals are 2 - floor(log10(largest)), at least 0.
    """
    largest = max((abs(d) for d in values), default=0.0)
    decimals = max(0, 2 - int(np.floor(np.log10(largest)))) if largest > 0 else 2
    return [f"{d:.{decimals}f} {unit}" for d in values]


def plot_finals(ax, rows, nets: np.ndarray, paths: np.ndarray, unit: str) -> None:
    """Per gait, the final net displacement (bar) and path length (hatched bar) of the nominal
    runs, in ``unit``, each labelled with its value (one label format for both)."""
    colors = [common.gait_color(g) for g, _ in rows]
    x = np.arange(len(rows), dtype=float)
    labels = distance_labels(list(nets) + list(paths), unit)
    for k, (values, extra) in enumerate(((nets, {}), (paths, {"hatch": "////", "alpha": 0.55}))):
        bars = ax.bar(x + (k - 0.5) * BAR_WIDTH, values, width=BAR_WIDTH, color=colors, edgecolor="k",
                      lw=0.3, **extra)
        # turned labels: no wider than a bar
        ax.bar_label(bars, labels[k * len(rows):(k + 1) * len(rows)], fontsize=5, padding=1.5, rotation=90)
    ax.margins(y=0.45)  # room above the tallest bar for its turned label
    ax.set_ylim(bottom=0.0)
    ax.set_xticks(x, [common.gait_label(g, t) for g, t in rows], rotation=30, ha="right")
    ax.set_ylabel(f"final distance [{unit}]")
    ax.legend(handles=[Patch(facecolor="0.6", edgecolor="k", lw=0.3, label=NET_NAME),
                      Patch(facecolor="0.6", edgecolor="k", lw=0.3, alpha=0.55, hatch="////", label=PATH_NAME)],
              loc="upper left", fontsize=5.5)


def plot_members(ax, rows, ensemble: dict, scale: float, unit: str) -> None:
    """Per gait, the net displacement of each ensemble member over the members' window, and their range."""
    n_members, top = 0, 0.0
    for i, (gait, _) in enumerate(rows):
        values = scale * common.ensemble_values(ensemble, gait, "box_distance")
        common.draw_spread(ax, float(i), values, common.gait_color(gait), gait, width=0.4)
        n_members = max(n_members, len(values))
        top = max([top, *values[np.isfinite(values)]])
    window = common.ensemble_window(ensemble)
    # headroom above the members for the legend
    ax.set_ylim(0.0, 1.5 * top if top > 0 else None)
    ax.set_xticks(range(len(rows)), [common.gait_label(g, t) for g, t in rows], rotation=30, ha="right")
    ax.set_xlim(-0.6, len(rows) - 0.4)
    ax.grid(False, axis="x")
    ax.set_ylabel(f"{NET_NAME} [{unit}]")
    ax.set_title(f"ensemble members, {NET_NAME}" + (f" after {window:g} s" if window else ""), loc="left")
    ax.legend(handles=common.spread_handles(n_members, window), loc="upper left", fontsize=5.5, ncol=2)


def plot_paths(ax, rows, unit: str, scale: float) -> None:
    """The box's horizontal displacement x_box(t) - x_box(0) per gait (top view, equal scale), in
    ``unit`` (metres x ``scale``).

    The direction in which each gait pushed the box.
    """
    for gait, traj in rows:
        d = scale * (traj.box_pose[:, :2] - traj.box_pose[0, :2])
        ax.plot(d[:, 0], d[:, 1], **common.gait_line(gait))
        ax.plot(d[-1:, 0], d[-1:, 1], "o", ms=3, color=common.gait_color(gait))
    ax.plot([0.0], [0.0], "k+", ms=6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.set_xlabel(rf"$\Delta x_{{box}}$ [{unit}]")
    ax.set_ylabel(rf"$\Delta y_{{box}}$ [{unit}]")
    ax.set_title("box path (+ = start)", loc="left")


def plot_net(ax, rows, distances: list, scale: float, unit: str) -> None:
    """d_box(t) of every gait's nominal run, in ``unit``, each in its ``gait_line``."""
    for (gait, traj), d in zip(rows, distances):
        ax.plot(traj.t[: len(d)], scale * d, **common.gait_line(gait), label=common.gait_label(gait, traj))
    ax.set_xlabel("time [s]")
    ax.set_ylabel(rf"{NET_NAME} $d_{{box}}$ [{unit}]")
    ax.set_title(f"{NET_NAME} of the box", loc="left")
    if rows:
        ax.legend(loc="upper left")


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None,
         goals: dict | None = None) -> list[str]:
    """Write ``fig09_box_distance.png/.pdf``: the box's net displacement over time, the final net
    displacement and path length per gait, the box's path, and with ``ensemble`` the members' net
    displacements on a panel of their own.

    Implements: [COBRA] fig. 9 with ``analysis.box_distance`` (net displacement) and
    ``path_length``.
    """
    rows = common.ordered(results)
    spread = any(len(common.ensemble_values(ensemble, g, "box_distance")) for g, _ in rows)
    fig = common.new_figure(common.TWO_COLUMN, 4.4)
    (ax_t, ax_bar), (ax_xy, ax_members) = fig.subplots(2, 2)
    distances = [box_distance(traj) for _, traj in rows]
    lengths = [path_length(traj) for _, traj in rows]
    scale, unit = distance_unit([float(s[-1]) for s in lengths])
    plot_net(ax_t, rows, distances, scale, unit)
    T = max((t.duration for _, t in rows), default=0)
    if rows:
        plot_finals(ax_bar, rows, scale * np.array([d[-1] for d in distances]),
                    scale * np.array([s[-1] for s in lengths]), unit)
        plot_paths(ax_xy, rows, unit, scale)
    else:
        for ax in (ax_t, ax_bar, ax_xy):
            common.empty_panel(ax, "no gait to show")
    ax_bar.set_title(f"after {T:.3g} s: {NET_NAME} and {PATH_NAME}", loc="left")
    if spread:
        plot_members(ax_members, rows, ensemble, scale, unit)
    else:
        ax_members.set_axis_off()
    note = common.mirror_note(g for g, _ in rows)
    fig.suptitle(f"Box distance in {T:.3g} s: the paper's \"total distance\" as {NET_NAME} and as {PATH_NAME}"
                 + (f"\n{note} (their box paths are mirror images)" if note else ""))
    return common.save(fig, out_dir, "fig09_box_distance")


if __name__ == "__main__":
    common.main(make)
