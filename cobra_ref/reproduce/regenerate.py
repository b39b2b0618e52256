"""``cobra-ref figures``: every result of [COBRA] (figs. 3-9, GIFs, the claims report) in one command.

The orchestration; the simulations are in ``runs``, the numbers in ``analysis``, the plots in
``figures``, the verdicts in ``claims``, the optima in ``optima``, the MuJoCo cross-check in
``mujoco_job`` and what is kept between runs in ``stamps``.

Steps:

0. with ``reoptimize_all``, re-run the single-shooting optimizer for every gait and for the
   direction goals (``DIRECTIONS``) into ``OUT/optimized/``;
1. simulate the five gaits (C, S, J, J-mirror, sidewinding), each as an ensemble of N members
   (``MEMBERS`` = 8 by default; ``ensemble.members``, assumption A29): member 0 is the figure run
   (10 s, 1 s with ``quick``), members 1 .. N-1 run ``ENSEMBLE_DURATION`` = 6 s (1 s with
   ``quick``), on both cores (or any executor), or read from the cache (``runs``: keyed by
   a hash of every input; each entry checked on read against its key and content, ``cache``). A gait with a params JSON in the optimized directory
   (``cobra_ref/optimized/<gait>.json`` by default) runs with its optimized parameters, the
   others with their defaults;
2. write each figure from the member-0 runs, figs. 6 and 9 with the members' spread; a figure
   whose inputs (the simulations' cache keys and the figure package's source) are unchanged
   since it was last written, and whose files still hold what was written, is kept
   (``.stamps.json`` in the output directory), unless ``force``;
   ``fig_optimization`` and ``fig_directions`` come from the params JSONs (each optimum
   replayed once, its box path cached);
3. judge the claims on the ensembles: every member over the same window, its first
   ``ENSEMBLE_DURATION`` seconds (member 0 truncated to it), claim GT on the direction optima's
   box paths (``optima.direction_outcomes``), and write ``claims.json`` (a list
   of claim entries, each with its ``statistics`` over the members, ``check``), ``claims.md``
   and ``summary.json`` with every gait's numbers and every member's; then the MuJoCo
   comparison on the first K = min(N, ``MUJOCO_MEMBERS`` = 4) members of each gait, cached;
4. with ``claims_map`` (a full run's default), the verdict map over the paper's unknowns
   (``claims_map``): its runs go with step 1's (the nominal set-up is the first members of step
   1), its cells are judged by the claims' rules, written to ``claims_map.json``,
   ``claims_map.md`` and ``fig_claims_map.png`` (``map_figure``), named per claim at the end of
   ``claims.md``, and joined to ``claims.json`` so that ``--check`` compares them too.

Why ENSEMBLE_DURATION = 6 s: the claims judge steady gaits, so the window holds the default
gaits' 2 s phase-rate ramp and two 0.5 Hz periods after it (the steady-power and phase claims
need those two periods; sidewinding meets its box at about 1.5 s and pushes for the rest). A
clean run then simulates 5 x 10 s figure runs and 35 x 6 s members, 260 simulated seconds, and the
map 124 more runs of 6 s, 744 simulated seconds. Why K = 4: ``mujoco_job``.

A quick run (``quick``, ``cobra-ref figures --quick``) is a smoke run: 1 s runs at ``QUICK_DT`` =
2 ms, ``QUICK_MEMBERS`` = 1 member per gait and no MuJoCo comparison unless asked for, the figures
as PNG only; the first
line of ``claims.md``, ``claims.json``, ``summary.json`` and of every figure's title says so
(``smoke_note``), and ``check.read_committed`` refuses such a report. A full run computes the
same whether or not quick runs were made.

Every file is written atomically (temporary file + rename): an interrupted run leaves the
previous outputs or none, never half a file.
"""

from __future__ import annotations

import importlib
import json
import os
import time
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np

from ..infra.executors import own_pool
from ..infra.output import write_text
from ..infra.validation import DEFAULT_DT
from .claims_map import MAP_MEMBERS, check_entries, judge, map_specs, where_lines
from .map_figure import write_map
from .mujoco_job import MUJOCO_MEMBERS, mujoco_rows, mujoco_submit
from .optima import (DIRECTIONS, OPTIMIZED_DIR, direction_outcomes, optimization_figures, optimized_files,
                     optimized_params, reoptimize, replays_submit, shown)
from .rules import fingerprint
from .runs import PAPER_GAITS, RunSpec, check_workers, run_all
from .stamps import Stamps, clean, figure_stamp, say

__all__ = ["DIRECTIONS", "ENSEMBLE_DURATION", "FULL_DURATION", "FiguresOptions", "MEMBERS", "MUJOCO_MEMBERS",
           "OPTIMIZED_DIR", "QUICK_DT", "QUICK_DURATION", "QUICK_MEMBERS", "SMOKE_KEY", "SMOKE_TITLE",
           "check_output_dir", "ensemble_report", "ensemble_specs", "ensemble_summaries", "goal_directions", "goal_offsets",
           "marked_json", "optimized_files", "optimized_params", "regenerate", "reoptimize", "smoke_note", "specs_for",
           "window"]

FULL_DURATION, QUICK_DURATION = 10.0, 1.0
QUICK_DT = 2e-3  # [s] the time step of a quick (smoke) run: half the steps, within the stable range
MEMBERS = 8  # members per gait (member 0: the figure run)
QUICK_MEMBERS = 1  # members per gait of a quick (smoke) run, unless asked for more
SMOKE_KEY = "smoke run"  # the first key of a quick run's claims.json and summary.json
SMOKE_TITLE = "SMOKE RUN (cobra-ref figures --quick): not the paper's results"  # a quick run's figures' first line
# [s] the other members' runs and the window every member is judged on: the default gaits' 2 s
# phase-rate ramp and two 0.5 Hz periods after it (the steady-power and phase claims need two
# periods after the ramp; sidewinding meets its box at about 1.5 s); the budget's lever
ENSEMBLE_DURATION = 6.0
CACHE_PROBE = "C-0000000000000000.npz"  # a cache entry's name: the file whose writing is tried before the runs


def check_output_dir(out_dir: str, what: str = "output directory", probe: str = "claims.json") -> None:
    """Create ``out_dir`` if needed; raise OSError naming it (as ``what``) if it is empty, not a
    directory, or cannot be written (checked before any simulation starts, so a bad directory
    costs nothing). ``probe``: the file whose writing is tried there."""
    from ..infra.output import check_output

    if not isinstance(out_dir, (str, os.PathLike)) or not str(out_dir).strip():
        raise OSError(f"{what} is empty: give a directory")
    if os.path.exists(out_dir) and not os.path.isdir(out_dir):
        raise OSError(f"{what} {out_dir} is not a directory")
    try:
        os.makedirs(out_dir, exist_ok=True)
    except OSError as exc:
        raise OSError(f"cannot create {what} {out_dir}: {exc.strerror}") from exc
    # a real probe (a temporary file created and removed): os.access answers yes to root everywhere
    check_output(os.path.join(out_dir, probe), what)


def specs_for(gaits=PAPER_GAITS, quick: bool = False, dt: float = DEFAULT_DT,
              params: dict | None = None) -> list[RunSpec]:
    """The figure run of each gait (member 0 of each ensemble): 10 s (1 s with ``quick``) at dt,
    with ``params[gait]`` if given."""
    duration = QUICK_DURATION if quick else FULL_DURATION
    params = params or {}
    return [RunSpec(g, duration=duration, dt=dt, params=dict(params.get(g, {}))) for g in gaits]


def ensemble_specs(gaits=PAPER_GAITS, n_members: int = MEMBERS, quick: bool = False, dt: float = DEFAULT_DT,
                   params: dict | None = None) -> dict:
    """{gait: [RunSpec per member]}: member 0 is the figure run (``specs_for``), members 1 .. n-1
    are ``ensemble.members(gait, n)``, each ``ENSEMBLE_DURATION`` seconds (1 s with ``quick``):
    the ensembles of the figure command (module docstring, step 1).
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
    """The seconds over which every member is judged (``ENSEMBLE_DURATION``; 1 s with ``quick``)."""
    return QUICK_DURATION if quick else ENSEMBLE_DURATION


def ensemble_summaries(specs: dict, results: dict, duration: float, goals: dict | None = None) -> dict:
    """{gait: [summary per member]}: ``claims.gait_summaries`` of each member's first ``duration``
    seconds (``Trajectory.truncated``), with the member's perturbation (``member``, None for
    member 0) and, for a gait optimized towards a goal, ``goal_direction`` (unit (x, y), world
    axes): the numbers behind the ensemble claims and the spreads of figs. 6 and 9.
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


def goal_offsets(files: dict) -> dict:
    """{gait: (dx, dy)} [m] of the goal of each params JSON in ``files`` ({gait: path}) that has a
    finite, non-zero one: ``settings.goal`` of the params JSON, relative to the box's start, world
    axes (fig. 3 marks it)."""
    out = {}
    for g, path in files.items():
        try:
            with open(path, encoding="utf-8") as f:
                goal = np.asarray(json.load(f)["settings"]["goal"], dtype=float)[:2]
        except (OSError, ValueError, KeyError, TypeError):
            continue
        if goal.shape == (2,) and np.all(np.isfinite(goal)) and np.linalg.norm(goal) > 0:
            out[g] = [float(x) for x in goal]
    return out


def goal_directions(files: dict) -> dict:
    """{gait: unit (x, y)} of the goal of each params JSON in ``files`` ({gait: path}) that has one
    (``goal_offsets``): ``goal_direction`` of the ensemble summaries."""
    return {g: [float(x) for x in np.asarray(v) / np.linalg.norm(v)] for g, v in goal_offsets(files).items()}


@dataclass(frozen=True)
class FiguresOptions:
    """What ``regenerate`` makes and from what: ``quick`` (a smoke run: 1 s runs, module
    docstring), ``force`` (every run and figure anew, the caches and stamps ignored), ``mujoco``
    (the MuJoCo comparison; None: with a full run, not with a quick one), ``gaits``,
    ``n_members`` (N >= 1 members per gait; None: ``MEMBERS``, ``QUICK_MEMBERS`` with ``quick``),
    ``params`` ({gait: gait parameters}; None = the optima in ``optimized_dir``, or the defaults
    without one), ``optimized_dir`` (None: the defaults, no optimization figures),
    ``reoptimize_all`` (step 0: re-run the optimizer into ``OUT/optimized/`` and use those
    optima), ``claims_map`` (step 4, the verdict map over the paper's unknowns; None: with a full
    run, not with a quick one). ValueError for a bad ``n_members``."""

    quick: bool = False
    force: bool = False
    mujoco: bool | None = None
    gaits: tuple = PAPER_GAITS
    n_members: int | None = None
    params: dict | None = None
    optimized_dir: str | None = OPTIMIZED_DIR
    reoptimize_all: bool = False
    claims_map: bool | None = None

    def __post_init__(self):
        if self.mujoco is None:
            object.__setattr__(self, "mujoco", not self.quick)
        if self.claims_map is None:
            object.__setattr__(self, "claims_map", not self.quick)
        if self.n_members is None:
            object.__setattr__(self, "n_members", QUICK_MEMBERS if self.quick else MEMBERS)
        n = self.n_members
        if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
            raise ValueError(f"members per gait must be a whole number >= 1, got {n!r}")


@dataclass(frozen=True)
class FiguresJob:
    """Everything steps 2-3 of the module docstring need once the runs are done (``regenerate``)."""

    options: FiguresOptions
    out_dir: str
    cache_dir: str
    optimized_dir: str | None  # where the optima are read (OUT/optimized with ``reoptimize_all``)
    progress: bool
    specs: dict  # {gait: [RunSpec per member]}
    runs: dict  # {RunSpec: Trajectory}
    files_opt: dict  # {gait: params JSON} of the gaits run with their optima
    params: dict  # {gait: gait parameters} of those gaits
    start: float  # time.perf_counter() at the start of ``regenerate``
    map_specs: dict  # {set-up: {gait: [RunSpec per member]}} of the verdict map (empty without it)

    @property
    def every(self) -> list:
        return [spec for runs in self.specs.values() for spec in runs]

    @property
    def window(self) -> float:
        return window(self.options.quick)


def regenerate(out_dir: str = "figures", options: FiguresOptions = FiguresOptions(), cache_dir: str | None = None,
               workers: int | None = None, progress: bool = True, executor=None) -> dict:
    """Run steps 0-3 of the module docstring; return {"files": [...], "claims": [...], "seconds": ...}.

    The body of ``cobra-ref figures``. ``options``: what to make (``FiguresOptions``);
    ``cache_dir``: the runs' cache (default ``OUT/.cache``); ``workers``, ``executor``: where the
    runs go (``runs.run_all``; default a process pool on the cores).
    """
    start = time.perf_counter()
    check_output_dir(out_dir)
    cache_dir = os.path.join(out_dir, ".cache") if cache_dir is None else cache_dir
    check_output_dir(cache_dir, "cache directory", CACHE_PROBE)
    check_workers(workers)
    optimized_dir = options.optimized_dir
    if options.reoptimize_all:
        optimized_dir = os.path.join(out_dir, "optimized")
        reoptimize(optimized_dir, options.gaits, progress)
    files_opt = optimized_files(optimized_dir, options.gaits) if optimized_dir else {}
    params = options.params
    if params is None:
        params = optimized_params(files_opt)
        if params:
            say(progress, f"optimized parameters for {', '.join(params)} (from {optimized_dir}); "
                          f"defaults (assumption A10) for any other gait")
        else:
            say(progress, "default gait parameters (assumption A10) for every gait")
    specs = ensemble_specs(options.gaits, options.n_members, options.quick, QUICK_DT if options.quick else DEFAULT_DT,
                           params)
    mapped = map_specs(specs, n_members=min(MAP_MEMBERS, options.n_members)) if options.claims_map else {}
    # sidewinding first among runs of one duration: its box-free placement run makes it the longest
    every = sorted((spec for runs in specs.values() for spec in runs), key=lambda s: s.gait != "sidewinding")
    every += [spec for per in mapped.values() for runs in per.values() for spec in runs]
    note = smoke_note(options)
    say(progress, (f"{note}\n" if note else "") + f"simulating {len(specs)} gaits x {options.n_members} member(s): "
                  f"member 0 {every[0].duration:g} s, the others {window(options.quick):g} s"
                  + (f"; the verdict map: {len(mapped) - 1} more set-ups" if mapped else "") + f" (cache: {cache_dir})")
    runs = run_all(every, cache_dir, force=options.force, workers=workers, progress=progress, executor=executor)
    job = FiguresJob(options, out_dir, cache_dir, optimized_dir, progress, specs, runs, files_opt, params, start,
                     mapped)
    # the MuJoCo comparison and the optima's replays run on the executor (default: a process pool of
    # ``workers``, ended at once on an interrupt) while this process draws the figures
    with nullcontext(executor) if executor is not None else own_pool(workers) as side:
        return _finish(job, side)


def _finish(job: FiguresJob, side) -> dict:
    """Steps 2-3 of the module docstring once the runs are done: the MuJoCo rows and the optima's
    replays go to ``side`` first, then the figures and the claims are made here."""
    from . import claims as claims_mod

    from .figures.common import smoke_run

    opts, note = job.options, smoke_note(job.options)
    # the replays first: their figure is drawn before the MuJoCo figure
    replays = replays_submit(side, job.optimized_dir, opts.gaits, job.cache_dir) if job.optimized_dir else []
    pending = mujoco_submit(side, job.specs, job.runs, job.window, job.cache_dir, opts.force,
                            job.progress) if opts.mujoco else None
    results = {g: job.runs[members[0]] for g, members in job.specs.items()}
    ensemble = ensemble_summaries(job.specs, job.runs, job.window, goal_directions(job.files_opt))
    goals = None  # the direction optima's outcomes (claim GT)
    with smoke_run(SMOKE_TITLE if note else None):
        files = _paper_figures(job, results, ensemble)
        if job.optimized_dir and os.path.isdir(job.optimized_dir):
            files += optimization_figures(job.optimized_dir, opts.gaits, job.out_dir, job.cache_dir, job.progress,
                                          replays)
            goals = direction_outcomes(job.optimized_dir, job.cache_dir)
        summaries = claims_mod.gait_summaries(results)
        report = ensemble_report(ensemble, goals)
        settings = _report_settings(job, results)
        if opts.mujoco:
            # the MuJoCo comparisons check the model, they are not claims of the paper
            report += [dict(row, kind=row.get("kind", "check")) for row in mujoco_rows(pending, job.out_dir,
                                                                                       job.progress, files)]
        claims_map = judge(job.map_specs, job.runs, job.window) if job.map_specs else None
        if claims_map:
            files += write_map(claims_map, job.out_dir, note)
    # the map's cells join the report that --check compares; claims.md names where each claim holds
    checked = report + (check_entries(claims_map) if claims_map else [])
    claims_json = marked_json({"claims": clean(checked)}, note) if note else json.dumps(clean(checked), indent=1)
    where = where_lines(claims_map) + ["", "(the map: claims_map.md, fig_claims_map.png)"] if claims_map else None
    paths = {"claims.json": claims_json,
             "claims.md": (f"**{note}**\n\n" if note else "") + claims_mod.to_markdown(report, summaries, settings,
                                                                                        where),
             "summary.json": marked_json(clean({"gaits": summaries, "ensemble": ensemble, "settings": settings}), note)}
    for fname, text in paths.items():
        write_text(os.path.join(job.out_dir, fname), text)
        files.append(os.path.join(job.out_dir, fname))
    return {"files": files, "claims": clean(checked), "seconds": time.perf_counter() - job.start}


def smoke_note(options: FiguresOptions) -> str | None:
    """The line that marks a quick run's outputs as a smoke run (module docstring); None for a full run."""
    if not options.quick:
        return None
    return (f"SMOKE RUN (cobra-ref figures --quick): {QUICK_DURATION:g} s runs at dt = {QUICK_DT * 1e3:g} ms, "
            f"{options.n_members} member(s) per "
            f"gait{'' if options.mujoco else ', no MuJoCo comparison'}: a check that the pipeline runs, not the "
            f"paper's results (cobra-ref figures makes those; --check compares only them)")


def marked_json(body: dict, note: str | None) -> str:
    """``body`` as indented JSON; with a ``note``, ``{SMOKE_KEY: note, ...body}`` with the note on the
    first line (a reader of the first line sees it is a smoke run)."""
    text = json.dumps(body, indent=1)
    if note is None:
        return text
    return "{" + json.dumps(SMOKE_KEY) + ": " + json.dumps(note) + (",\n" + text[2:] if body else "}")


def _paper_figures(job: FiguresJob, results: dict, ensemble: dict) -> list[str]:
    """Every figure of ``figures.FIGURES`` from the member-0 runs (figs. 6 and 9 with the members'
    spread); a figure whose stamp is unchanged is kept (``stamps.Stamps``)."""
    from .figures import FIGURES
    from ..robots import cobra_model

    model = cobra_model(with_box=True)
    keys = {spec.label(): spec.key() for spec in job.every}
    keys["ensemble window (s)"] = job.window
    # fig. 3 marks each optimum's goal
    keys["goals"] = goals = goal_offsets(job.files_opt)
    stamps = Stamps(job.out_dir, job.options.force)
    files = []
    for name in FIGURES:
        module = importlib.import_module(f".figures.{name}", __package__)
        stamp = figure_stamp(keys, module)
        kept = stamps.kept(name, stamp)
        if kept is not None:
            files += kept
            say(job.progress, f"  {name}: unchanged, kept")
            continue
        t0 = time.perf_counter()
        written = module.make(results, job.out_dir, model, ensemble=ensemble, goals=goals)
        stamps.record(name, stamp, written)
        files += written
        say(job.progress, f"  {name}: {len(written)} file(s), {time.perf_counter() - t0:.1f} s")
    return files


def _report_settings(job: FiguresJob, results: dict) -> dict:
    """The settings the claims report and ``summary.json`` state: durations, dt, the ensemble, where
    the gait parameters came from, and sidewinding's box direction."""
    opts, first = job.options, job.every[0]
    return {"duration (s)": first.duration, "dt (s)": first.dt, "quick": opts.quick,
            "ensemble": {"members per gait": opts.n_members, "window (s)": job.window,
                         "rule": "cobra_ref/reproduce/ensemble.py (assumption A29)"},
            "optimized parameters from": {g: shown(job.files_opt[g]) if g in job.files_opt
                                          else "defaults (assumption A10)" for g in opts.gaits}
            if job.params else "defaults (assumption A10)",
            "gait parameters": {g: r.meta.get("gait_params") for g, r in results.items()},
            "box direction (sidewinding)": results["sidewinding"].meta.get("box_direction")
            if "sidewinding" in results else None,
            "claim rules (SHA-256 of their code, rules.fingerprint)": fingerprint()}


def ensemble_report(ensemble: dict, goals=None) -> list[dict]:
    """The paper's claims judged on the ensembles (``claims.ensemble_claims``), each entry with its
    ``statistics`` over the members (``check.claim_statistics``); ``goals``: the direction optima's outcomes (``optima.direction_outcomes``) for claim GT."""
    from . import claims as claims_mod
    from .check import claim_statistics

    report = claims_mod.ensemble_claims(ensemble, goals)
    stats = claim_statistics(ensemble, lambda summaries: claims_mod.paper_claims(summaries, goals))
    for entry in report:
        if entry["id"] in stats:
            entry["statistics"] = stats[entry["id"]]
    return report
