"""``cobra-ref bench``: time per step of the full COBRA + box model, against MuJoCo.

Helper: a benchmark, not a test. It simulates the built-in rolling reference with the box
(the ``cobra-ref simulate`` defaults) for ``duration`` seconds at dt, and reports:

* ``us_per_step`` -- wall time per step [us] and ``real_time_factor`` = simulated / wall time;
* ``breakdown_us`` -- per step: ``dynamics`` (poses, M, h, the contact-free velocity),
  ``contacts`` (gap functions, J_c, Delassus G and c), ``qp`` (the OSQP least-action solve with
  its friction fixed point), ``rest`` (torques, energy ledger, integration);
* ``mujoco_us_per_step`` -- MuJoCo's ``mj_step`` on the exported MJCF of the same model, same
  dt, its position actuators tracking the same reference from the same initial state (soft
  contact, pyramidal cone, default solver), timed over the same number of steps; and
  ``ratio_vs_mujoco`` = us_per_step / mujoco_us_per_step;
* ``osqp_fallback`` -- the same numbers (and ``osqp_solves_per_step``) for the run with
  ``StepSettings(osqp="fallback")``, where OSQP solves only the steps that the certified
  active-set path cannot (contact_qp.ContactQP); the main keys are the default, OSQP every step.

One core: the loop is single-threaded Python + OSQP; MuJoCo runs single-threaded too.
"""

from __future__ import annotations

import platform
import time

import numpy as np

from ..gaits import RollingGait
from ..robots import cobra_model
from ..simulate import initial_state, simulate
from ..fast.stepper import PHASES, StepSettings


def run_bench(duration: float = 2.0, dt: float = 1e-3, with_mujoco: bool = True, progress=None) -> dict:
    """Time the rolling push; return the benchmark record (see the module docstring).

    Helper: the benchmark (cobra-ref bench).
    """
    model = cobra_model()
    reference = RollingGait()
    q0, qd0 = initial_state(model, reference)
    runs = {}
    for osqp in ("every-step", "fallback"):
        traj = simulate(model, reference, duration, StepSettings(dt=dt, osqp=osqp), q0, qd0, progress=progress)
        n = len(traj.tau)
        runs[osqp] = {
            "us_per_step": round(traj.wall_time / n * 1e6, 1),
            "real_time_factor": round(traj.duration / traj.wall_time, 4),
            "breakdown_us": {k: round(traj.meta["phase_seconds"][k] / n * 1e6, 1) for k in PHASES},
            "osqp_solves_per_step": round(float(np.mean(traj.steps["osqp_solves"])), 3),
            "mean_contacts": round(float(np.mean(traj.steps["n_contacts"])), 2),
            "mean_fixed_point_iterates": round(float(np.mean(traj.steps["fp_iter"])), 2),
            "ratio_vs_mujoco": None,
        }
    fallback = runs.pop("fallback")
    record = {
        "model": f"COBRA + box, nq = {model.nq}, nv = {model.nv}, built-in rolling, dt = {dt}",
        "steps": n,
        **runs["every-step"],
        "mujoco_us_per_step": None,
        "osqp_fallback": fallback,
        "machine": f"{platform.processor() or platform.machine()}, Python {platform.python_version()}",
    }
    if with_mujoco:
        mj_us = mujoco_us_per_step(model, reference, q0, n, dt)
        if mj_us is not None:
            record["mujoco_us_per_step"] = round(mj_us, 2)
            for r in (record, fallback):
                r["ratio_vs_mujoco"] = round(r["us_per_step"] / mj_us, 1)
    return record


def mujoco_us_per_step(model, reference, q0, n_steps: int, dt: float) -> float | None:
    """MuJoCo's wall time per mj_step [us] on the exported model, or None without mujoco.

    Helper: the benchmark (cobra-ref bench).
    """
    try:
        import mujoco
    except ImportError:
        return None
    from ..mjcf import to_mjcf

    m = mujoco.MjModel.from_xml_string(to_mjcf(model, timestep=dt))
    d = mujoco.MjData(m)
    d.qpos[:] = q0
    mujoco.mj_forward(m, d)
    # the reference sampled beforehand, so only mj_step is timed
    ctrl = np.array([reference(k * dt)[0] for k in range(n_steps)])
    start = time.perf_counter()
    for k in range(n_steps):
        d.ctrl[:] = ctrl[k]
        mujoco.mj_step(m, d)
    return (time.perf_counter() - start) / n_steps * 1e6


def format_table(record: dict) -> str:
    """The benchmark record as a small text table.

    Helper: the benchmark (cobra-ref bench).
    """
    lines = [f"{record['model']}, {record['steps']} steps"]
    for name, r in (("OSQP every step (default)", record), ("osqp='fallback'", record["osqp_fallback"])):
        lines.append(f"{name:<28}{r['us_per_step']:>10.1f} us/step   real-time factor {r['real_time_factor']}"
                     + (f"   {r['ratio_vs_mujoco']} x MuJoCo" if r["ratio_vs_mujoco"] is not None else ""))
        for k, v in r["breakdown_us"].items():
            lines.append(f"  {k:<26}{v:>10.1f} us/step")
        lines.append(f"  (mean {r['mean_contacts']} contacts, {r['mean_fixed_point_iterates']} friction "
                     f"fixed-point iterates, {r['osqp_solves_per_step']} OSQP solves per step)")
    if record["mujoco_us_per_step"] is not None:
        lines.append(f"{'MuJoCo mj_step (same MJCF)':<28}{record['mujoco_us_per_step']:>10.2f} us/step")
    else:
        lines.append("MuJoCo: not installed (pip install mujoco), no comparison")
    return "\n".join(lines)
