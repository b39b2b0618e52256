"""MuJoCo as the plant of the push planner: the plan predicted with cobra_ref, executed in MuJoCo.

The planner (:func:`cobra_ref.planning.receding.push`) advances its plant one period at a time and
reads its state back (q, qd: MuJoCo's qpos and qvel are cobra_ref's coordinates, A19). This plant
runs :func:`cobra_ref.mjcf.to_mjcf` of the same model at MuJoCo's stable timestep (``mjcf.TIMESTEP``,
0.05 ms, A27), its position actuators driven by the plan's reference at each of its steps
(``mujoco_check.servo_control``: our servo law), and records the state every ``dt`` (1 ms). What
MuJoCo does not report as our contact solve does (impacts, the contact log, the solver's residuals)
is recorded as zero and named so in the run's meta. MuJoCo is deterministic: the same plan on
the same start gives the same run.
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import numpy as np

from ..mjcf import TIMESTEP, to_mjcf
from ..step import SimulationError
from ..trajectory import CONTACT_KEYS, STEP_KEYS, Trajectory
from .mujoco_check import _check_layout, _import_mujoco, servo_control


class MujocoPlant:
    """The planner's plant in MuJoCo (module docstring): ``q``, ``qd``, ``t``, ``settings``,
    ``advance(reference, n_steps)`` (steps of ``settings.dt``) and ``finish(error)``."""

    def __init__(self, model, settings, q0, qd0, capacity: int, timestep: float = TIMESTEP):
        mujoco = _import_mujoco()
        self.mujoco, self.model, self.settings, self.timestep = mujoco, model, settings, timestep
        self.m = mujoco.MjModel.from_xml_string(to_mjcf(model, timestep))
        self.d = mujoco.MjData(self.m)
        _check_layout(model, self.m)
        self.d.qpos[:], self.d.qvel[:] = model.check_q(q0), model.check_qd(qd0)
        self.per_step = max(1, int(round(settings.dt / timestep)))
        self.q_log = np.zeros((capacity + 1, model.nq))
        self.qd_log = np.zeros((capacity + 1, model.nv))
        self.tau = np.zeros((capacity, self.m.nu))
        self.q_log[0], self.qd_log[0] = self.d.qpos, self.d.qvel
        self.k, self.wall_time = 0, 0.0
        self.stepping = SimpleNamespace(memory=None)  # no stepper memory to hand to the rollouts

    @property
    def q(self) -> np.ndarray:
        return self.d.qpos.copy()

    @property
    def qd(self) -> np.ndarray:
        return self.d.qvel.copy()

    @property
    def t(self) -> float:
        """The time [s] the run has reached."""
        return self.k * self.settings.dt

    def advance(self, reference, n_steps: int, progress=None) -> None:
        """``n_steps`` steps of ``settings.dt``, each ``per_step`` MuJoCo steps with ctrl from the
        reference at each one's start; a ``SimulationError`` when the state leaves the finite."""
        start = time.perf_counter()
        try:
            for _ in range(n_steps):
                t0 = self.k * self.settings.dt
                for j in range(self.per_step):
                    q_ref, qd_ref, _ = reference(t0 + j * self.timestep)
                    self.d.ctrl[:] = servo_control(self.model, q_ref, qd_ref)
                    self.mujoco.mj_step(self.m, self.d)
                if not (np.isfinite(self.d.qpos).all() and np.isfinite(self.d.qvel).all()):
                    raise SimulationError(f"MuJoCo's state is not finite at t = {t0 + self.settings.dt:.4f} s",
                                          self.finish("non-finite state"))
                self.tau[self.k] = self.d.actuator_force
                self.k += 1
                self.q_log[self.k], self.qd_log[self.k] = self.d.qpos, self.d.qvel
        finally:
            self.wall_time += time.perf_counter() - start

    def finish(self, error: str = "") -> Trajectory:
        """The run so far as a ``Trajectory`` (module docstring: what MuJoCo does not report is zero)."""
        n, model = self.k, self.model
        box = model.q_idx[model.boxes[0].body]
        steps = {key: np.zeros(n) for key in STEP_KEYS}
        steps["fp_converged"] = np.ones(n)
        contacts = {key: np.zeros((0, 3) if key in ("contact_point", "contact_normal", "contact_force") else 0)
                    for key in CONTACT_KEYS}
        meta = {"plant": "mujoco", "timestep": self.timestep, "not_reported": "impacts, the contact log and the "
                "contact solve's residuals (zero here): MuJoCo does not report them as cobra_ref's step does"}
        return Trajectory(self.settings.dt, np.arange(n + 1) * self.settings.dt, self.q_log[:n + 1].copy(),
                          self.qd_log[:n + 1].copy(), self.tau[:n].copy(), self.q_log[:n + 1, box].copy(), steps,
                          contacts, self.wall_time, error, meta)
