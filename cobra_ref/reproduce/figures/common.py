"""Shared helpers of the paper-figure scripts: style, gait order and colours, saving, ``main``.

Helper: no physics here. Every figure module has
``make(results, out_dir, model) -> list[str]`` and ends with ``common.main(make)``, so that
``python -m cobra_ref.figures.fig07_power --out figures`` runs the quick simulations through
``reproduce.run_all`` (cached) and writes that one figure.

Sizes follow the paper: one column is ``ONE_COLUMN`` = 3.5 in wide, two columns ``TWO_COLUMN`` =
7 in; fonts are 7-8 pt so the figures stay readable at that size (``STYLE``).
"""

from __future__ import annotations

import argparse
import functools
import os
import sys

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402

from ...output import atomic_write  # noqa: E402

ONE_COLUMN, TWO_COLUMN = 3.5, 7.0  # figure widths [in]
DPI = 150
GAIT_ORDER = ("C", "S", "J", "J-mirror", "sidewinding")
GAIT_COLORS = {"C": "tab:blue", "S": "tab:orange", "J": "tab:green", "J-mirror": "tab:olive",
               "sidewinding": "tab:red"}
STYLE = {
    "font.size": 7.5, "axes.titlesize": 8, "axes.labelsize": 7.5, "legend.fontsize": 6.5,
    "xtick.labelsize": 6.5, "ytick.labelsize": 6.5, "lines.linewidth": 0.9, "axes.grid": True,
    "grid.alpha": 0.3, "grid.linewidth": 0.5, "legend.frameon": False, "figure.dpi": 100,
    "savefig.dpi": DPI, "pdf.fonttype": 42,
}
NO_CONTACT = "no contact"


def paper_style(make):
    """Decorator: run a figure's ``make`` under the paper's rcParams (``STYLE``), leaving the
    caller's matplotlib settings untouched.

    Helper: shared figure style.
    """
    @functools.wraps(make)
    def styled(*args, **kwargs):
        with plt.rc_context(STYLE):
            return make(*args, **kwargs)

    return styled


def new_figure(width: float, height: float) -> Figure:
    """A Figure with its own Agg canvas (no pyplot state, so nothing to close afterwards).

    Helper: figure creation.
    """
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, out_dir: str, stem: str) -> list[str]:
    """Write ``stem.png`` (``DPI``) and ``stem.pdf`` into ``out_dir``; return both paths.

    Helper: each file is written to a temporary file in ``out_dir`` and renamed with
    ``os.replace``, so a reader never sees a half-written figure. The PDF carries no creation
    date, so re-running on the same data gives the same bytes.
    """
    os.makedirs(out_dir, exist_ok=True)
    paths = []
    for fmt, extra in (("png", {"dpi": DPI}), ("pdf", {"metadata": {"CreationDate": None}})):
        path = os.path.join(out_dir, f"{stem}.{fmt}")
        atomic_write(path, lambda f, fmt=fmt, extra=extra: fig.savefig(f, format=fmt, **extra))
        paths.append(path)
    return paths


def ordered(results: dict) -> list[tuple[str, object]]:
    """The (gait, trajectory) pairs of ``results``: paper order first, then any other gait.

    Helper: gait order of the figures; a gait missing from ``results`` is simply left out.
    """
    known = [g for g in GAIT_ORDER if g in results]
    return [(g, results[g]) for g in known + sorted(set(results) - set(known))]


def gait_color(gait: str) -> str:
    """The gait's colour (``GAIT_COLORS``; grey for a gait the paper does not have).

    Helper: one colour per gait in every figure.
    """
    return GAIT_COLORS.get(gait, "tab:gray")


def gait_label(gait: str, traj) -> str:
    """The gait's name, marked "(partial)" when its simulation stopped early.

    Helper: panel titles and legends.
    """
    error = getattr(traj, "error", "") or traj.meta.get("error", "")
    return f"{gait} (partial)" if error else gait


def step_times(traj) -> np.ndarray:
    """(N,) start time of each step, the time axis of per-step quantities (tau, power, forces).

    Helper: t_k for k = 0..N-1.
    """
    return np.asarray(traj.t[: len(traj.tau)])


def minmax_decimate(t: np.ndarray, y: np.ndarray, max_points: int = 4000) -> tuple[np.ndarray, np.ndarray]:
    """Thin a long time series for plotting while keeping its envelope.

    Helper: splits the (n,) samples ``y`` into bins and keeps each bin's minimum and maximum (in
    time order), so peaks survive and a 10 s run at dt = 1 ms does not bloat the PDF; series
    shorter than ``max_points`` are returned unchanged.
    """
    n = len(t)
    if n <= max_points:
        return t, y
    edges = np.linspace(0, n, max_points // 2 + 1).astype(int)
    keep = []
    for a, b in zip(edges[:-1], edges[1:]):
        i, j = a + int(np.argmin(y[a:b])), a + int(np.argmax(y[a:b]))
        keep.extend(sorted({i, j}))
    keep = np.array(keep)
    return t[keep], y[keep]


FORCE_WINDOW = 0.02  # [s] contact forces are drawn as means over windows of this length


def window_mean(t: np.ndarray, y: np.ndarray, window: float = FORCE_WINDOW) -> tuple[np.ndarray, np.ndarray]:
    """Means of ``y`` over consecutive windows of ``window`` seconds, at the windows' centres.

    Helper: a rigid contact solver redistributes the force among redundant contacts from one
    1 ms step to the next; the mean force over a window (its impulse / window) is the physically
    meaningful, readable quantity. Samples of a final, shorter window are averaged on their own.
    """
    if len(t) < 2:
        return t, y
    per = max(1, int(round(window / (t[1] - t[0]))))
    n = len(t)
    starts = np.arange(0, n, per)
    sums = np.add.reduceat(y, starts, axis=0)
    counts = np.diff(np.append(starts, n))
    centres = np.add.reduceat(t, starts) / counts
    return centres, sums / (counts if y.ndim == 1 else counts[:, None])


def robust_ylim(ax, values: np.ndarray, unit: str = "N", quantile: float = 0.99) -> None:
    """Cap the y axis at 1.2 x the ``quantile`` of |values| when a few spikes (e.g. the landing
    impact in the first steps) would otherwise flatten everything else; the clipped maximum is
    written in the panel's corner.

    Helper: readable force / power / torque panels without hiding that the peaks exist.
    """
    v = np.abs(np.asarray(values, dtype=float)).ravel()
    v = v[np.isfinite(v) & (v > 0)]
    if len(v) == 0:
        return
    cap, peak = 1.2 * float(np.quantile(v, quantile)), float(v.max())
    if peak <= 1.5 * cap:
        return
    lo, hi = ax.get_ylim()
    ax.set_ylim(max(lo, -cap), min(hi, cap))
    ax.text(0.99, 0.97, f"peak {peak:.3g} {unit} (clipped)", transform=ax.transAxes, ha="right",
            va="top", fontsize=5.5, color="0.35")


def empty_panel(ax, text: str = NO_CONTACT) -> None:
    """Write ``text`` in the middle of an axes that has nothing to show.

    Helper: robust figures ("no contact" panels, missing gaits).
    """
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.4",
            fontsize=8, style="italic")


def box_body(model) -> int | None:
    """Index of the box body, or None for a model without a box.

    Helper: ``model.boxes[0].body``.
    """
    return model.boxes[0].body if getattr(model, "boxes", ()) else None


def robot_bodies(model) -> list[tuple[str, int]]:
    """(name, body index) of the robot's bodies from the head to the tail (head, L1..L10, tail).

    Helper: fig. 4's rows; the links keep the paper's names L1..L10 (numbered from the head).
    """
    box = box_body(model)
    return [(n, i) for i, n in enumerate(model.body_names) if i != box]


def main(make, argv=None) -> list[str]:
    """Command-line entry of one figure script: run the quick simulations (cached) and ``make``.

    Helper: ``python -m cobra_ref.figures.<module> [--out figures] [--cache .cobra_cache]
    [--duration 1.0] [--gaits C S ...]``; prints the paths written.
    """
    from ..runs import PAPER_GAITS, RunSpec, run_all
    from ...robots import cobra_model

    doc = (sys.modules[make.__module__].__doc__ or make.__doc__ or "").strip()
    parser = argparse.ArgumentParser(description=doc.splitlines()[0] if doc else None)
    parser.add_argument("--out", default="figures", help="output directory (default: figures)")
    parser.add_argument("--cache", default=".cobra_cache", help="simulation cache (default: .cobra_cache)")
    parser.add_argument("--duration", type=float, default=1.0, help="simulated seconds per gait (default 1)")
    parser.add_argument("--gaits", nargs="+", default=list(PAPER_GAITS), help="gaits to run")
    args = parser.parse_args(argv)
    results = run_all([RunSpec(g, duration=args.duration) for g in args.gaits], args.cache)
    paths = make(results, args.out, cobra_model())
    for p in paths:
        print(p)
    return paths
