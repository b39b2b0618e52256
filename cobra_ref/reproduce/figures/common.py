"""Shared helpers of the paper-figure scripts: style, gait order and colours, saving, ``main``.

No physics here. Every figure module has ``make(results, out_dir, model, ensemble=None) ->
list[str]`` and ends with ``common.main(make)``, so that ``python -m cobra_ref.reproduce.figures.fig07_power
--out figures`` runs the quick simulations through ``reproduce.run_all`` (cached) and writes that
one figure. ``results`` = {gait: Trajectory} (the nominal runs); ``ensemble`` = {gait: [summary dict
per member]}, each ``analysis.summary`` of one member's trajectory, member 0 (the nominal run)
first: figs. 6 and 9 draw its spread (``draw_spread``), the others draw the nominal runs only.

Figures that compare gaits put them on one y scale that holds every peak (``common_ylim``), and
notes go above the axes, outside the data (``note_above``). Each gait has its own colour and line
style (``gait_line``): J-mirror's line lies exactly on J's, so it is dashed and drawn on top.

Sizes follow the paper: one column is ``ONE_COLUMN`` = 3.5 in wide, two columns ``TWO_COLUMN`` =
7 in; fonts are 7-8 pt so the figures stay readable at that size (``STYLE``).
"""

from __future__ import annotations

import argparse
import contextlib
import contextvars
import functools
import os
import sys

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402  (after the backend is chosen)
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.figure import Figure  # noqa: E402
from matplotlib.lines import Line2D  # noqa: E402

from ...infra.output import atomic_write  # noqa: E402

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
# the line that marks every figure saved inside ``smoke_run`` (None: a full run)
_SMOKE = contextvars.ContextVar("smoke_note", default=None)


@contextlib.contextmanager
def smoke_run(note: str | None):
    """Within this context, ``save`` marks every figure with ``note`` (its first title line, in red)
    and writes the PNG only: the figures of ``cobra-ref figures --quick``. ``note`` None: no change."""
    token = _SMOKE.set(note)
    try:
        yield
    finally:
        _SMOKE.reset(token)


def paper_style(make):
    """Decorator: run a figure's ``make`` under the paper's rcParams (``STYLE``), leaving the
    caller's matplotlib settings untouched.
    """
    @functools.wraps(make)
    def styled(*args, **kwargs):
        with plt.rc_context(STYLE):
            return make(*args, **kwargs)

    return styled


def new_figure(width: float, height: float) -> Figure:
    """A Figure with its own Agg canvas (no pyplot state, so nothing to close afterwards).
    """
    fig = Figure(figsize=(width, height), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save(fig: Figure, out_dir: str, stem: str) -> list[str]:
    """Write ``stem.png`` (``DPI``) and ``stem.pdf`` into ``out_dir``; return both paths.

    Each file is written to a temporary file in ``out_dir`` and renamed with ``os.replace``, so a
    reader never sees a half-written figure. The PDF carries no creation date, so re-running on the
    same data gives the same bytes. Inside ``smoke_run``: the smoke note above the title, the PNG only.
    """
    os.makedirs(out_dir, exist_ok=True)
    paths, note = [], _SMOKE.get()
    formats = (("png", {"dpi": DPI}), ("pdf", {"metadata": {"CreationDate": None}}))
    if note:
        title = fig._suptitle.get_text() if fig._suptitle is not None else ""
        fig.suptitle(note + ("\n" + title if title else ""), color="tab:red")
        formats = formats[:1]
    for fmt, extra in formats:
        path = os.path.join(out_dir, f"{stem}.{fmt}")
        atomic_write(path, lambda f, fmt=fmt, extra=extra: fig.savefig(f, format=fmt, **extra))
        paths.append(path)
    return paths


def ordered(results: dict) -> list[tuple[str, object]]:
    """The (gait, trajectory) pairs of ``results``: paper order first, then any other gait.

    Gait order of the figures; a gait missing from ``results`` is simply left out.
    """
    known = [g for g in GAIT_ORDER if g in results]
    return [(g, results[g]) for g in known + sorted(set(results) - set(known))]


def gait_color(gait: str) -> str:
    """The gait's colour (``GAIT_COLORS``; grey for a gait the paper does not have).

    One colour per gait in every figure.
    """
    return GAIT_COLORS.get(gait, "tab:gray")


# a line style per gait besides its colour, so that lines that coincide stay apart (and the
# figures read in grey). J-mirror is J reflected (y -> -y): every scalar of it (work, distance)
# equals J's, so its line lies exactly on J's; dashed and drawn on top, both stay visible
GAIT_LINESTYLES = {"C": (0, (7.0, 2.0)), "S": (0, (4.0, 1.5, 1.0, 1.5)), "J": "-", "J-mirror": (0, (3.0, 2.0)),
                   "sidewinding": (0, (4.0, 1.0, 1.0, 1.0, 1.0, 1.0))}
MIRROR_NOTE = "J-mirror (dashed) coincides with J by symmetry"


def gait_line(gait: str) -> dict:
    """Keyword arguments of a gait's line: its colour (``gait_color``) and line style
    (``GAIT_LINESTYLES``; solid for a gait the paper does not have), the solid lines below the others.

    Every line that compares gaits, so that no gait hides another.
    """
    ls = GAIT_LINESTYLES.get(gait, "-")
    return {"color": gait_color(gait), "ls": ls, "zorder": 2.5 if ls != "-" else 2.0}


GAIT_MARKERS = {"J-mirror": "x"}  # markers of scattered points where J-mirror's coincide with J's


def gait_marker(gait: str) -> str:
    """The marker of a gait's scattered points (``GAIT_MARKERS``; a dot otherwise)."""
    return GAIT_MARKERS.get(gait, ".")


def mirror_note(gaits) -> str:
    """``MIRROR_NOTE`` when both J and J-mirror are among ``gaits``, else "".

    The caption's word on the two lines that coincide.
    """
    return MIRROR_NOTE if {"J", "J-mirror"} <= set(gaits) else ""


def gait_label(gait: str, traj) -> str:
    """The gait's name, marked "(partial)" when its simulation stopped early.
    """
    error = getattr(traj, "error", "") or traj.meta.get("error", "")
    return f"{gait} (partial)" if error else gait


def step_times(traj) -> np.ndarray:
    """(N,) start time of each step, the time axis of per-step quantities (tau, power, forces).
    """
    return np.asarray(traj.t[: len(traj.tau)])


def minmax_decimate(t: np.ndarray, y: np.ndarray, max_points: int = 4000) -> tuple[np.ndarray, np.ndarray]:
    """Thin a long time series for plotting while keeping its envelope.

    Splits the (n,) samples ``y`` into bins and keeps each bin's minimum and maximum (in time
    order), so peaks survive and a 10 s run at dt = 1 ms does not bloat the PDF; series shorter than
    ``max_points`` are returned unchanged.
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

    A rigid contact solver redistributes the force among redundant contacts from one 1 ms step to
    the next; the mean force over a window (its impulse / window) is the physically meaningful,
    readable quantity. Samples of a final, shorter window are averaged on their own.
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


def common_ylim(axes, values, bottom: float | None = None) -> None:
    """Give ``axes`` one y range that contains every plotted value (``values``: one array per
    axes), 5 % beyond the largest |value|; ``bottom``: a fixed lower end (0 for magnitudes).

    Force / power / torque panels that compare gaits on one scale: a gait with larger values looks
    larger, and every peak a claim is about is inside the axes. Call it after everything is
    plotted.
    """
    if not axes:
        return
    peaks = [float(np.abs(v).max()) for v in values if np.size(v) and np.isfinite(v).any()]
    limit = 1.05 * max(peaks) if peaks and max(peaks) > 0 else np.inf
    # the union of the autoscaled ranges (already one range when the axes share y), then bounded
    lo = min(ax.get_ylim()[0] for ax in axes) if bottom is None else bottom
    hi = max(ax.get_ylim()[1] for ax in axes)
    for ax in axes:
        ax.set_ylim(max(lo, -limit), min(hi, limit))


def note_above(ax, text: str) -> None:
    """Write ``text`` small and grey above the axes' top right corner (the right-hand title slot),
    outside the data area; the layout makes room for it.

    Peak annotations and captions of a panel. Column titles then go on the left (``loc="left"``).
    """
    ax.set_title(text, loc="right", fontsize=5.5, color="0.35", pad=2)


ENSEMBLE_RANGE = (0.1, 0.9)  # the quantiles of an ensemble's members drawn as its range bar
MEMBERS_GID, RANGE_GID = "ensemble-members", "ensemble-range"  # artist ids: "<gid>:<gait>"


def ensemble_values(ensemble: dict | None, gait: str, key: str) -> np.ndarray:
    """(n,) ``key`` of each member's summary in ``ensemble[gait]`` (member 0, the nominal run,
    first); empty without an ensemble or without that gait.

    ``ensemble`` = {gait: [summary dict per member]}, each ``analysis.summary`` of one member's
    trajectory (figs. 6 and 9).
    """
    members = (ensemble or {}).get(gait, [])
    return np.array([float(m.get(key, np.nan)) for m in members], dtype=float)


def draw_spread(ax, x: float, values: np.ndarray, color: str, gait: str, width: float = 0.24) -> int:
    """Draw an ensemble's values at x: one small dot per member, spread evenly over x +- width / 2
    in member order, and a black bar from the 10th to the 90th percentile (``ENSEMBLE_RANGE``) at
    x; return how many members were not drawn (a non-finite value, e.g. an infinite slope).

    The spread of figs. 6 and 9. The dots' Line2D has gid "ensemble-members:<gait>", the bar's
    "ensemble-range:<gait>".
    """
    v = np.asarray(values, dtype=float)
    finite = v[np.isfinite(v)]
    if len(finite):
        xs = x + width * (np.linspace(-0.5, 0.5, len(finite)) if len(finite) > 1 else np.zeros(1))
        ax.plot(xs, finite, "o", ls="none", ms=2.2, mfc=color, mec="k", mew=0.3, zorder=3,
                gid=f"{MEMBERS_GID}:{gait}")
        lo, hi = np.quantile(finite, ENSEMBLE_RANGE)
        ax.plot([x, x], [lo, hi], color="k", lw=0.9, marker="_", ms=5, mew=0.9, zorder=4,
                gid=f"{RANGE_GID}:{gait}")
    return len(v) - len(finite)


def ensemble_window(ensemble: dict | None) -> float | None:
    """The seconds each member's summary covers (its ``duration``; the claims' window), or None.

    Figs. 6 and 9 say that the members' dots are over this window.
    """
    durations = [m.get("duration") for members in (ensemble or {}).values() for m in members if m.get("duration")]
    return max(durations) if durations else None


def spread_handles(n_members: int, window: float | None = None) -> list:
    """Legend entries of ``draw_spread``: the members' dots (over their first ``window`` seconds,
    when given) and the 10-90 % bar.
    """
    lo, hi = (round(100 * q) for q in ENSEMBLE_RANGE)
    over = "" if window is None else f", first {window:g} s"
    return [Line2D([], [], marker="o", ls="none", ms=2.2, mfc="0.6", mec="k", mew=0.3,
                   label=f"ensemble members (N = {n_members}{over})"),
            Line2D([], [], color="k", lw=0.9, marker="_", ms=5, label=f"{lo}-{hi} % of the members")]


def empty_panel(ax, text: str = NO_CONTACT) -> None:
    """Write ``text`` in the middle of an axes that has nothing to show.

    Robust figures ("no contact" panels, missing gaits).
    """
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", color="0.4",
            fontsize=8, style="italic")


def box_body(model) -> int | None:
    """Index of the box body, or None for a model without a box.
    """
    return model.boxes[0].body if getattr(model, "boxes", ()) else None


def robot_bodies(model) -> list[tuple[str, int]]:
    """(name, body index) of the robot's bodies from the head to the tail (head, L1..L10, tail).

    Fig. 4's rows; the links keep the paper's names L1..L10 (numbered from the head).
    """
    box = box_body(model)
    return [(n, i) for i, n in enumerate(model.body_names) if i != box]


def main(make, argv=None) -> list[str]:
    """Command-line entry of one figure script: run the quick simulations (cached) and ``make``.

    ``python -m cobra_ref.reproduce.figures.<module> [--out figures] [--cache .cobra_cache] [--duration 1.0]
    [--gaits C S ...]``; prints the paths written.
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
    runs = run_all([RunSpec(g, duration=args.duration) for g in args.gaits], args.cache)
    results = {spec.gait: traj for spec, traj in runs.items()}
    paths = make(results, args.out, cobra_model())
    for p in paths:
        print(p)
    return paths
