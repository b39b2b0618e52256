"""``cobra-ref bench``: time per step of the full COBRA + box model, broken down, against MuJoCo.

A benchmark, not a test. It simulates the built-in C rolling with the box (the ``cobra-ref
simulate`` defaults: compliant contact, position servo) for ``duration`` seconds at dt, from the
settled start, and reports:

* ``us_per_step`` -- the fast stepper's wall time per step [us] and ``real_time_factor`` =
  simulated / wall time;
* ``breakdown_us`` -- per step: ``dynamics`` (poses, M, h, the free velocity), ``contacts``
  (gap functions, J_c, G and the least-action problem), ``qp`` (the least-action solve with its
  friction loop), ``rest`` (torques, residuals, energy ledger, integration);
* ``qp_solves_per_step`` and ``fixed_point_iterates_per_step``;
* ``reference_us_per_step`` -- the readable reference step (:func:`cobra_ref.step.step`) over
  the first ``REFERENCE_STEPS`` steps of the same run (it is for reading, not for speed);
* ``batched_us_per_member_step`` -- {K: wall time per member per step [us]} of the batched
  engine (:mod:`cobra_ref.batch`) advancing K copies of the same start and reference for
  ``BATCH_STEPS`` steps (the run's steps if fewer), K in ``BATCH_SIZES``; ``batched_ratio_same_dt``: each over MuJoCo's time per
  step at our dt;
* ``mujoco`` -- MuJoCo on the exported MJCF of the same model, its position actuators tracking
  the same reference from the same start over the same simulated time, at three timesteps:

  - ``same_dt``: one ``mj_step`` of dt per step of ours, the per-step comparison
    (``ratio_same_dt`` = ``us_per_step`` / its time per step). At dt = 1 ms MuJoCo's explicit
    stiff contact is not accurate (A27): the record says where its box ended (``box_travel_m``);
  - ``tenth_ms``: 0.1 ms (``TENTH_MS``), timed per dt of simulated time: stable for the box, but
    its explicit contact damper still errs by a few per cent on a 1 kg contact (A27);
  - ``accurate``: the export's own timestep (``mjcf.TIMESTEP``, 0.05 ms), timed per dt of
    simulated time: the accuracy-matched comparison (``ratio_accurate``; both simulators then
    agree within the like-for-like check's tolerances, docs/mujoco.md).

  ``mujoco_us_per_step`` and ``ratio_vs_mujoco`` repeat the accurate pair; ``mujoco_skipped``
  says that the comparison was not asked for (``--no-mujoco``), as against MuJoCo missing.

One core: the loop is single-threaded Python + OSQP; MuJoCo runs single-threaded too.
"""

from __future__ import annotations

import platform
import time

import numpy as np

from ..gaits import RollingGait
from ..infra.validation import DEFAULT_DT
from ..robots import cobra_model
from ..simulate import simulate
from ..start import initial_state
from ..step import StepSettings
from ..fast.stepper import PHASES

REFERENCE_STEPS = 100
BATCH_SIZES = (1, 4, 16, 64)  # the batched engine's sizes K that are timed
BATCH_STEPS = 200  # the steps each batch takes
TENTH_MS = 1e-4  # [s] MuJoCo's second timed timestep (module docstring)


def run_bench(duration: float = 2.0, dt: float = DEFAULT_DT, with_mujoco: bool = True, progress=None) -> dict:
    """Time the rolling push; return the benchmark record (see the module docstring).
    """
    model, reference, settings = cobra_model(), RollingGait(), StepSettings(dt=dt)
    q0, qd0 = initial_state(model, reference, settings)
    traj = simulate(model, reference, duration, settings, q0, qd0, progress=progress)
    n = len(traj.tau)
    short = simulate(model, reference, REFERENCE_STEPS * dt, settings, q0, qd0, stepper="reference")
    record = {
        "model": f"COBRA + box, nq = {model.nq}, nv = {model.nv}, built-in C rolling, dt = {dt}, "
                 f"{settings.contact} contact, {settings.servo} servo",
        "steps": n,
        "us_per_step": round(traj.wall_time / n * 1e6, 1),
        "real_time_factor": round(traj.duration / traj.wall_time, 4),
        "breakdown_us": {k: round(traj.meta["phase_seconds"][k] / n * 1e6, 1) for k in PHASES},
        "qp_solves_per_step": round(float(np.mean(traj.steps["qp_solves"])), 3),
        "fixed_point_iterates_per_step": round(float(np.mean(traj.steps["fp_iter"])), 3),
        "mean_contacts": round(float(np.mean(traj.steps["n_contacts"])), 2),
        "reference_us_per_step": round(short.wall_time / len(short.tau) * 1e6, 1),
        "batched_us_per_member_step": batched_us(model, reference, settings, q0, qd0, n_steps=min(n, BATCH_STEPS)),
        "batched_ratio_same_dt": None,
        "mujoco": None,
        "mujoco_skipped": not with_mujoco,
        "mujoco_us_per_step": None,
        "ratio_vs_mujoco": None,
        "machine": f"{platform.processor() or platform.machine()}, Python {platform.python_version()}",
    }
    if with_mujoco:
        record["mujoco"] = mujoco_side_by_side(model, reference, q0, n, dt, record["us_per_step"])
        if record["mujoco"] is not None:
            same = record["mujoco"]["same_dt"]["us_per_step"]
            record["batched_ratio_same_dt"] = {K: round(us / same, 1)
                                               for K, us in record["batched_us_per_member_step"].items()}
            accurate = record["mujoco"]["accurate"]
            record["mujoco_us_per_step"], record["ratio_vs_mujoco"] = accurate["us_per_step"], accurate["ratio"]
    return record


def batched_us(model, reference, settings, q0, qd0, sizes=BATCH_SIZES, n_steps: int = BATCH_STEPS) -> dict:
    """{K: wall time [us] per member per step} of ``fast.batch.BatchRun`` with K copies of the start
    (q0, qd0) and ``reference``, ``n_steps`` steps each (module docstring)."""
    from ..batch import BatchRun

    out = {}
    for K in sizes:
        run = BatchRun(model, settings, [(q0, qd0)] * K, n_steps)
        run.advance([reference] * K, n_steps)
        out[K] = round(run.wall_time / (K * n_steps) * 1e6, 1)
    return out


def mujoco_side_by_side(model, reference, q0, n_steps: int, dt: float, ours_us: float) -> dict | None:
    """{"same_dt", "tenth_ms", "accurate"}: MuJoCo at our dt, at 0.1 ms and at the export's timestep,
    each with its time per step of ours [us], our ratio to it and the box's travel [m]; None without
    mujoco (module docstring)."""
    from ..mjcf import TIMESTEP

    out = {}
    for name, timestep in (("same_dt", dt), ("tenth_ms", TENTH_MS), ("accurate", TIMESTEP)):
        timed = mujoco_us_per_step(model, reference, q0, n_steps, dt, timestep)
        if timed is None:
            return None
        us, travel = timed
        out[name] = {"timestep_s": timestep, "us_per_step": round(us, 2), "ratio": round(ours_us / us, 1),
                     "box_travel_m": round(travel, 4)}
    return out


def mujoco_us_per_step(model, reference, q0, n_steps: int, dt: float, timestep: float):
    """(MuJoCo's wall time [us] per ``dt`` of simulated time, the box's travel [m]) on the exported
    model at ``timestep``, or None without mujoco.

    The benchmark (cobra-ref bench). One of our steps of dt is dt / timestep of MuJoCo's steps; its
    position actuators track the same reference (``mujoco_check.servo_control``).
    """
    try:
        import mujoco
    except ImportError:
        return None
    from ..mjcf import to_mjcf
    from .mujoco_check import servo_control

    m = mujoco.MjModel.from_xml_string(to_mjcf(model, timestep=timestep))
    d = mujoco.MjData(m)
    d.qpos[:] = q0
    mujoco.mj_forward(m, d)
    per_step = max(1, int(round(dt / timestep)))
    # the controls sampled beforehand (the reference at each step's start), so only mj_step is timed
    ctrl = [servo_control(model, *reference(k * timestep)[:2]) for k in range(n_steps * per_step)]
    start = time.perf_counter()
    for u in ctrl:
        d.ctrl[:] = u
        mujoco.mj_step(m, d)
    elapsed = time.perf_counter() - start
    box = model.q_idx[model.boxes[0].body].start
    travel = float(np.linalg.norm(d.qpos[box:box + 3] - q0[box:box + 3]))
    return elapsed / n_steps * 1e6, travel


def format_table(record: dict) -> str:
    """The benchmark record as a small text table.
    """
    lines = [f"{record['model']}, {record['steps']} steps",
             f"{'fast stepper (default)':<28}{record['us_per_step']:>10.1f} us/step   real-time factor "
             f"{record['real_time_factor']}"]
    for k, v in record["breakdown_us"].items():
        lines.append(f"  {k:<26}{v:>10.1f} us/step")
    lines.append(f"  (mean {record['mean_contacts']} contacts, {record['fixed_point_iterates_per_step']} friction "
                 f"fixed-point iterates, {record['qp_solves_per_step']} OSQP solves per step)")
    lines.append(f"{'reference step (readable)':<28}{record['reference_us_per_step']:>10.1f} us/step "
                 f"(first {REFERENCE_STEPS} steps)")
    ratios = record["batched_ratio_same_dt"] or {}
    for K, us in record["batched_us_per_member_step"].items():
        ratio = f"   = {ratios[K]} x MuJoCo at the same dt" if K in ratios else ""
        lines.append(f"{f'batched, K = {K}':<28}{us:>10.1f} us per member-step{ratio}")
    if record["mujoco"] is not None:
        for name, what in (("same_dt", "the per-step comparison"), ("tenth_ms", "at 0.1 ms"),
                           ("accurate", "accuracy-matched")):
            mj = record["mujoco"][name]
            label = f"MuJoCo at {mj['timestep_s'] * 1e3:g} ms"
            lines.append(f"{label:<28}{mj['us_per_step']:>10.2f} us per step of ours   fast = {mj['ratio']} x "
                         f"({what}; its box moved {mj['box_travel_m']:g} m)")
    else:
        lines.append("MuJoCo: skipped (--no-mujoco)" if record.get("mujoco_skipped") else
                     "MuJoCo: not installed (pip install mujoco), no comparison")
    return "\n".join(lines)
