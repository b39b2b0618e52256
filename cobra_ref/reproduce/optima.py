"""The optima of the figure command: the committed params JSONs, their re-optimization, their replays
and the optimization figures.

``cobra-ref figures`` simulates each gait with its optimized parameters when a params JSON
exists in the optimized directory (``OPTIMIZED_DIR`` = ``cobra_ref/optimized/``, committed), with
the defaults otherwise; ``--reoptimize`` writes them anew (``reoptimize``). ``fig_optimization``
(one optimum per gait) and ``fig_directions`` (the direction goals, ``DIRECTIONS``) show each
optimum's box path, the one its optimization recorded, or, for a JSON without one, a replay
computed once and cached under a hash of the JSON and the physics source; the direction optima's
final box displacements against their goals (``direction_outcomes``) are what claim GT judges.
"""

from __future__ import annotations

import hashlib
import json
import os
import time

import numpy as np

from ..infra.executors import SerialExecutor, own_pool
from ..provenance import PLANNING_MODULES, physics_hash
from .cache import read_path, verified, write_path
from .runs import PAPER_GAITS
from .stamps import say

OPTIMIZED_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "optimized")  # cobra_ref/optimized
# the direction-control optimizations: goal (dx, dy) relative to the box's start, and the gait
DIRECTIONS = {"ahead": ("J", (0.3, 0.0)), "left": ("J-mirror", (0.25, 0.15)), "right": ("C", (0.2, -0.15))}


def optimized_files(directory: str = OPTIMIZED_DIR, gaits=PAPER_GAITS) -> dict:
    """{gait: path} of the params JSONs of ``cobra-ref optimize`` present in ``directory``: the
    gaits the figure command simulates with their optimized parameters."""
    paths = {g: os.path.join(directory, f"{g}.json") for g in gaits}
    return {g: p for g, p in paths.items() if os.path.isfile(p)}


def optimized_params(files: dict) -> dict:
    """{gait: gait parameters} from the params JSONs ``files`` ({gait: path}): the ``params`` of
    each optimum (phase-rate ramp included), for ``regenerate.specs_for``."""
    from ..planning.results import load_result

    return {g: dict(load_result(p)["params"]) for g, p in files.items()}


def reoptimize(directory: str, gaits=PAPER_GAITS, progress: bool = True) -> dict:
    """Run the optimizer for every gait at its defaults (``planning.problem.DEFAULTS``) and for the
    direction goals (``DIRECTIONS``), each optimum checked at dt = 0.5 ms (``planning.results.transfer``),
    writing the params JSONs into ``directory``; return {name: path}.

    ``cobra-ref figures --reoptimize``. The optimizations are independent: they run side by side,
    one per core, each rolling out serially (no core waits for a batch's last rollout or a check),
    sidewinding's (the longest) first; progress lines carry the optimum's name.
    """
    os.makedirs(directory, exist_ok=True)
    jobs = [(g, g, None) for g in gaits] + [(f"direction-{name}", g, goal) for name, (g, goal) in DIRECTIONS.items()]
    jobs.sort(key=lambda job: job[1] != "sidewinding")  # stable: otherwise in the order above
    files = {name: os.path.join(directory, f"{name}.json") for name, _, _ in jobs}
    with own_pool(min(len(jobs), os.cpu_count() or 1)) as pool:
        futures = [pool.submit(_optimize_one, name, g, goal, files[name], progress) for name, g, goal in jobs]
        for f in futures:
            f.result()  # re-raises an optimization's exception here
    return files


def _optimize_one(name: str, g: str, goal, out: str, progress: bool) -> None:
    """One optimization of ``reoptimize`` (in a worker), its rollouts in this process."""
    from ..planning.search import optimize_gait

    lines = (lambda line: say(True, f"    {name}: {line}")) if progress else (lambda line: None)
    say(progress, f"  optimizing {name} with {g}" + ("" if goal is None else f", goal {goal}"))
    optimize_gait(g, goal=goal, out=out, executor=SerialExecutor(), progress=lines)


def optimum_paths(directory: str, gaits) -> list[str]:
    """The params JSONs in ``directory`` that the optimization figures show: one per gait, then ``DIRECTIONS``."""
    paths = [os.path.join(directory, f"{g}.json") for g in gaits]
    paths += [os.path.join(directory, f"direction-{name}.json") for name in DIRECTIONS]
    return [p for p in paths if os.path.isfile(p)]


def replays_submit(executor, directory: str, gaits, cache_dir: str) -> list:
    """Futures of the optima's replays (``replayed_box_path``) on ``executor``, for those that did
    not record their box path and are not yet cached."""
    if not os.path.isdir(directory):
        return []
    return [executor.submit(replayed_box_path, p, cache_dir) for p in optimum_paths(directory, gaits)
            if not _records_box_path(p) and _cached_replay(p, cache_dir) is None]


def _records_box_path(path: str) -> bool:
    """Whether the params JSON ``path`` holds its optimum's box path (then no replay is needed)."""
    try:
        with open(path) as f:
            return bool(json.load(f).get("box_path"))
    except (OSError, ValueError, AttributeError):
        return False  # the figure's load_result reports what is wrong with it


def optimization_figures(directory: str, gaits, out_dir: str, cache_dir: str, progress: bool,
                         replays=None) -> list[str]:
    """``fig_optimization`` (one optimum per gait) and ``fig_directions`` (``DIRECTIONS``) from the
    params JSONs in ``directory``, each with the box path its optimization recorded; a JSON
    without one is replayed once and its path cached. ``replays``: futures of replays already
    started (``replays_submit``); an optimum whose replay is not cached is replayed here."""
    from .figures.fig_optimization import make
    from ..planning.results import load_result

    def runs(names):
        out = []
        for label, gait, path in names:
            if os.path.isfile(path):
                record = load_result(path)
                out.append({"label": label, "gait": gait, "record": record, "box_xy": _box_xy(record, path, cache_dir)})
        return out

    t0 = time.perf_counter()
    for f in replays or []:
        f.result()  # re-raises a replay's exception here
    per_gait = runs([(g, g, os.path.join(directory, f"{g}.json")) for g in gaits])
    directions = runs([(f"{name}: {g}", g, os.path.join(directory, f"direction-{name}.json"))
                       for name, (g, _) in DIRECTIONS.items()])
    files = []
    if per_gait:
        files += make(per_gait, out_dir, "fig_optimization", "Single shooting per gait (cobra-ref optimize)")
    if directions:
        files += make(directions, out_dir, "fig_directions", "Direction control: choose the gait for the goal")
    say(progress, f"  optimization figures: {len(per_gait)} gaits, {len(directions)} directions, "
                  f"{time.perf_counter() - t0:.1f} s")
    return files


def _box_xy(record: dict, path: str, cache_dir: str):
    """The box path (n, 2) of the optimum ``record`` read from ``path``: the one its optimization
    recorded, else its cached replay (``replayed_box_path``)."""
    return record["box_path"]["xy"] if record.get("box_path") else replayed_box_path(path, cache_dir)


def direction_outcomes(directory: str, cache_dir: str) -> list[dict]:
    """[{"name", "gait", "goal", "displacement", "source"}] of the direction optima (``DIRECTIONS``)
    in ``directory``: each goal (``settings.goal``) and the box's final displacement from its start
    along the optimum's box path (``_box_xy``), relative to the box's start in world axes [m]; the
    outcomes claim GT is judged on (``claims.ensemble_claims``)."""
    from ..planning.results import load_result

    out = []
    for name, (gait, _) in DIRECTIONS.items():
        path = os.path.join(directory, f"direction-{name}.json")
        if not os.path.isfile(path):
            continue
        record = load_result(path)
        xy = np.asarray(_box_xy(record, path, cache_dir), dtype=float)
        out.append({"name": name, "gait": gait, "goal": [float(x) for x in record["settings"]["goal"][:2]],
                    "displacement": [float(x) for x in xy[-1] - xy[0]], "source": shown(path)})
    return out


def replayed_box_path(path: str, cache_dir: str) -> np.ndarray:
    """(n, 2) box path of the optimum of the params JSON ``path``, replayed once and cached under a
    hash of the JSON and the physics source (the entry checked on read: ``cache.read_path``)."""
    from ..planning.results import replay

    xy = _cached_replay(path, cache_dir)
    if xy is not None:
        return xy
    traj, _ = replay(path)
    xy = traj.box_pose[:, :2].copy()
    key = _replay_key(path)
    os.makedirs(cache_dir, exist_ok=True)
    write_path(_replay_file(key, cache_dir), key, xy)
    return xy


def _cached_replay(path: str, cache_dir: str) -> np.ndarray | None:
    """The cached box path of the optimum ``path`` if the cache holds it whole, else None (a damaged
    entry is named on stderr and removed: ``cache.verified``)."""
    key = _replay_key(path)
    cached = _replay_file(key, cache_dir)
    return verified(cached, lambda p: read_path(p, key)) if os.path.isfile(cached) else None


def _replay_key(path: str) -> str:
    """The key of the optimum ``path``'s replay: SHA-256 of the JSON and the physics source."""
    with open(path, "rb") as f:
        return hashlib.sha256(f.read() + physics_hash(PLANNING_MODULES).encode()).hexdigest()


def _replay_file(key: str, cache_dir: str) -> str:
    """Where ``replayed_box_path`` caches the replay of ``key``."""
    return os.path.join(cache_dir, f"optimum-{key[:16]}.npz")


def shown(path: str) -> str:
    """A params file as the report shows it: ``cobra_ref/optimized/<name>`` for the committed ones."""
    if os.path.dirname(os.path.abspath(path)) == OPTIMIZED_DIR:
        return "cobra_ref/optimized/" + os.path.basename(path)
    return path
