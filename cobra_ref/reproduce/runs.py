"""Run the paper's gaits for the figures: one simulation per gait and ensemble member, cached, on any executor.

The simulation half of ``cobra-ref figures`` ([COBRA] sec. "Results", figs. 3-9).

Each run is a ``RunSpec``: the gait's name and parameters, the duration, dt, the robot-box
friction and the ensemble member (``ensemble.Member``: box shift and turn, phase shift, friction
scale; None for the nominal run). Its result is the ``Trajectory`` NPZ of ``cobra-ref simulate``,
stored in the cache directory under ``<gait>[-m<i>]-<key>.npz``, where key = SHA-256 of every
input: the spec, the model parameters (``CobraParameters``), the stepper settings and the
source code of every module the simulation runs (so editing the physics invalidates the cache,
editing a figure does not). A nominal member adds nothing to the key: member 0 is the nominal run.
A run that fails mid-way is stored as ``<name>.failed.npz`` with what it computed and its error,
and the figures use that partial trajectory (the claims report says so). Each entry records its key
and a SHA-256 of its arrays in its ``meta`` and is checked on read (``cache.read_trajectory``): a
damaged or foreign entry is named on stderr, simulated again and replaced. ``run_all`` sends the
runs to any ``concurrent.futures.Executor`` and reads every result back from the cache, so the
numbers do not depend on where the runs ran.

Box placement per gait (assumption A9, extended):

* C, S, J, J-mirror: the box starts 5 cm from the middle link on the concave side of the start
  shape, one face turned to the robot (``simulate.initial_state``). For S, whose shape has no
  single concave side at the middle, it is the side the robot's centre of mass lies on.
* sidewinding moves sideways along the ground instead of rolling in place, so its box goes in
  the direction the gait *travels*, 5 cm beyond the band its wave sweeps
  (``placement.travel_placement``, assumption A31; computed with the run, its direction and
  clearance reported in the trajectory's ``meta``).

A spec with ``placement = "travel"`` places every gait's box by the travelling rule (A31), and
``box_size`` / ``box_mass`` replace the box of ``CobraParameters`` (the verdict map over the
paper's unknowns, ``claims_map``); at their defaults (None, "per gait") they add nothing to the key.

An ensemble member's box is placed by the same rule as its nominal run's (for sidewinding, the
nominal run's box-free placement, ``nominal_placement``), then shifted by ``box_shift`` and
turned by ``box_turn`` (``start.placed_state``); its frictions are scaled by ``mu_scale``.
"""

from __future__ import annotations

import functools
import hashlib
import json
import os
import sys
import time
import warnings
from concurrent.futures import FIRST_COMPLETED, wait
from dataclasses import asdict, dataclass, field, replace


from ..provenance import __version__, physics_hash
from ..gaits import gait, gait_params
from ..infra.executors import own_pool, progress_queue
from ..infra.output import write_error
from ..params import CobraParameters
from ..placement import travel_placement
from ..infra.progress import end_line, progress_printer, rewrite
from ..infra.validation import DEFAULT_DT, check
from ..robots import cobra_model
from ..batch import initial_states, simulate_batch
from ..simulate import LeftPhysicsWarning, left_physics, simulate
from ..start import BoxPlacement
from ..step import SimulationError, StepSettings
from ..trajectory import Trajectory
from .cache import read_trajectory, seal_trajectory, verified
from .ensemble import Member

PAPER_GAITS = ("C", "S", "J", "J-mirror", "sidewinding")
PLACEMENTS = ("per gait", "travel")  # the box placement rules: A9 (A31 for sidewinding), or A31 for every gait
# runs advanced together in one task (``batches``; ``cobra_ref.batch``, faster per run in larger batches):
BATCH_SIZE = 16  # on an executor whose workers are not known (a cluster: more tasks than workers)
POOL_BATCH = 48  # at most, on our own pool of known workers (each member holds its log in memory: docs/results.md)


@dataclass(frozen=True)
class RunSpec:
    """One gait run: the gait, its parameters (empty = the defaults of assumption A10), the settings,
    the ensemble member (None: the nominal run, ``ensemble.Member``), and the box: its size [m] and
    mass [kg] (None: ``CobraParameters``'), its placement rule (``PLACEMENTS``, module docstring)."""

    gait: str
    duration: float = 10.0
    dt: float = DEFAULT_DT
    params: dict = field(default_factory=dict, hash=False)
    mu_robot_box: float | None = None
    member: Member | None = None
    box_size: float | None = None
    box_mass: float | None = None
    placement: str = "per gait"

    def __post_init__(self):
        if self.placement not in PLACEMENTS:
            raise ValueError(f"placement = {self.placement!r} is not a placement rule (allowed: "
                             f"{', '.join(PLACEMENTS)})")
        # sidewinding's own rule is the travelling one: one spec (one cache entry) for both names
        if self.gait == "sidewinding":
            object.__setattr__(self, "placement", "per gait")

    @property
    def travels(self) -> bool:
        """Whether the box is placed by the travelling rule (A31): sidewinding, or ``placement = "travel"``."""
        return self.gait == "sidewinding" or self.placement == "travel"

    def reference(self):
        """The gait with ``params``, its ``phase`` shifted by the member's."""
        ref = gait(self.gait, **self.params)
        if self.member is not None and self.member.phase:
            ref = replace(ref, phase=ref.phase + self.member.phase)
        return ref

    def cobra_parameters(self) -> CobraParameters:
        """The model parameters: ``mu_robot_box`` if given, every friction coefficient times the member's ``mu_scale``."""
        p = CobraParameters()
        p = p if self.mu_robot_box is None else replace(p, mu_robot_box=self.mu_robot_box)
        p = p if self.box_size is None else replace(p, box_size=self.box_size)
        p = p if self.box_mass is None else replace(p, box_mass=self.box_mass)
        if self.member is not None and self.member.mu_scale != 1.0:
            p = replace(p, mu=p.mu * self.member.mu_scale, mu_robot_box=p.mu_robot_box * self.member.mu_scale)
        return p

    def key(self) -> str:
        """SHA-256 of every input of the run (module docstring); a nominal member adds nothing to it."""
        h = hashlib.sha256()
        spec = asdict(self)
        if self.member is None or self.member.nominal:
            del spec["member"]
        for name, default in (("box_size", None), ("box_mass", None), ("placement", "per gait")):
            if spec[name] == default:
                del spec[name]
        record = {"spec": spec, "gait": gait_params(self.reference()),
                  "cobra": asdict(self.cobra_parameters()), "settings": asdict(StepSettings(dt=self.dt)),
                  "version": __version__}
        h.update(json.dumps(record, sort_keys=True, default=str).encode())
        h.update(physics_hash().encode())
        # and how a run is set up from its spec (the placement, the members' perturbations)
        here = os.path.dirname(os.path.abspath(__file__))
        for name in ("runs.py", "ensemble.py"):
            with open(os.path.join(here, name), "rb") as f:
                h.update(f.read())
        return h.hexdigest()

    def label(self) -> str:
        """The run's name in progress lines: the gait, ``#i`` for member i, and the box, friction and
        placement where they are not the model's."""
        name = self.gait if self.member is None else f"{self.gait}#{self.member.index}"
        box = [f"{v:g} {unit}" for v, unit in ((self.box_size, "m"), (self.box_mass, "kg")) if v is not None]
        box += [] if self.mu_robot_box is None else [f"mu_rb {self.mu_robot_box:g}"]
        box += [] if self.placement == "per gait" else [f"{self.placement} placement"]
        return name + (f" ({', '.join(box)})" if box else "")

    def filename(self) -> str:
        stem = self.gait if self.member is None else f"{self.gait}-m{self.member.index}"
        return f"{stem}-{self.key()[:16]}.npz"


def run(spec: RunSpec, cache_dir: str, force: bool = False, progress=None) -> tuple[Trajectory, bool]:
    """The trajectory of ``spec``, from the cache when it holds this exact run (unless ``force``),
    else simulated and stored. Returns (trajectory, came_from_cache).

    One gait run of the figure command (module docstring: cache key, box placement).
    """
    if not force:
        cached = load(spec, cache_dir)
        if cached is not None:
            return cached, True
    traj, failed = simulate_spec(spec, progress)
    store(spec, cache_dir, traj, failed)
    return traj, False


def nominal_placement(spec: RunSpec):
    """The travelling gait's box placement (``placement.travel_placement``) of the nominal run of
    ``spec``: its gait parameters and frictions without the member's perturbation, so every member
    starts from the same placement before its own shift and turn.

    ``simulate_spec``; once per process per gait, parameters and dt (a box-free run: no box enters it).
    """
    nominal = replace(spec, member=None)
    return _placement(nominal.gait, json.dumps(nominal.params, sort_keys=True), nominal.dt)


@functools.lru_cache(maxsize=None)
def _placement(gait_name: str, params_json: str, dt: float):
    spec = RunSpec(gait_name, dt=dt, params=json.loads(params_json))
    return travel_placement(cobra_model(spec.cobra_parameters(), with_box=False), spec.reference(), dt)


def simulate_spec(spec: RunSpec, progress=None) -> tuple[Trajectory, bool]:
    """Simulate ``spec`` from its placed and settled start, its member's perturbation applied;
    return (trajectory, failed): a run that fails mid-way returns what it computed, its error set.

    The simulation of ``run``, alone so that any executor can run it (nothing is written).
    """
    model, ref, start, placement = figure_start(spec)
    try:
        traj, failed = simulate(model, ref, spec.duration, StepSettings(dt=spec.dt), *start, progress=progress), False
    except SimulationError as exc:
        if exc.trajectory is None:
            raise
        traj, failed = exc.trajectory, True
    _annotate(traj, spec, ref, placement)
    return traj, failed


def simulate_specs(specs, progress=None) -> list:
    """``simulate_spec`` of each of ``specs`` (one ``batch_key``), their runs advanced together as
    one batch (:mod:`cobra_ref.batch`: each the same steps, bit for bit, as its own run):
    [(trajectory, failed)] in order."""
    models, references, starts, placements = zip(*figure_starts(specs))
    trajectories = simulate_batch(list(models), references, specs[0].duration, StepSettings(dt=specs[0].dt), starts,
                                  progress)
    out = []
    for spec, ref, used, traj in zip(specs, references, placements, trajectories):
        message = left_physics(traj)
        if message:  # as simulate says it
            warnings.warn(message, LeftPhysicsWarning, stacklevel=2)
        _annotate(traj, spec, ref, used)
        out.append((traj, bool(traj.error)))
    return out


def batch_key(spec: RunSpec) -> tuple:
    """What the runs of one batch share (``simulate_specs``): the bodies (box size and mass), dt and duration."""
    return (spec.box_size, spec.box_mass, spec.dt, spec.duration)


def figure_start(spec: RunSpec):
    """(model, reference, (q0, qd0), placement) of ``spec``: its placed and settled start (``simulate_spec``);
    placement is the travelling rule's (``nominal_placement``), None for a box placed by A9."""
    return figure_starts([spec])[0]


def figure_starts(specs) -> list:
    """``figure_start`` of each of ``specs`` (one ``batch_key``), their starts settled together
    (``batch.initial_states``: each member's ``start.initial_state``, bit for bit)."""
    models, references, boxes, placements = zip(*(_figure_setup(spec) for spec in specs))
    return list(zip(models, references, initial_states(models, references, boxes), placements))


def _figure_setup(spec: RunSpec):
    """(model, reference, box placement, travelling placement or None) of ``spec`` (``figure_start``)."""
    placement, member = (nominal_placement(spec) if spec.travels else None), spec.member
    box = BoxPlacement(gap=0.05 if placement is None else placement.box_gap,
                       direction=None if placement is None else placement.direction,
                       shift=None if member is None else member.box_shift, turn=0.0 if member is None else member.box_turn)
    return cobra_model(spec.cobra_parameters(), with_box=True), spec.reference(), box, placement


def _annotate(traj: Trajectory, spec: RunSpec, ref, placement) -> None:
    """The run's inputs in ``traj.meta`` (gait, parameters, cache key, box placement, member)."""
    direction = None if placement is None else placement.direction
    traj.meta.update({"gait": spec.gait, "gait_params": gait_params(ref), "cache_key": spec.key(),
                      "box_direction": None if direction is None else [float(x) for x in direction],
                      "box_gap": None if placement is None else placement.box_gap,
                      "box_reach": None if placement is None else placement.reach,
                      "member": None if spec.member is None else spec.member.as_dict()})


def store(spec: RunSpec, cache_dir: str, traj: Trajectory, failed: bool) -> str:
    """Write ``traj`` to the cache (``<name>.npz``, or ``<name>.failed.npz`` for a failed run), its
    key and content hash in its ``meta`` (``cache.seal_trajectory``); return the path.

    An ``OutputError`` names the file and the reason when it cannot be written (a full disk); the
    entries stored before are kept.
    """
    path = os.path.join(cache_dir, spec.filename())
    out = path[:-4] + ".failed.npz" if failed else path
    try:
        os.makedirs(cache_dir, exist_ok=True)
    except OSError as exc:
        raise write_error(out, "cache entry", exc) from None
    seal_trajectory(traj, spec.key())
    traj.to_npz(out)
    return out


def cached_path(spec: RunSpec, cache_dir: str) -> str | None:
    """The cache file of ``spec`` (complete or failed run), or None.
    """
    path = os.path.join(cache_dir, spec.filename())
    for p in (path, path[:-4] + ".failed.npz"):
        if os.path.isfile(p):
            return p
    return None


def load(spec: RunSpec, cache_dir: str) -> Trajectory | None:
    """The cached run of ``spec`` if the cache holds it whole (``cache.read_trajectory``: its key,
    arrays and content hash), else None; a damaged entry is named on stderr and removed."""
    path = cached_path(spec, cache_dir)
    return None if path is None else verified(path, lambda p: read_trajectory(p, spec.key()))


def _run_in_worker(specs: list, queue=None):
    """Executor entry: simulate a batch of specs (``simulate_specs``), reporting (label, done,
    total) to ``queue`` if given."""
    label = _label(specs)
    report = None if queue is None else (lambda done, total: queue.put((label, done, total)))
    return simulate_specs(specs, report)


def _label(specs) -> str:
    """A batch's name in the progress lines: its first run's label, and how many more it advances."""
    return specs[0].label() + (f" and {len(specs) - 1} more" if len(specs) > 1 else "")


def batch_size(runs: int, workers: int | None) -> int:
    """The largest batch for ``runs`` runs on ``workers`` workers: ``BATCH_SIZE`` where they are
    not known (None, an executor's), else a worker's share of the runs, at most ``POOL_BATCH``."""
    return BATCH_SIZE if not workers else max(1, min(POOL_BATCH, -(-runs // workers)))


def batches(specs, size: int = BATCH_SIZE) -> list:
    """``specs`` in batches of runs that share a ``batch_key``: each key's runs split into the fewest
    batches of at most ``size``, as even as can be, the batches of the most steps first (so that no
    worker is left alone with a long one at the end)."""
    groups: dict = {}
    for spec in specs:
        groups.setdefault(batch_key(spec), []).append(spec)
    out = []
    for group in groups.values():
        n = -(-len(group) // size)
        out += [group[i * len(group) // n:(i + 1) * len(group) // n] for i in range(n)]
    return sorted(out, key=lambda batch: -len(batch) * batch[0].duration)


def run_all(specs, cache_dir: str, force: bool = False, workers: int | None = None,
            progress: bool = True, executor=None) -> dict:
    """Run every spec not in the cache and return {spec: Trajectory}, every trajectory read back
    from the cache (so the results do not depend on where the runs ran).

    The figure command's simulations. ``executor``: any ``concurrent.futures.Executor`` (a process
    pool, ``executors.SerialExecutor``, a Dask client's ``get_executor()``); the runs are simulated
    there and written to ``cache_dir`` here. Default: a process pool with ``executors.worker_init``
    on ``workers`` processes (default: the machine's cores), or this process for a single run or a
    single worker; either advances the runs in ``batches``. Progress on stderr: with a pool, the runs
    done of the total and the time left as each run completes, and each running batch's percentage;
    in this process, each batch's percentage. A run's exception is raised here.
    """
    specs = list(specs)
    check_workers(workers)
    done = {} if force else {s: t for s in dict.fromkeys(specs) if (t := load(s, cache_dir)) is not None}
    todo = [s for s in dict.fromkeys(specs) if s not in done]
    todo.sort(key=lambda s: -s.duration)  # the longest runs first: no core waits alone for one at the end
    stored = []  # the cache files written by this call
    try:
        _run_todo(todo, cache_dir, workers, progress, executor, stored)
    except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: say what was kept (cli.figures)
        exc.kept = {"stored": list(stored), "todo": len(todo), "cache_dir": cache_dir}
        raise
    # the runs just made, read back as every cached one was (a damaged one here is an error, not recomputed)
    done |= {s: read_trajectory(cached_path(s, cache_dir), s.key()) for s in todo}
    return {s: done[s] for s in specs}


def check_workers(workers) -> None:
    """A ``ValidationError`` unless ``workers`` is None (the cores) or a whole number >= 1."""
    if workers is not None:
        check("workers", workers)


def _run_todo(todo, cache_dir: str, workers, progress: bool, executor, stored: list) -> None:
    """Simulate every spec of ``todo`` and store it (``run_all``'s executors), appending each
    cache file written to ``stored``."""
    if not todo:
        return
    workers = workers or min(len(todo), os.cpu_count() or 1)
    if executor is not None:
        _run_on(executor, todo, cache_dir, progress, None, stored)
    elif workers > 1 and len(todo) > 1:
        # the workers and the progress queue's server end at once on an interrupt (executors)
        with progress_queue() as queue, own_pool(min(workers, len(todo))) as pool:
            _run_on(pool, todo, cache_dir, progress, queue, stored, batch_size(len(todo), workers))
    else:  # in this process, in batches as a pool's worker runs them, each stored as its batch ends
        done = 0
        for batch in batches(todo, batch_size(len(todo), 1)):
            label = f"  runs {done + 1}-{done + len(batch)}/{len(todo)} {_label(batch)}"
            for spec, result in zip(batch, simulate_specs(batch, progress_printer(label) if progress else None)):
                stored.append(store(spec, cache_dir, *result))
            done += len(batch)


def _run_on(executor, todo, cache_dir: str, progress: bool, queue, stored: list, size: int = BATCH_SIZE) -> None:
    """Submit every spec of ``todo`` to ``executor`` in ``batches`` of at most ``size`` (one task
    each), store each result as its batch completes, report progress.

    A sidewinding member needs its nominal run's box-free placement run (``nominal_placement``),
    made once in each process that needs it (a few seconds); members go in batches of their own key
    like every other run.
    """
    futures = {executor.submit(_run_in_worker, b, queue): b for b in batches(todo, size)}
    watcher = _Progress(todo, progress, queue)
    pending = set(futures)
    try:
        while pending:
            done, pending = wait(pending, timeout=0.5, return_when=FIRST_COMPLETED)
            for f in done:
                for spec, (traj, failed) in zip(futures[f], f.result()):  # re-raises a run's exception here
                    stored.append(store(spec, cache_dir, traj, failed))
                    watcher.completed(spec)
            watcher.poll()
    except BaseException:
        for f in pending:
            f.cancel()
        raise


class _Progress:
    """Progress of a batch of runs on stderr: a line per completed run (runs done / total, time
    left from the mean time per run so far); with a queue of (label, done, total) step counts,
    the running runs' percentages too, rewritten in place on a terminal, every 10 s otherwise."""

    def __init__(self, specs, progress: bool, queue):
        self.total, self.done, self.progress, self.queue = len(specs), 0, progress, queue
        self.start, self.last, self.tty = time.perf_counter(), 0.0, sys.stderr.isatty()
        self.state = {}  # label: (steps done, steps total) of the running runs

    def _write(self, text: str, newline: bool) -> None:
        if not self.progress:
            return
        if self.tty:  # one line rewritten in place (progress.rewrite), ended after a completed run
            rewrite(text + " ")
            if newline:
                end_line()
        else:
            sys.stderr.write(text + "\n")
            sys.stderr.flush()

    def completed(self, spec) -> None:
        self.done += 1
        self.state.pop(spec.label(), None)
        elapsed = time.perf_counter() - self.start
        left = elapsed / self.done * (self.total - self.done)
        self._write(f"  runs done: {self.done}/{self.total} ({spec.label()}), {elapsed:.0f} s so far, "
                    f"~{left:.0f} s left", True)

    def poll(self) -> None:
        if self.queue is None:
            return
        while not self.queue.empty():
            label, done, total = self.queue.get()
            if done < total:
                self.state[label] = (done, total)
            else:
                self.state.pop(label, None)
        elapsed = time.perf_counter() - self.start
        if self.state and (self.tty or elapsed - self.last >= 10.0):
            self.last = elapsed
            parts = "  ".join(f"{k} {100 * d / t:3.0f}%" for k, (d, t) in self.state.items())
            self._write(f"  running: {parts}  ({self.done}/{self.total} runs done)", not self.tty)
