"""``cobra-ref figures``: every result of [COBRA] (figs. 3-9, GIFs, the claims report) in one command.

Helper: the orchestration; the physics is in ``reproduce`` (simulations), ``analysis`` (numbers),
``figures`` (plots), ``claims`` (verdicts) and ``mujoco_rollout`` (the cross-check).

Steps:

0. with ``reoptimize_all``, re-run the single-shooting optimizer for every gait and for the
   direction goals (``DIRECTIONS``) into ``OUT/optimized/``;
1. simulate the five gaits (C, S, J, J-mirror, sidewinding; 10 s each, 1 s with ``quick``) on
   both cores, or read them from the cache (``reproduce``: keyed by a hash of every input). A gait
   with a params JSON in the optimized directory (``cobra_ref/optimized/<gait>.json`` by
   default, committed) runs with its optimized parameters, the others with their defaults;
2. write each figure; a figure whose inputs (the simulations' cache keys and the figure
   module's source) are unchanged since it was last written is kept (``.stamps.json`` in the
   output directory), unless ``force``;
   ``fig_optimization`` and ``fig_directions`` come from the params JSONs (each optimum
   replayed once, its box path cached);
3. write ``claims.json`` (a list of {id, claim, values, holds}) and ``claims.md``, and
   ``summary.json`` with every gait's numbers.

Every file is written atomically (temporary file + rename): an interrupted run leaves the
previous outputs or none, never half a file.
"""

from __future__ import annotations

import hashlib
import importlib
import json
import os
import sys
import time

import numpy as np

from ..output import atomic_write, write_text
from .runs import PAPER_GAITS, RunSpec, run_all

FULL_DURATION, QUICK_DURATION = 10.0, 1.0


def check_output_dir(out_dir: str) -> None:
    """Create ``out_dir`` if needed; raise OSError naming it if it cannot be written.

    Helper: checked before any simulation starts, so a bad directory costs nothing.
    """
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise OSError(f"cannot create output directory {out_dir}: {exc.strerror}") from exc
    if not os.access(out_dir, os.W_OK):
        raise OSError(f"output directory is not writable: {out_dir}")


def specs_for(gaits=PAPER_GAITS, quick: bool = False, dt: float = 1e-3, params: dict | None = None) -> list[RunSpec]:
    """The run of each gait: 10 s (1 s with ``quick``) at dt, with ``params[gait]`` if given.

    Helper: the figure command's simulations.
    """
    duration = QUICK_DURATION if quick else FULL_DURATION
    params = params or {}
    return [RunSpec(g, duration=duration, dt=dt, params=dict(params.get(g, {}))) for g in gaits]


OPTIMIZED_DIR = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "optimized")  # cobra_ref/optimized
# the direction-control optimizations: goal (dx, dy) relative to the box's start, and the gait
DIRECTIONS = {"ahead": ("J", (0.3, 0.0)), "left": ("J-mirror", (0.25, 0.15)), "right": ("C", (0.2, -0.15))}


def optimized_files(directory: str = OPTIMIZED_DIR, gaits=PAPER_GAITS) -> dict:
    """{gait: path} of the params JSONs of ``cobra-ref optimize`` present in ``directory``.

    Helper: the figure command simulates each gait with its optimized parameters when a file
    exists (``cobra_ref/optimized/<gait>.json``, committed), with the defaults otherwise.
    """
    paths = {g: os.path.join(directory, f"{g}.json") for g in gaits}
    return {g: p for g, p in paths.items() if os.path.isfile(p)}


def optimized_params(files: dict) -> dict:
    """{gait: gait parameters} from the params JSONs ``files`` ({gait: path}).

    Helper: the ``params`` of each optimum (phase-rate ramp included), for ``specs_for``.
    """
    from ..planning.results import load_result

    return {g: dict(load_result(p)["params"]) for g, p in files.items()}


def reoptimize(directory: str, gaits=PAPER_GAITS, progress: bool = True) -> dict:
    """Run the optimizer for every gait at its defaults (``planning.problem.DEFAULTS``) and for the
    direction goals (``DIRECTIONS``), each optimum checked at dt = 0.5 ms (``planning.results.transfer``),
    writing the params JSONs into ``directory``; return {name: path}.

    Helper: ``cobra-ref figures --reoptimize``.
    """
    from ..planning.search import optimize_gait

    os.makedirs(directory, exist_ok=True)
    say = (lambda line: _say(True, "    " + line)) if progress else (lambda line: None)
    files = {}
    for g in gaits:
        _say(progress, f"  optimizing {g}")
        files[g] = os.path.join(directory, f"{g}.json")
        optimize_gait(g, out=files[g], progress=say)
    for name, (g, goal) in DIRECTIONS.items():
        _say(progress, f"  optimizing direction '{name}' with {g}, goal {goal}")
        files[f"direction-{name}"] = os.path.join(directory, f"direction-{name}.json")
        optimize_gait(g, goal=goal, out=files[f"direction-{name}"], progress=say)
    return files


def regenerate(out_dir: str = "figures", quick: bool = False, force: bool = False, cache_dir: str | None = None,
               workers: int | None = None, mujoco: bool = True, progress: bool = True, gaits=PAPER_GAITS,
               params: dict | None = None, optimized_dir: str | None = OPTIMIZED_DIR,
               reoptimize_all: bool = False) -> dict:
    """Run steps 1-3 of the module docstring; return {"files": [...], "claims": [...], "seconds": ...}.

    Helper: the body of ``cobra-ref figures``.
    """
    from . import claims as claims_mod
    from .figures import FIGURES
    from ..robots import cobra_model

    start = time.perf_counter()
    check_output_dir(out_dir)
    cache_dir = cache_dir or os.path.join(out_dir, ".cache")
    if reoptimize_all:
        optimized_dir = os.path.join(out_dir, "optimized")
        reoptimize(optimized_dir, gaits, progress)
    files_opt = optimized_files(optimized_dir, gaits) if optimized_dir else {}
    if params is None:
        params = optimized_params(files_opt)
        if params:
            _say(progress, f"optimized parameters for {', '.join(params)} (from {optimized_dir}); "
                           f"defaults (assumption A10) for any other gait")
        else:
            _say(progress, "default gait parameters (assumption A10) for every gait")
    specs = specs_for(gaits, quick, params=params)
    _say(progress, f"simulating {len(specs)} gaits x {specs[0].duration:g} s (cache: {cache_dir})")
    results = run_all(specs, cache_dir, force=force, workers=workers, progress=progress)
    model = cobra_model(with_box=True)
    keys = {s.gait: s.key() for s in specs}
    stamps_path = os.path.join(out_dir, ".stamps.json")
    stamps = _read_json(stamps_path) if not force else {}
    files = []
    for name in FIGURES:
        module = importlib.import_module(f".figures.{name}", __package__)
        stamp = _stamp(keys, module)
        old = stamps.get(name, {})
        if old.get("stamp") == stamp and old.get("files") and all(os.path.isfile(f) for f in old["files"]):
            files += old["files"]
            _say(progress, f"  {name}: unchanged, kept")
            continue
        t0 = time.perf_counter()
        written = module.make(results, out_dir, model)
        stamps[name] = {"stamp": stamp, "files": written}
        write_text(stamps_path, json.dumps(stamps, indent=1))
        files += written
        _say(progress, f"  {name}: {len(written)} file(s), {time.perf_counter() - t0:.1f} s")
    if optimized_dir and os.path.isdir(optimized_dir):
        files += _optimization_figures(optimized_dir, gaits, out_dir, cache_dir, progress)
    summaries = claims_mod.gait_summaries(results)
    report = claims_mod.paper_claims(summaries)
    settings = {"duration (s)": specs[0].duration, "dt (s)": specs[0].dt, "quick": quick,
                "optimized parameters from": {g: _shown(files_opt[g]) if g in files_opt else "defaults (assumption A10)"
                                              for g in gaits}
                if params else "defaults (assumption A10)",
                "gait parameters": {g: r.meta.get("gait_params") for g, r in results.items()},
                "box direction (sidewinding)": results["sidewinding"].meta.get("box_direction")
                if "sidewinding" in results else None}
    if mujoco:
        report += _mujoco_rows(results, out_dir, progress, files)
    paths = {"claims.json": json.dumps(_clean(report), indent=1),
             "claims.md": claims_mod.to_markdown(report, summaries, settings),
             "summary.json": json.dumps(_clean({"gaits": summaries, "settings": settings}), indent=1)}
    for fname, text in paths.items():
        write_text(os.path.join(out_dir, fname), text)
        files.append(os.path.join(out_dir, fname))
    return {"files": files, "claims": report, "seconds": time.perf_counter() - start}


def _mujoco_rows(results, out_dir, progress, files) -> list[dict]:
    """The MuJoCo comparison as claims, and its figure; empty, with a note on stderr, when mujoco
    is not installed (it is an optional extra).

    Helper: (a) the robot alone, each gait, ``mujoco_check.TRAVEL_DURATION`` seconds in both
    simulators; (b) the box displacement after ``BOX_DURATION`` seconds from each figure run's own
    start (one member per gait until the figure runs become ensembles), ours read off the run.
    """
    from .mujoco_check import box_ensemble_rows, claims, mujoco_available, robot_travel_rows

    if not mujoco_available():
        _say(progress, "  MuJoCo comparison skipped: mujoco is not installed (pip install mujoco)")
        return []
    done = {g: r for g, r in results.items() if not r.error}
    if not done:
        return []
    from ..gaits import gait

    t0 = time.perf_counter()
    params = {g: r.meta.get("gait_params", {}) for g, r in done.items()}
    rows = robot_travel_rows(list(done), params=params)
    members = {}
    for g, r in done.items():
        n = min(int(round(BOX_DURATION / r.dt)), len(r.box_pose) - 1)
        members[g] = [{"reference": gait(g, **params[g]), "q0": r.q[0], "qd0": r.qd[0], "mu_scale": 1.0,
                       "ours": r.box_pose[n, :2] - r.box_pose[0, :2]}]
    duration = min(BOX_DURATION, min(r.duration for r in done.values()))
    rows += box_ensemble_rows(members, duration)
    from .figures.fig_mujoco_check import make as make_figure

    files += make_figure(rows, out_dir)
    _say(progress, f"  MuJoCo comparison: {len(done)} gaits, {time.perf_counter() - t0:.1f} s")
    return claims(rows)


BOX_DURATION = 3.0  # [s] the box comparison with MuJoCo (0.1 ms steps there: 30 000 per member)


def _optimization_figures(directory: str, gaits, out_dir: str, cache_dir: str, progress: bool) -> list[str]:
    """``fig_optimization`` (one optimum per gait) and ``fig_directions`` (``DIRECTIONS``) from the
    params JSONs in ``directory``; each optimum is replayed once and its box path cached."""
    from .figures.fig_optimization import make
    from ..planning.results import load_result

    def runs(names):
        out = []
        for label, gait, path in names:
            if os.path.isfile(path):
                out.append({"label": label, "gait": gait, "record": load_result(path),
                            "box_xy": _replayed_box_path(path, cache_dir)})
        return out

    t0 = time.perf_counter()
    # replay the optima not yet cached, in parallel (each is an independent simulation)
    paths = [os.path.join(directory, f"{g}.json") for g in gaits]
    paths += [os.path.join(directory, f"direction-{name}.json") for name in DIRECTIONS]
    paths = [p for p in paths if os.path.isfile(p)]
    if len(paths) > 1:
        from concurrent.futures import ProcessPoolExecutor

        from ..executors import worker_init

        with ProcessPoolExecutor(min(len(paths), os.cpu_count() or 1), initializer=worker_init) as pool:
            list(pool.map(_replayed_box_path, paths, [cache_dir] * len(paths)))
    per_gait = runs([(g, g, os.path.join(directory, f"{g}.json")) for g in gaits])
    directions = runs([(f"{name}: {g}", g, os.path.join(directory, f"direction-{name}.json"))
                       for name, (g, _) in DIRECTIONS.items()])
    files = []
    if per_gait:
        files += make(per_gait, out_dir, "fig_optimization", "Single shooting per gait (cobra-ref optimize)")
    if directions:
        files += make(directions, out_dir, "fig_directions", "Direction control: choose the gait for the goal")
    _say(progress, f"  optimization figures: {len(per_gait)} gaits, {len(directions)} directions, "
                   f"{time.perf_counter() - t0:.1f} s")
    return files


def _replayed_box_path(path: str, cache_dir: str) -> np.ndarray:
    """(n, 2) box path of the optimum of the params JSON ``path``, replayed once and cached under a
    hash of the JSON and the physics source."""
    from .runs import physics_hash
    from ..planning.results import replay

    with open(path, "rb") as f:
        key = hashlib.sha256(f.read() + physics_hash(("planning",)).encode()).hexdigest()[:16]
    cached = os.path.join(cache_dir, f"optimum-{key}.npy")
    if os.path.isfile(cached):
        return np.load(cached)
    traj, _ = replay(path)
    xy = traj.box_pose[:, :2].copy()
    os.makedirs(cache_dir, exist_ok=True)
    atomic_write(cached, lambda tmp: np.save(tmp, xy))
    return xy


def _shown(path: str) -> str:
    """A params file as the report shows it: ``cobra_ref/optimized/<name>`` for the committed ones."""
    if os.path.dirname(os.path.abspath(path)) == OPTIMIZED_DIR:
        return "cobra_ref/optimized/" + os.path.basename(path)
    return path


def _stamp(keys: dict, module) -> str:
    """Hash of the simulations' cache keys, the figure module's name and the source of the whole
    figures package (figures share drawing code: the GIFs reuse fig. 3's)."""
    here = os.path.join(os.path.dirname(os.path.abspath(__file__)), "figures")
    h = hashlib.sha256((json.dumps(keys, sort_keys=True) + module.__name__).encode())
    for name in sorted(os.listdir(here)):
        if name.endswith(".py"):
            with open(os.path.join(here, name), "rb") as f:
                h.update(f.read())
    return h.hexdigest()


def _read_json(path: str) -> dict:
    try:
        with open(path) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {}


def _clean(x):
    """Plain JSON: numpy values to Python ones, inf and nan to null (strict JSON has neither)."""
    if isinstance(x, dict):
        return {str(k): _clean(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_clean(v) for v in x]
    if hasattr(x, "tolist"):
        return _clean(x.tolist())
    if isinstance(x, float) and not (x == x and abs(x) != float("inf")):
        return None
    return x


def _say(progress: bool, text: str) -> None:
    if progress:
        sys.stderr.write(text + "\n")
        sys.stderr.flush()
