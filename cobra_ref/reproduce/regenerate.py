"""``cobra-ref figures``: every result of [COBRA] (figs. 3-9, GIFs, the claims report) in one command.

Helper: the orchestration; the physics is in ``reproduce`` (simulations), ``analysis`` (numbers),
``figures`` (plots), ``claims`` (verdicts) and ``mujoco_rollout`` (the cross-check).

Steps:

0. with ``reoptimize_all``, re-run the single-shooting optimizer for every gait and for the
   direction goals (``DIRECTIONS``) into ``OUT/optimized/``;
1. simulate the five gaits (C, S, J, J-mirror, sidewinding), each as an ensemble of N members
   (``MEMBERS`` = 8 by default; ``ensemble.members``, assumption A29): member 0 is the figure run
   (10 s, 1 s with ``quick``), members 1 .. N-1 run ``ENSEMBLE_DURATION`` = 6 s (1 s with
   ``quick``), on both cores (or any executor), or read from the cache (``reproduce``: keyed by
   a hash of every input). A gait with a params JSON in the optimized directory
   (``cobra_ref/optimized/<gait>.json`` by default) runs with its optimized parameters, the
   others with their defaults;
2. write each figure from the member-0 runs, figs. 6 and 9 with the members' spread; a figure
   whose inputs (the simulations' cache keys and the figure package's source) are unchanged
   since it was last written is kept (``.stamps.json`` in the output directory), unless ``force``;
   ``fig_optimization`` and ``fig_directions`` come from the params JSONs (each optimum
   replayed once, its box path cached);
3. judge the claims on the ensembles: every member over the same window, its first
   ``ENSEMBLE_DURATION`` seconds (member 0 truncated to it), and write ``claims.json`` (a list
   of claim entries, each with its ``statistics`` over the members, ``check``), ``claims.md``
   and ``summary.json`` with every gait's numbers and every member's; then the MuJoCo
   comparison on the first K = min(N, ``MUJOCO_MEMBERS`` = 4) members of each gait, cached.

Why ENSEMBLE_DURATION = 6 s: the claims judge steady gaits, so the window holds the default
gaits' 2 s phase-rate ramp and two 0.5 Hz periods after it (the steady-power and phase claims
need those two periods; sidewinding meets its box at about 1.5 s and pushes for the rest). A
clean run then simulates 5 x 10 s figure runs and 35 x 6 s members, 260 simulated seconds. Why K = 4: MuJoCo's box rollouts run at 0.1 ms steps
(about 2 wall seconds per simulated second); 4 members per gait keep the comparison under a
minute on two cores and still give a spread (min-max of 4) to compare against.

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
from contextlib import nullcontext

import numpy as np

from ..infra.executors import SerialExecutor, own_pool
from ..infra.output import atomic_write, write_text
from ..provenance import PLANNING_MODULES, physics_hash
from .runs import PAPER_GAITS, RunSpec, run_all

FULL_DURATION, QUICK_DURATION = 10.0, 1.0
MEMBERS = 8  # members per gait (member 0: the figure run)
# [s] the other members' runs and the window every member is judged on: the default gaits' 2 s
# phase-rate ramp and two 0.5 Hz periods after it (the steady-power and phase claims need two
# periods after the ramp; sidewinding meets its box at about 1.5 s); the budget's lever
ENSEMBLE_DURATION = 6.0
MUJOCO_MEMBERS = 4  # members per gait in the MuJoCo box comparison: K = min(N, 4)


def check_output_dir(out_dir: str) -> None:
    """Create ``out_dir`` if needed; raise OSError naming it if it cannot be written.

    Helper: checked before any simulation starts, so a bad directory costs nothing.
    """
    from ..infra.output import check_output

    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise OSError(f"cannot create output directory {out_dir}: {exc.strerror}") from exc
    # a real probe (a temporary file created and removed): os.access answers yes to root everywhere
    check_output(os.path.join(out_dir, "claims.json"), "the figures")


def specs_for(gaits=PAPER_GAITS, quick: bool = False, dt: float = 1e-3, params: dict | None = None) -> list[RunSpec]:
    """The figure run of each gait: 10 s (1 s with ``quick``) at dt, with ``params[gait]`` if given.

    Helper: the figure command's simulations (member 0 of each ensemble).
    """
    duration = QUICK_DURATION if quick else FULL_DURATION
    params = params or {}
    return [RunSpec(g, duration=duration, dt=dt, params=dict(params.get(g, {}))) for g in gaits]


def ensemble_specs(gaits=PAPER_GAITS, n_members: int = MEMBERS, quick: bool = False, dt: float = 1e-3,
                   params: dict | None = None) -> dict:
    """{gait: [RunSpec per member]}: member 0 is the figure run (``specs_for``), members 1 .. n-1
    are ``ensemble.members(gait, n)``, each ``ENSEMBLE_DURATION`` seconds (1 s with ``quick``).

    Helper: the ensembles of the figure command (module docstring, step 1).
    """
    from .ensemble import members

    duration = QUICK_DURATION if quick else ENSEMBLE_DURATION
    params = params or {}
    out = {}
    for nominal in specs_for(gaits, quick, dt, params):
        out[nominal.gait] = [nominal] + [RunSpec(nominal.gait, duration=duration, dt=dt, params=dict(nominal.params),
                                                 member=m) for m in members(nominal.gait, n_members)[1:]]
    return out


def window(quick: bool) -> float:
    """Helper: the seconds over which every member is judged (``ENSEMBLE_DURATION``; 1 s with ``quick``)."""
    return QUICK_DURATION if quick else ENSEMBLE_DURATION


def ensemble_summaries(specs: dict, results: dict, duration: float, goals: dict | None = None) -> dict:
    """{gait: [summary per member]}: ``claims.gait_summaries`` of each member's first ``duration``
    seconds (``Trajectory.truncated``), with the member's perturbation (``member``, None for
    member 0) and, for a gait optimized towards a goal, ``goal_direction`` (unit (x, y), world axes).

    Helper: the numbers behind the ensemble claims and the spreads of figs. 6 and 9.
    """
    from .claims import gait_summaries

    goals = goals or {}
    out = {}
    for g, runs in specs.items():
        out[g] = []
        for spec in runs:
            summary = gait_summaries({g: results[spec].truncated(duration)})[g]
            summary["member"] = None if spec.member is None else spec.member.as_dict()
            if g in goals:
                summary["goal_direction"] = list(goals[g])
            out[g].append(summary)
    return out


def goal_directions(files: dict) -> dict:
    """{gait: unit (x, y)} of the goal of each params JSON in ``files`` ({gait: path}) that has one.

    Helper: ``goal_direction`` of the ensemble summaries (the goal is relative to the box's
    start, world axes: ``settings.goal`` of the params JSON).
    """
    out = {}
    for g, path in files.items():
        try:
            with open(path, encoding="utf-8") as f:
                goal = np.asarray(json.load(f)["settings"]["goal"], dtype=float)[:2]
        except (OSError, ValueError, KeyError, TypeError):
            continue
        if goal.shape == (2,) and np.all(np.isfinite(goal)) and np.linalg.norm(goal) > 0:
            out[g] = [float(x) for x in goal / np.linalg.norm(goal)]
    return out


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

    Helper: ``cobra-ref figures --reoptimize``. The optimizations are independent: they run side
    by side, one per core, each rolling out serially (no core waits for a batch's last rollout or a
    check), sidewinding's (the longest) first; progress lines carry the optimum's name.
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

    say = (lambda line: _say(True, f"    {name}: {line}")) if progress else (lambda line: None)
    _say(progress, f"  optimizing {name} with {g}" + ("" if goal is None else f", goal {goal}"))
    optimize_gait(g, goal=goal, out=out, executor=SerialExecutor(), progress=say)


def regenerate(out_dir: str = "figures", quick: bool = False, force: bool = False, cache_dir: str | None = None,
               workers: int | None = None, mujoco: bool = True, progress: bool = True, gaits=PAPER_GAITS,
               params: dict | None = None, optimized_dir: str | None = OPTIMIZED_DIR,
               reoptimize_all: bool = False, n_members: int = MEMBERS, executor=None) -> dict:
    """Run steps 1-3 of the module docstring; return {"files": [...], "claims": [...], "seconds": ...}.

    Helper: the body of ``cobra-ref figures``. ``n_members`` (N >= 1) members per gait;
    ``executor``: where the runs go (``runs.run_all``; default a process pool on the cores).
    """
    start = time.perf_counter()
    if isinstance(n_members, bool) or not isinstance(n_members, (int, np.integer)) or n_members < 1:
        raise ValueError(f"members per gait must be a whole number >= 1, got {n_members!r}")
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
    specs = ensemble_specs(gaits, n_members, quick, params=params)
    every = [spec for runs in specs.values() for spec in runs]
    T = window(quick)
    _say(progress, f"simulating {len(specs)} gaits x {n_members} member(s): member 0 {every[0].duration:g} s, "
                   f"the others {T:g} s (cache: {cache_dir})")
    runs = run_all(every, cache_dir, force=force, workers=workers, progress=progress, executor=executor)
    # the MuJoCo comparison and the optima's replays run on the executor (default: a process pool)
    # while this process draws the figures
    with nullcontext(executor) if executor is not None else own_pool() as side:
        return _finish(specs, every, runs, T, files_opt, params, out_dir, cache_dir, optimized_dir, gaits, n_members,
                       quick, mujoco, force, progress, side, start)


def _finish(specs, every, runs, T, files_opt, params, out_dir, cache_dir, optimized_dir, gaits, n_members, quick,
            mujoco, force, progress, side, start) -> dict:
    """Steps 2-3 of the module docstring once the runs are done: the MuJoCo rows and the optima's
    replays go to ``side`` first, then the figures and the claims are made here."""
    from . import claims as claims_mod
    from .figures import FIGURES
    from ..robots import cobra_model

    # the replays first: their figure is drawn before the MuJoCo figure
    replays = _replays_submit(side, optimized_dir, gaits, cache_dir) if optimized_dir else []
    pending = _mujoco_submit(side, specs, runs, T, cache_dir, force, progress) if mujoco else None
    results = {g: runs[members[0]] for g, members in specs.items()}
    ensemble = ensemble_summaries(specs, runs, T, goal_directions(files_opt))
    model = cobra_model(with_box=True)
    keys = {spec.label(): spec.key() for spec in every}
    keys["ensemble window (s)"] = T
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
        written = module.make(results, out_dir, model, ensemble=ensemble)
        stamps[name] = {"stamp": stamp, "files": written}
        write_text(stamps_path, json.dumps(stamps, indent=1))
        files += written
        _say(progress, f"  {name}: {len(written)} file(s), {time.perf_counter() - t0:.1f} s")
    if optimized_dir and os.path.isdir(optimized_dir):
        files += _optimization_figures(optimized_dir, gaits, out_dir, cache_dir, progress, replays)
    summaries = claims_mod.gait_summaries(results)
    report = ensemble_report(ensemble)
    settings = {"duration (s)": every[0].duration, "dt (s)": every[0].dt, "quick": quick,
                "ensemble": {"members per gait": n_members, "window (s)": T,
                             "rule": "cobra_ref/reproduce/ensemble.py (assumption A29)"},
                "optimized parameters from": {g: _shown(files_opt[g]) if g in files_opt else "defaults (assumption A10)"
                                              for g in gaits}
                if params else "defaults (assumption A10)",
                "gait parameters": {g: r.meta.get("gait_params") for g, r in results.items()},
                "box direction (sidewinding)": results["sidewinding"].meta.get("box_direction")
                if "sidewinding" in results else None}
    if mujoco:
        report += _mujoco_rows(pending, out_dir, progress, files)
    paths = {"claims.json": json.dumps(_clean(report), indent=1),
             "claims.md": claims_mod.to_markdown(report, summaries, settings),
             "summary.json": json.dumps(_clean({"gaits": summaries, "ensemble": ensemble, "settings": settings}),
                                        indent=1)}
    for fname, text in paths.items():
        write_text(os.path.join(out_dir, fname), text)
        files.append(os.path.join(out_dir, fname))
    return {"files": files, "claims": _clean(report), "seconds": time.perf_counter() - start}


def ensemble_report(ensemble: dict) -> list[dict]:
    """The paper's claims judged on the ensembles, each entry with its ``statistics`` over the
    members (``check.claim_statistics``).

    Helper: ``claims.ensemble_claims`` when the claims module has it; otherwise
    ``claims.paper_claims`` of the member-0 summaries (over the same window).
    """
    from . import claims as claims_mod
    from .check import claim_statistics

    judge = getattr(claims_mod, "ensemble_claims", None)
    report = judge(ensemble) if judge else claims_mod.paper_claims({g: m[0] for g, m in ensemble.items()})
    stats = claim_statistics(ensemble, claims_mod.paper_claims)
    for entry in report:
        if entry["id"] in stats:
            entry["statistics"] = stats[entry["id"]]
    return report


def _mujoco_submit(side, specs, runs, window_s, cache_dir, force: bool, progress) -> dict | None:
    """Start the MuJoCo comparison on ``side``, or read it from the cache; None, with a note on
    stderr, when mujoco is not installed (it is an optional extra).

    Helper: (a) the robot alone, each gait, ``mujoco_check.TRAVEL_DURATION`` seconds in both
    simulators; (b) per gait the first K = min(N, ``MUJOCO_MEMBERS``) members, each from its own
    settled start (q0, qd0) with its own friction scale, the box displacement after
    ``BOX_DURATION`` seconds (or the ensemble window if shorter), ours read off the member's run.
    Every row is cached in ``cache_dir`` under a hash of its inputs (``_mujoco_key``); ``force``
    computes them again. ``_mujoco_rows`` collects them.
    """
    from .mujoco_check import mujoco_available

    if not mujoco_available():
        _say(progress, "  MuJoCo comparison skipped: mujoco is not installed (pip install mujoco)")
        return None
    done = {g: members for g, members in specs.items() if not runs[members[0]].error}
    if not done:
        return None
    duration = min(BOX_DURATION, window_s, min(runs[m[0]].duration for m in done.values()))
    k = min(len(next(iter(done.values()))), MUJOCO_MEMBERS)
    boxed = {g: [m for m in members[:k] if not runs[m].error] for g, members in done.items()}
    key = _mujoco_key(boxed, runs, duration)
    job = {"key": key, "cached": os.path.join(cache_dir, f"mujoco-{key[:16]}.json"), "gaits": len(done), "k": k,
           "t0": time.perf_counter(), "rows": None, "futures": []}
    if os.path.isfile(job["cached"]) and not force:
        job["rows"] = _read_json(job["cached"]).get("rows")
    if job["rows"] is None:
        job["futures"] = _mujoco_compute(side, boxed, runs, duration)
    return job


def _mujoco_rows(job: dict | None, out_dir, progress, files) -> list[dict]:
    """The MuJoCo comparison of ``_mujoco_submit`` as claims, and its figure (appended to ``files``).

    Helper: waits for the rows, caches computed ones; the figure is kept when its rows came from
    the cache and it was drawn from them (``.stamps.json``).
    """
    from .figures import fig_mujoco_check
    from .mujoco_check import claims

    if job is None:
        return []
    if job["rows"] is None:
        job["rows"] = [row for f in job["futures"] for row in f.result()]
        os.makedirs(os.path.dirname(job["cached"]), exist_ok=True)
        write_text(job["cached"], json.dumps({"key": job["key"], "rows": _clean(job["rows"])}))
        what = "computed"
    else:
        what = "from the cache"
    stamps_path = os.path.join(out_dir, ".stamps.json")
    stamps, stamp = _read_json(stamps_path), _stamp({"mujoco": job["key"]}, fig_mujoco_check)
    old = stamps.get("fig_mujoco_check", {})
    if what == "from the cache" and old.get("stamp") == stamp and all(os.path.isfile(f) for f in old.get("files", [])):
        files += old["files"]
    else:
        written = fig_mujoco_check.make(job["rows"], out_dir)
        stamps["fig_mujoco_check"] = {"stamp": stamp, "files": written}
        write_text(stamps_path, json.dumps(stamps, indent=1))
        files += written
    _say(progress, f"  MuJoCo comparison: {job['gaits']} gaits x {job['k']} member(s), {what}, "
                   f"{time.perf_counter() - job['t0']:.1f} s")
    return claims(job["rows"])


def _mujoco_key(boxed: dict, runs: dict, duration: float) -> str:
    """SHA-256 of every input of the MuJoCo rows: the runs' cache keys (their starts, gaits and
    physics), the duration, the source of ``mujoco_check`` and ``mjcf`` and mujoco's version."""
    import mujoco

    from . import mujoco_check
    from .. import mjcf

    h = hashlib.sha256(json.dumps({"runs": {g: [s.key() for s in members] for g, members in boxed.items()},
                                   "duration": duration, "mujoco": mujoco.__version__,
                                   "members": MUJOCO_MEMBERS}, sort_keys=True).encode())
    for module in (mujoco_check, mjcf):
        with open(module.__file__, "rb") as f:
            h.update(f.read())
    h.update(physics_hash().encode())
    return h.hexdigest()


def _mujoco_compute(executor, boxed: dict, runs: dict, duration: float) -> list:
    """Futures of the travel rows and the box-ensemble rows, one task per gait and kind on ``executor``
    (each a list of rows); the box rows, the longest, are submitted first."""
    from .mujoco_check import box_ensemble_rows, robot_travel_rows

    ensembles = {}
    for g, members in boxed.items():
        ensembles[g] = []
        for spec in members:
            r = runs[spec]
            n = min(int(round(duration / r.dt)), len(r.box_pose) - 1)
            ensembles[g].append({"reference": spec.reference(), "q0": r.q[0], "qd0": r.qd[0],
                                 "mu_scale": 1.0 if spec.member is None else spec.member.mu_scale,
                                 "ours": r.box_pose[n, :2] - r.box_pose[0, :2]})
    boxes = [executor.submit(box_ensemble_rows, {g: e}, duration) for g, e in ensembles.items()]
    travel = [executor.submit(robot_travel_rows, [g], params={g: runs[members[0]].meta.get("gait_params", {})})
              for g, members in boxed.items()]
    # the rows in the order they always had: every travel row, then every box row
    return travel + boxes


BOX_DURATION = 3.0  # [s] the box comparison with MuJoCo (0.1 ms steps there: 30 000 per member)


def _optimum_paths(directory: str, gaits) -> list[str]:
    """The params JSONs in ``directory`` that the optimization figures show: one per gait, then ``DIRECTIONS``."""
    paths = [os.path.join(directory, f"{g}.json") for g in gaits]
    paths += [os.path.join(directory, f"direction-{name}.json") for name in DIRECTIONS]
    return [p for p in paths if os.path.isfile(p)]


def _replays_submit(executor, directory: str, gaits, cache_dir: str) -> list:
    """Futures of the optima's replays (``_replayed_box_path``) on ``executor``, for those that did
    not record their box path and are not yet cached."""
    if not os.path.isdir(directory):
        return []
    return [executor.submit(_replayed_box_path, p, cache_dir) for p in _optimum_paths(directory, gaits)
            if not _records_box_path(p) and not os.path.isfile(_replay_cache(p, cache_dir))]


def _records_box_path(path: str) -> bool:
    """Whether the params JSON ``path`` holds its optimum's box path (then no replay is needed)."""
    try:
        with open(path) as f:
            return bool(json.load(f).get("box_path"))
    except (OSError, ValueError, AttributeError):
        return False  # the figure's load_result reports what is wrong with it


def _optimization_figures(directory: str, gaits, out_dir: str, cache_dir: str, progress: bool,
                          replays=None) -> list[str]:
    """``fig_optimization`` (one optimum per gait) and ``fig_directions`` (``DIRECTIONS``) from the
    params JSONs in ``directory``, each with the box path its optimization recorded; a JSON
    without one (written before ``box_path`` was kept) is replayed once and its path cached.
    ``replays``: futures of replays already started (``_replays_submit``); an optimum whose replay
    is not cached is replayed here."""
    from .figures.fig_optimization import make
    from ..planning.results import load_result

    def runs(names):
        out = []
        for label, gait, path in names:
            if os.path.isfile(path):
                record = load_result(path)
                xy = record["box_path"]["xy"] if record.get("box_path") else _replayed_box_path(path, cache_dir)
                out.append({"label": label, "gait": gait, "record": record, "box_xy": xy})
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
    _say(progress, f"  optimization figures: {len(per_gait)} gaits, {len(directions)} directions, "
                   f"{time.perf_counter() - t0:.1f} s")
    return files


def _replayed_box_path(path: str, cache_dir: str) -> np.ndarray:
    """(n, 2) box path of the optimum of the params JSON ``path``, replayed once and cached under a
    hash of the JSON and the physics source."""
    from ..planning.results import replay

    cached = _replay_cache(path, cache_dir)
    if os.path.isfile(cached):
        return np.load(cached)
    traj, _ = replay(path)
    xy = traj.box_pose[:, :2].copy()
    os.makedirs(cache_dir, exist_ok=True)
    atomic_write(cached, lambda tmp: np.save(tmp, xy))
    return xy


def _replay_cache(path: str, cache_dir: str) -> str:
    """Where ``_replayed_box_path`` caches the optimum ``path``: a hash of the JSON and the physics source."""

    with open(path, "rb") as f:
        key = hashlib.sha256(f.read() + physics_hash(PLANNING_MODULES).encode()).hexdigest()[:16]
    return os.path.join(cache_dir, f"optimum-{key}.npy")


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
