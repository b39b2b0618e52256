"""The figure command's MuJoCo comparison: its rows computed on an executor (or read from the cache),
its claims and its figure.

(a) The robot alone, each gait, ``mujoco_check.TRAVEL_DURATION`` seconds in both simulators;
(b) per gait the first K = min(N, ``MUJOCO_MEMBERS``) members of the ensemble, each from its own
settled start (q0, qd0) with its own friction scale, the box displacement after ``BOX_DURATION``
seconds (or the ensemble window if shorter), ours read off the member's run. Every row is cached
under a hash of its inputs (``mujoco_key``), checked on read (``cache.read_rows``).

Why K = 4: MuJoCo's box rollouts run at 0.05 ms steps; 4 members per gait keep the comparison
short on two cores and still give a spread (min-max of 4) to compare against (docs/results.md,
"Time to regenerate").
"""

from __future__ import annotations

import hashlib
import json
import os
import time

from ..provenance import physics_hash
from .cache import read_rows, verified, write_rows
from .stamps import Stamps, clean, figure_stamp, say

MUJOCO_MEMBERS = 4  # members per gait in the MuJoCo box comparison: K = min(N, 4)
BOX_DURATION = 3.0  # [s] the box comparison with MuJoCo (0.05 ms steps there: 60 000 per member)


def mujoco_submit(side, specs: dict, runs: dict, window_s: float, cache_dir: str, force: bool, progress) -> dict | None:
    """Start the MuJoCo comparison (module docstring) on the executor ``side``, or read it from the
    cache (``force``: compute it again); None, with a note on stderr, when mujoco is not installed
    (it is an optional extra). ``mujoco_rows`` collects it."""
    from .mujoco_check import mujoco_available

    if not mujoco_available():
        say(progress, "  MuJoCo comparison skipped: mujoco is not installed (pip install mujoco)")
        return None
    done = {g: members for g, members in specs.items() if not runs[members[0]].error}
    if not done:
        return None
    duration = min(BOX_DURATION, window_s, min(runs[m[0]].duration for m in done.values()))
    k = min(len(next(iter(done.values()))), MUJOCO_MEMBERS)
    boxed = {g: [m for m in members[:k] if not runs[m].error] for g, members in done.items()}
    key = mujoco_key(boxed, runs, duration)
    job = {"key": key, "cached": os.path.join(cache_dir, f"mujoco-{key[:16]}.json"), "gaits": len(done), "k": k,
           "t0": time.perf_counter(), "rows": None, "futures": []}
    if os.path.isfile(job["cached"]) and not force:
        job["rows"] = verified(job["cached"], lambda p: read_rows(p, key))
    if job["rows"] is None:
        job["futures"] = _mujoco_compute(side, boxed, runs, duration)
    return job


def mujoco_rows(job: dict | None, out_dir: str, progress, files: list) -> list[dict]:
    """The MuJoCo comparison of ``mujoco_submit`` as claims, and its figure (appended to ``files``).

    Waits for the rows and caches computed ones; the figure is kept when its rows came from the
    cache and it was drawn from them (``stamps.Stamps``).
    """
    from .figures import fig_mujoco_check
    from .mujoco_check import claims

    if job is None:
        return []
    if job["rows"] is None:
        job["rows"] = [row for f in job["futures"] for row in f.result()]
        os.makedirs(os.path.dirname(job["cached"]), exist_ok=True)
        write_rows(job["cached"], job["key"], clean(job["rows"]))
        what = "computed"
    else:
        what = "from the cache"
    stamps, stamp = Stamps(out_dir), figure_stamp({"mujoco": job["key"]}, fig_mujoco_check)
    kept = stamps.kept("fig_mujoco_check", stamp) if what == "from the cache" else None
    if kept is not None:
        files += kept
    else:
        written = fig_mujoco_check.make(job["rows"], out_dir)
        stamps.record("fig_mujoco_check", stamp, written)
        files += written
    say(progress, f"  MuJoCo comparison: {job['gaits']} gaits x {job['k']} member(s), {what}, "
                  f"{time.perf_counter() - job['t0']:.1f} s")
    return claims(job["rows"])


def mujoco_key(boxed: dict, runs: dict, duration: float) -> str:
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
