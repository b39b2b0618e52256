"""``cobra-ref figures``: every result of [COBRA] (figs. 3-9, GIFs, the claims report) in one command.

Helper: the orchestration; the physics is in ``reproduce`` (simulations), ``analysis`` (numbers),
``figures`` (plots), ``claims`` (verdicts) and ``mujoco_rollout`` (the cross-check).

Steps:

1. simulate the five gaits (C, S, J, J-mirror, sidewinding; 10 s each, 1 s with ``quick``) on
   both cores, or read them from the cache (``reproduce``: keyed by a hash of every input);
2. write each figure; a figure whose inputs (the simulations' cache keys and the figure
   module's source) are unchanged since it was last written is kept (``.stamps.json`` in the
   output directory), unless ``force``;
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

from .atomic import write_text
from .reproduce import PAPER_GAITS, RunSpec, run_all

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


def regenerate(out_dir: str = "figures", quick: bool = False, force: bool = False, cache_dir: str | None = None,
               workers: int | None = None, mujoco: bool = True, progress: bool = True, gaits=PAPER_GAITS,
               params: dict | None = None) -> dict:
    """Run steps 1-3 of the module docstring; return {"files": [...], "claims": [...], "seconds": ...}.

    Helper: the body of ``cobra-ref figures``.
    """
    from . import claims as claims_mod
    from .figures import FIGURES
    from .robots import cobra_model

    start = time.perf_counter()
    check_output_dir(out_dir)
    cache_dir = cache_dir or os.path.join(out_dir, ".cache")
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
    summaries = claims_mod.gait_summaries(results)
    report = claims_mod.paper_claims(summaries)
    settings = {"duration (s)": specs[0].duration, "dt (s)": specs[0].dt, "quick": quick,
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
    """The MuJoCo rollout cross-check (design brief sec. 7) as claims, and its figure; empty, with
    a note on stderr, when mujoco is not installed (it is an optional extra)."""
    from . import claims as claims_mod
    from .mujoco_rollout import cross_check, mujoco_available

    if not mujoco_available():
        _say(progress, "  MuJoCo cross-check skipped: mujoco is not installed (pip install mujoco)")
        return []
    done = {g: r for g, r in results.items() if not r.error}
    if not done:
        return []
    first = next(iter(done.values()))
    ours = {g: r.box_pose[-1, :2] - r.box_pose[0, :2] for g, r in done.items()}
    directions = {g: r.meta.get("box_direction") for g, r in done.items()}
    params = {g: r.meta.get("gait_params", {}) for g, r in done.items()}
    t0 = time.perf_counter()
    rows = cross_check(list(done), first.duration, first.dt, ours=ours, box_directions=directions, params=params)
    from .figures.mujoco_check import make as make_figure

    files += make_figure(rows, out_dir)
    _say(progress, f"  MuJoCo cross-check: {len(rows)} gaits, {time.perf_counter() - t0:.1f} s")
    return claims_mod.mujoco_claims(rows)


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
