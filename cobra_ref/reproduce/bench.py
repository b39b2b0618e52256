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
* ``mujoco_us_per_step`` -- MuJoCo on the exported MJCF of the same model, its position
  actuators tracking the same reference from the same start, per dt of simulated time at its own
  stable timestep (0.1 ms, A27), over the same simulated time; and ``ratio_vs_mujoco``.

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
        "mujoco_us_per_step": None,
        "ratio_vs_mujoco": None,
        "machine": f"{platform.processor() or platform.machine()}, Python {platform.python_version()}",
    }
    if with_mujoco:
        mj_us = mujoco_us_per_step(model, reference, q0, n, dt)
        if mj_us is not None:
            record["mujoco_us_per_step"] = round(mj_us, 2)
            record["ratio_vs_mujoco"] = round(record["us_per_step"] / mj_us, 1)
    return record


def mujoco_us_per_step(model, reference, q0, n_steps: int, dt: float) -> float | None:
    """MuJoCo's wall time [us] per ``dt`` of simulated time on the exported model, or None without mujoco.

    The benchmark (cobra-ref bench). MuJoCo runs at its own stable timestep (``mjcf.TIMESTEP``, 0.1
    ms: it integrates the stiff contact explicitly, A27), so one of our steps of dt is dt / TIMESTEP
    of its steps; its position actuators track the same reference (``mujoco_check.servo_control``).
    """
    try:
        import mujoco
    except ImportError:
        return None
    from ..mjcf import TIMESTEP, to_mjcf
    from .mujoco_check import servo_control

    m = mujoco.MjModel.from_xml_string(to_mjcf(model, timestep=TIMESTEP))
    d = mujoco.MjData(m)
    d.qpos[:] = q0
    mujoco.mj_forward(m, d)
    per_step = max(1, int(round(dt / TIMESTEP)))
    # the controls sampled beforehand (the reference at each step's start), so only mj_step is timed
    ctrl = [servo_control(model, *reference(k * TIMESTEP)[:2]) for k in range(n_steps * per_step)]
    start = time.perf_counter()
    for u in ctrl:
        d.ctrl[:] = u
        mujoco.mj_step(m, d)
    return (time.perf_counter() - start) / n_steps * 1e6


def format_table(record: dict) -> str:
    """The benchmark record as a small text table.
    """
    lines = [f"{record['model']}, {record['steps']} steps",
             f"{'fast stepper (default)':<28}{record['us_per_step']:>10.1f} us/step   real-time factor "
             f"{record['real_time_factor']}" + (f"   {record['ratio_vs_mujoco']} x MuJoCo"
                                                  if record["ratio_vs_mujoco"] is not None else "")]
    for k, v in record["breakdown_us"].items():
        lines.append(f"  {k:<26}{v:>10.1f} us/step")
    lines.append(f"  (mean {record['mean_contacts']} contacts, {record['fixed_point_iterates_per_step']} friction "
                 f"fixed-point iterates, {record['qp_solves_per_step']} OSQP solves per step)")
    lines.append(f"{'reference step (readable)':<28}{record['reference_us_per_step']:>10.1f} us/step "
                 f"(first {REFERENCE_STEPS} steps)")
    if record["mujoco_us_per_step"] is not None:
        lines.append(f"{'MuJoCo (same MJCF, 0.1 ms)':<28}{record['mujoco_us_per_step']:>10.2f} us per 1 ms simulated")
    else:
        lines.append("MuJoCo: not installed (pip install mujoco), no comparison")
    return "\n".join(lines)
