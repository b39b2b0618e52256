"""Run the paper's gaits for the figures: one simulation per gait, cached, both cores in use.

Helper: the simulation half of ``cobra-ref figures`` ([COBRA] sec. "Results", figs. 3-9).

Each gait run is a ``RunSpec``: the gait's name and parameters, the duration, dt and the robot-box
friction. Its result is the ``Trajectory`` NPZ of ``cobra-ref simulate``, stored in the cache
directory under ``<gait>-<key>.npz``, where key = SHA-256 of every input: the spec, the model
parameters (``CobraParameters``), the stepper settings and the source code of every module the
simulation runs (so editing the physics invalidates the cache, editing a figure does not).
A run that fails mid-way is stored as ``<gait>-<key>.failed.npz`` with what it computed and its
error, and the figures use that partial trajectory (the claims report says so).

Box placement per gait (assumption C9, extended):

* C, S, J, J-mirror: the box starts 5 cm from the middle link on the concave side of the start
  shape, one face turned to the robot (``simulate.initial_state``). For S, whose shape has no
  single concave side at the middle, it is the side the robot's centre of mass lies on.
* sidewinding moves sideways along the ground instead of rolling in place, so its box goes in
  the direction the gait *travels*, 5 cm beyond the band its wave sweeps
  (``placement.travel_placement``, assumption A31; computed with the run, its direction and
  clearance reported in the trajectory's ``meta``).
"""

from __future__ import annotations

import hashlib
import json
import os
import sys
import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import asdict, dataclass, field, replace

import numpy as np

from .. import __version__
from ..gaits import gait, gait_params
from ..executors import worker_init
from ..params import CobraParameters
from ..placement import travel_placement
from ..progress import progress_printer
from ..robots import cobra_model
from ..simulate import simulate
from ..start import initial_state
from ..step import SimulationError, StepSettings
from ..trajectory import Trajectory

PAPER_GAITS = ("C", "S", "J", "J-mirror", "sidewinding")



@dataclass(frozen=True)
class RunSpec:
    """One gait run: the gait, its parameters (empty = the defaults of assumption A10), and the settings."""

    gait: str
    duration: float = 10.0
    dt: float = 1e-3
    params: dict = field(default_factory=dict, hash=False)
    mu_robot_box: float | None = None

    def reference(self):
        return gait(self.gait, **self.params)

    def cobra_parameters(self) -> CobraParameters:
        p = CobraParameters()
        return p if self.mu_robot_box is None else replace(p, mu_robot_box=self.mu_robot_box)

    def key(self) -> str:
        """SHA-256 of every input of the run (module docstring)."""
        h = hashlib.sha256()
        record = {"spec": asdict(self), "gait": gait_params(self.reference()),
                  "cobra": asdict(self.cobra_parameters()), "settings": asdict(StepSettings(dt=self.dt)),
                  "version": __version__}
        h.update(json.dumps(record, sort_keys=True, default=str).encode())
        h.update(physics_hash().encode())
        return h.hexdigest()

    def filename(self) -> str:
        return f"{self.gait}-{self.key()[:16]}.npz"


def physics_hash(extra=()) -> str:
    """SHA-256 of the source of every module a simulation can run: the physics core (the modules
    at the top of the package) and the fast wing, plus the subpackages named in ``extra``.

    Helper: the code-version part of the cache keys and of the optimizer's params JSON. The files
    are found, not listed, so a new physics module cannot be forgotten.
    """
    root, h = os.path.dirname(os.path.dirname(os.path.abspath(__file__))), hashlib.sha256()
    for folder in ("", "fast") + tuple(extra):
        directory = os.path.join(root, folder)
        for name in sorted(os.listdir(directory)):
            if name.endswith(".py"):
                with open(os.path.join(directory, name), "rb") as f:
                    h.update(f"{folder}/{name}".encode() + f.read())
    return h.hexdigest()


def run(spec: RunSpec, cache_dir: str, force: bool = False, progress=None) -> tuple[Trajectory, bool]:
    """The trajectory of ``spec``, from the cache when it holds this exact run (unless ``force``),
    else simulated and stored. Returns (trajectory, came_from_cache).

    Helper: one gait run of the figure command (module docstring: cache key, box placement).
    """
    path = os.path.join(cache_dir, spec.filename())
    failed = path[:-4] + ".failed.npz"
    if not force:
        for p in (path, failed):
            if os.path.isfile(p):
                return Trajectory.from_npz(p), True
    model = cobra_model(spec.cobra_parameters(), with_box=True)
    ref = spec.reference()
    placement = (travel_placement(cobra_model(spec.cobra_parameters(), with_box=False), ref, spec.dt)
                 if spec.gait == "sidewinding" else None)
    direction = None if placement is None else placement.direction
    q0, qd0 = initial_state(model, ref, box_direction=direction,
                            box_gap=0.05 if placement is None else placement.box_gap)
    try:
        traj = simulate(model, ref, spec.duration, StepSettings(dt=spec.dt), q0, qd0, progress=progress)
        out = path
    except SimulationError as exc:
        if exc.trajectory is None:
            raise
        traj, out = exc.trajectory, failed
    traj.meta.update({"gait": spec.gait, "gait_params": gait_params(ref), "cache_key": spec.key(),
                      "box_direction": None if direction is None else [float(x) for x in direction],
                      "box_gap": None if placement is None else placement.box_gap})
    os.makedirs(cache_dir, exist_ok=True)
    traj.to_npz(out)
    return traj, False


def _run_in_worker(spec: RunSpec, cache_dir: str, force: bool, queue):
    """Process-pool entry: run one spec, reporting (gait, done, total) to ``queue``."""
    report = None if queue is None else (lambda done, total: queue.put((spec.gait, done, total)))
    traj, cached = run(spec, cache_dir, force, report)
    return spec.gait, cached


def run_all(specs, cache_dir: str, force: bool = False, workers: int | None = None,
            progress: bool = True) -> dict:
    """Run every spec (in parallel on ``workers`` processes, default: the machine's cores) and
    return {gait: Trajectory}. Progress on stderr: each gait's percentage and the time left.

    Helper: the figure command's simulations; a worker's exception is raised here.
    """
    specs = list(specs)
    workers = workers or min(len(specs), os.cpu_count() or 1)
    todo = [s for s in specs if force or not _cached(s, cache_dir)]
    if todo and workers > 1 and len(todo) > 1:
        import multiprocessing

        with multiprocessing.Manager() as manager:
            queue = manager.Queue()
            with ProcessPoolExecutor(workers, initializer=worker_init) as pool:
                futures = [pool.submit(_run_in_worker, s, cache_dir, force, queue) for s in todo]
                _watch(futures, queue, todo, progress)
                for f in futures:
                    f.result()  # re-raises a worker's exception here
        done = {}
    else:
        done = {s.gait: run(s, cache_dir, force, progress_printer(f"  {s.gait}") if progress else None)[0]
                for s in todo}
    return {s.gait: done[s.gait] if s.gait in done else run(s, cache_dir)[0] for s in specs}


def _cached(spec: RunSpec, cache_dir: str) -> bool:
    path = os.path.join(cache_dir, spec.filename())
    return os.path.isfile(path) or os.path.isfile(path[:-4] + ".failed.npz")


def _watch(futures, queue, specs, progress: bool) -> None:
    """Print the status of all running gaits until every future is done: one line rewritten in
    place on a terminal, a new line every 10 s otherwise (logs, CI)."""
    start, state = time.perf_counter(), {s.gait: (0, 1) for s in specs}
    tty, last = sys.stderr.isatty(), 0.0
    while not all(f.done() for f in futures):
        time.sleep(0.5)
        while not queue.empty():
            name, done, total = queue.get()
            state[name] = (done, total)
        elapsed = time.perf_counter() - start
        if progress and (tty or elapsed - last >= 10.0):
            last = elapsed
            frac = sum(d / t for d, t in state.values()) / len(state)
            left = f"~{elapsed / frac * (1 - frac):4.0f} s left" if frac > 0 else "estimating time left"
            parts = "  ".join(f"{k} {100 * d / t:3.0f}%" for k, (d, t) in state.items())
            sys.stderr.write(("\r" if tty else "") + f"  simulating: {parts}  {left} " + ("" if tty else "\n"))
            sys.stderr.flush()
    if progress and tty:
        sys.stderr.write("\n")
