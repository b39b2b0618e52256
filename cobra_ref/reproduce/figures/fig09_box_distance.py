"""Fig. 9: how far each gait moved the box in the same time.

The paper's fig. 9 "depicts the total distance the robot moves the box for each gait in the
same amount of time". Plotted, from ``analysis.box_distance``, d_box(t) = |x_box(t) - x_box(0)|
(horizontal) for every gait in one axes, and a bar of the final distance per gait, labelled with
its value. A third panel shows the box's horizontal path relative to its start,
x_box(t) - x_box(0), which shows the direction as well: the mirrored J gait should move the box
the other way. Every panel is in metres, or in millimetres when no gait moved the box 0.1 m
(``distance_unit``: short labels on the short runs), and the bar labels are in that unit.

With an ``ensemble`` ({gait: [``analysis.summary`` per member]}), each gait's bar (the nominal
run) has the members' final distances (``box_distance`` of each summary) beside it: one dot per
member and their 10-90 % range (``common.draw_spread``).
"""

from __future__ import annotations

import numpy as np
from matplotlib.patches import Patch
from matplotlib.ticker import MaxNLocator

from ..analysis import box_distance
from . import common

BAR_WIDTH = 0.8  # without an ensemble; with one, the bar is narrower and the spread beside it
BAR_WIDTH_ENSEMBLE, SPREAD_OFFSET, SPREAD_WIDTH = 0.45, 0.4, 0.16  # [bar slots]
MM_BELOW = 0.1  # [m] distances all below this are shown in millimetres


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


def plot_finals(ax, rows, finals: np.ndarray, unit: str, scale: float, ensemble: dict | None) -> None:
    """Bars of the nominal runs' final distances (in ``unit``: metres x ``scale``), labelled; with
    an ensemble, each gait's members beside its bar.
    """
    colors = [common.gait_color(g) for g, _ in rows]
    spread = any(len(common.ensemble_values(ensemble, g, "box_distance")) for g, _ in rows)
    x = np.arange(len(rows), dtype=float)
    width, shift = (BAR_WIDTH_ENSEMBLE, SPREAD_OFFSET / 2) if spread else (BAR_WIDTH, 0.0)
    bars = ax.bar(x - shift, finals, width=width, color=colors)
    # turned labels: no wider than a bar, and clear of the spread beside it
    ax.bar_label(bars, distance_labels(list(finals), unit), fontsize=5.5, padding=1.5, rotation=90)
    n_members = 0
    for i, (gait, _) in enumerate(rows):
        values = scale * common.ensemble_values(ensemble, gait, "box_distance")
        common.draw_spread(ax, x[i] + SPREAD_OFFSET / 2, values, colors[i], gait, width=SPREAD_WIDTH)
        n_members = max(n_members, len(values))
    if spread:
        T = max((traj.duration for _, traj in rows), default=0.0)
        nominal = Patch(facecolor="0.6", label=f"nominal run, {T:g} s (bar)")
        ax.figure.legend(handles=[nominal] + common.spread_handles(n_members, common.ensemble_window(ensemble)),
                         loc="outside lower center", ncol=3)
    ax.margins(y=0.45)  # room above the tallest bar for its turned label
    ax.set_ylim(bottom=0.0)
    ax.set_xticks(x, [common.gait_label(g, t) for g, t in rows], rotation=30, ha="right")
    ax.set_ylabel(rf"final $d_{{box}}$ [{unit}]")


def plot_paths(ax, rows, unit: str, scale: float) -> None:
    """The box's horizontal displacement x_box(t) - x_box(0) per gait (top view, equal scale), in
    ``unit`` (metres x ``scale``).

    The direction in which each gait pushed the box.
    """
    for gait, traj in rows:
        d = scale * (traj.box_pose[:, :2] - traj.box_pose[0, :2])
        ax.plot(d[:, 0], d[:, 1], color=common.gait_color(gait))
        ax.plot(d[-1:, 0], d[-1:, 1], "o", ms=3, color=common.gait_color(gait))
    ax.plot([0.0], [0.0], "k+", ms=6)
    ax.set_aspect("equal", adjustable="datalim")
    ax.xaxis.set_major_locator(MaxNLocator(4))
    ax.yaxis.set_major_locator(MaxNLocator(4))
    ax.set_xlabel(rf"$\Delta x_{{box}}$ [{unit}]")
    ax.set_ylabel(rf"$\Delta y_{{box}}$ [{unit}]")
    ax.set_title("box path (+ = start)")


@common.paper_style
def make(results: dict, out_dir: str, model, ensemble: dict | None = None) -> list[str]:
    """Write ``fig09_box_distance.png/.pdf``: box distance vs time, final distance per gait (with
    the ensemble's members beside each bar when ``ensemble`` is given), and the box's path.

    Implements: [COBRA] fig. 9 with ``analysis.box_distance``.
    """
    rows = common.ordered(results)
    fig = common.new_figure(common.TWO_COLUMN, 2.3)
    ax_t, ax_bar, ax_xy = fig.subplots(1, 3, width_ratios=[1.4, 1.0, 1.0])
    if not rows:
        for ax in (ax_t, ax_bar, ax_xy):
            common.empty_panel(ax, "no gait to show")
    distances = [box_distance(traj) for _, traj in rows]
    scale, unit = distance_unit([float(d[-1]) if len(d) else 0.0 for d in distances])
    for (gait, traj), d in zip(rows, distances):
        ax_t.plot(traj.t[: len(d)], scale * d, color=common.gait_color(gait), label=common.gait_label(gait, traj))
    ax_t.set_xlabel("time [s]")
    ax_t.set_ylabel(rf"box distance $d_{{box}}$ [{unit}]")
    ax_t.set_title("distance the box moved")
    if rows:
        ax_t.legend(loc="upper left")
        finals = scale * np.array([d[-1] if len(d) else 0.0 for d in distances])
        plot_finals(ax_bar, rows, finals, unit, scale, ensemble)
        plot_paths(ax_xy, rows, unit, scale)
    ax_bar.set_title(f"after {max((t.duration for _, t in rows), default=0):.3g} s")
    return common.save(fig, out_dir, "fig09_box_distance")


if __name__ == "__main__":
    common.main(make)
