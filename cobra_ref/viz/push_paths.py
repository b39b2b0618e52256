"""The push benchmark in one picture: every executed box path from the box's start, with its goal.

``plot_pushes(rows, path)`` takes the rows of :func:`cobra_ref.planning.benchmark.run_benchmark`
(or the ``rows`` of the JSON ``cobra-ref push --benchmark`` writes) and draws, seen from above in
the box's start frame (x = the robot's initial heading): each path as a line, its goal as a
circle of the criterion's radius (``benchmark.REACHED``), waypoints as squares, the final error
in the legend. matplotlib is imported when the figure is drawn.
"""

from __future__ import annotations

import numpy as np

from ..planning.benchmark import PASSED, REACHED


def plot_pushes(rows: list, path: str | None = None):
    """Draw the benchmark's box paths (module docstring); save to ``path`` if given; return the figure."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 7))
    colors = plt.get_cmap("tab20")(np.linspace(0, 1, max(len(rows), 2)))
    for row, color in zip(rows, colors):
        box = np.asarray(row["box_path"], dtype=float).reshape(-1, 2)
        ax.plot(box[:, 0], box[:, 1], color=color, lw=1.2,
                label=f"{row['task']}: {100 * row['final_error']:.1f} cm")
        ax.add_patch(plt.Circle(row["goal"], REACHED, fill=False, color=color, lw=1))
        for w in row.get("via", []):
            ax.add_patch(plt.Rectangle((w[0] - PASSED, w[1] - PASSED), 2 * PASSED, 2 * PASSED, fill=False,
                                       color=color, ls="--", lw=0.8))
    ax.plot(0, 0, "k+", ms=12)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m] (the robot's initial heading)")
    ax.set_ylabel("y [m]")
    ax.set_title(f"push benchmark: box paths, goals (circles of {100 * REACHED:g} cm)")
    ax.legend(fontsize=6, loc="center left", bbox_to_anchor=(1.0, 0.5))
    ax.grid(alpha=0.3)
    fig.tight_layout()
    if path is not None:
        fig.savefig(path, dpi=120)
    return fig
