"""One velocity-level ("non-impulsive") time step of COBRA, the box and the ground.

Implements: [COBRA] eq. (1) discretized over dt, with the contact impulses of eq. (5)-(6)::

    M (u+ - u) = dt (tau - h) + J_c^T p                     # eq. (1), impulses p = f dt
    q+ = q (+) dt u+                                         # kinematics.integrate: semi-implicit Euler

Contacts are persistent and there is no restitution: the QP asks the gap after the step to
stay >= 0, g + dt g'+ >= 0, with a penetration g < 0 removed at the rate beta g / dt.

Servo (notes C7; Eq. (6) constraints (2)-(3)):

* ``"prescribed"`` (default, Simscape's "motion provided"): the 11 joints follow the
  reference exactly. The joint velocity over the step is the secant
  u+_a = (q_ref(t + dt) - q_a) / dt, so q_a(t + dt) = q_ref(t + dt) to rounding; only the
  base and the box (12 DoF) are free, and the joint torques are recovered afterwards from
  eq. (1) with the contact impulses: tau = M (u+ - u) / dt + h - J_c^T p / dt.
  Torque limits are reported per step (``tau_excess``), never clipped silently.
* ``"pd"``: tau = clip(K_p (q_ref - q) + K_d (qd_ref - qd), -tau_max, tau_max): saturation
  enforced, joint-limit excursions reported per step (``q_excess``).
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np
from scipy.linalg import get_lapack_funcs

from .contacts import ROBOT_BOX, Contacts, contact_jacobian, find_contacts
from .contact_qp import ContactQP, QPInfo
from .chain import ChainModel
from ..quaternion import quat_exp, quat_mul
from ..model import Model


# the phases of a step, timed for ``cobra-ref bench``
PHASES = ("dynamics", "contacts", "qp", "rest")


class SimulationError(RuntimeError):
    """A simulation that cannot go on; ``trajectory`` (if set) holds what was computed."""

    def __init__(self, message: str, trajectory=None):
        super().__init__(message)
        self.trajectory = trajectory


@dataclass(frozen=True)
class StepSettings:
    """Settings of the time stepper (defaults: notes C14-C15 and the module docstring)."""

    dt: float = 1e-3
    servo: str = "prescribed"
    kp: float = 100.0  # PD servo only [N m / rad] (notes C7)
    kd: float = 2.0  # PD servo only [N m s / rad]
    n_facets: int = 4
    friction: str = "fixed-point"  # or "convex" (contact_qp module docstring)
    reg: float = 1e-6
    fp_max: int = 10  # friction fixed-point iterates per step (warm-started; contact_qp docstring)
    fp_path: str = "active-set"  # or "osqp": OSQP for every iterate, the reference (contact_qp.ContactQP)
    osqp: str = "every-step"  # or "fallback": OSQP only where no certified answer is found (contact_qp.ContactQP)
    margin: float = 0.01  # candidate contacts within 10 mm
    beta: float = 0.2  # fraction of a penetration removed per step
    max_start_penetration: float = 0.005

    def __post_init__(self):
        if not (np.isfinite(self.dt) and self.dt > 0):
            raise ValueError(f"dt must be positive and finite, got {self.dt}")
        if self.servo not in ("prescribed", "pd"):
            raise ValueError(f"servo must be 'prescribed' or 'pd', got {self.servo!r}")


class StepResult(NamedTuple):
    q: np.ndarray  # configuration after the step
    qd: np.ndarray  # velocity after the step
    tau: np.ndarray  # (11,) joint torques over the step
    contacts: Contacts  # candidates at the start of the step
    p: np.ndarray  # (3m,) impulses in the contact frames
    w: np.ndarray  # (3m,) contact velocities after the step (J_c u+)
    qp: QPInfo
    kinetic: float  # kinetic energy at the start of the step
    potential: float  # potential energy at the start of the step
    work_actuators: float  # dt tau . u_mid over the joints, u_mid = (u + u+) / 2
    work_contacts: float  # p . J_c u_mid: work of the contact impulses (<= 0: dissipated)


class Stepper:
    """Advances (q, qd) by one step for a given joint reference (see the module docstring)."""

    def __init__(self, model: Model, settings: StepSettings = StepSettings()):
        self.model, self.s = model, settings
        self.chain = ChainModel(model)
        self.qp = ContactQP(model.mu, settings.n_facets, settings.reg, friction=settings.friction,
                            fp_max=settings.fp_max, fp_path=settings.fp_path, osqp=settings.osqp)
        # actuated = revolute joints (one dof each); a model may have none (a lone ball or box)
        revolute = [i for i, jt in enumerate(model.joint_type) if jt != "free"]
        self.act = np.array([model.v_idx[i].start for i in revolute], dtype=int)
        self.act_q = np.array([model.q_idx[i].start for i in revolute], dtype=int)
        self.tau_max = np.array([model.tau_limit[i] for i in revolute], dtype=float)
        self.q_max = np.array([model.q_limit[i] for i in revolute], dtype=float)
        prescribed = settings.servo == "prescribed"
        self.free = np.setdiff1d(np.arange(model.nv), self.act) if prescribed else np.arange(model.nv)
        self.prescribed = np.setdiff1d(np.arange(model.nv), self.free)
        # warm starts: (contact key -> row, rows of [p_N, p_t1, p_t2, OSQP duals]); the last row is
        # all zeros, the start of a new contact
        self._no_warm = ({}, np.zeros((1, 3 + self.qp.rows_per_contact)))
        self._warm = self._no_warm
        self._hint: dict = {}
        self.timing = dict.fromkeys(PHASES, 0.0)  # seconds spent in each phase, summed over steps

    def step(self, q: np.ndarray, qd: np.ndarray, t: float, reference, tau_ext=None) -> StepResult:
        """One step from (q, qd) at time t; ``tau_ext`` (nv,): an optional generalized external
        force held over the step (a hand pushing a body; zero by default), added to tau in eq. (1)."""
        s, model, dt = self.s, self.model, self.s.dt
        clock = [time.perf_counter()]
        terms = self.chain.terms(q, qd)
        M, h = terms.M, terms.h
        # Step 1: actuation -- prescribed joint velocities, or PD torques
        tau = np.zeros(model.nv)
        qd_next = qd.copy()
        if s.servo == "prescribed":
            q_ref_next = _finite(reference(t + dt)[0], t + dt)
            qd_next[self.act] = (q_ref_next - q[self.act_q]) / dt
        else:
            q_ref, qd_ref, _ = reference(t)
            _finite(np.concatenate([q_ref, qd_ref]), t)
            tau_pd = s.kp * (q_ref - q[self.act_q]) + s.kd * (qd_ref - qd[self.act])
            tau[self.act] = np.clip(tau_pd, -self.tau_max, self.tau_max)
        # Step 2: eq. (1) without contact for the free coordinates F
        tau_ext = np.zeros(model.nv) if tau_ext is None else np.asarray(tau_ext, dtype=float)
        F, P = self.free, self.prescribed
        M_F = M[F]
        rhs = dt * (tau[F] + tau_ext[F] - h[F]) - M_F[:, P] @ (qd_next[P] - qd[P])
        L = _cholesky(M_F[:, F])
        qd_next[F] = qd[F] + _potrs(L, rhs, lower=1)[0]
        clock.append(time.perf_counter())
        # Step 3: contacts, J_c (eq. 3-4), Delassus G and free velocity c (eq. 5)
        contacts = find_contacts(model, terms, s.margin, self._hint)
        J = contact_jacobian(self.chain, terms, contacts)
        # G = J_F M_FF^-1 J_F^T = B^T B with B = L^-1 J_F^T (M_FF = L L^T)
        B = _trtrs(L, J[:, F].T, lower=1)[0]
        Minv_JT = _trtrs(L, B, lower=1, trans=1)[0]
        G = B.T @ B
        c = J @ qd_next
        g_stab = np.where(contacts.g >= 0, contacts.g, s.beta * contacts.g)
        c[0::3] += g_stab / dt
        clock.append(time.perf_counter())
        # Step 4: least action, eq. (6)
        keys = contacts.keys()
        p_warm, y_warm = self._warm_start(keys)
        p, info = self.qp.solve(G, c, p_warm, mu=self._mu(contacts), y_warm=y_warm, G_factor=B.T)
        clock.append(time.perf_counter())
        qd_next[F] += Minv_JT @ p
        w = J @ qd_next
        # Step 5: joint torques from eq. (1) with the contact impulses (prescribed servo)
        if s.servo == "prescribed":
            tau = M @ (qd_next - qd) / dt + h - J.T @ p / dt - tau_ext
        self._remember(keys, p, w, contacts)
        # energy bookkeeping at the midpoint velocity: Delta KE = u_mid . M (u+ - u) exactly
        u_mid = 0.5 * (qd + qd_next)
        work_actuators = dt * float(tau[self.act] @ u_mid[self.act])
        work_contacts = float(p @ (J @ u_mid))
        kinetic = 0.5 * qd @ M @ qd
        potential = self._potential(terms)
        q_next = self._integrate(q, qd_next)
        clock.append(time.perf_counter())
        for phase, t0, t1 in zip(PHASES, clock[:-1], clock[1:]):
            self.timing[phase] += t1 - t0
        return StepResult(q_next, qd_next, tau[self.act], contacts, p, w, info, kinetic, potential,
                          work_actuators, work_contacts)

    def _mu(self, contacts: Contacts) -> np.ndarray:
        """Friction coefficient per contact: model.mu, or model.mu_robot_box for robot-box pairs."""
        return np.where(contacts.kind == ROBOT_BOX, self.model.mu_rb, self.model.mu)

    def _warm_start(self, keys):
        """This step's starting impulses and OSQP duals: the previous step's, contact by contact
        (zero for a new contact: the last remembered row)."""
        if not keys:
            return None, None
        index, rows = self._warm
        picked = rows[[index.get(k, -1) for k in keys]]
        return picked[:, :3].ravel(), self.qp.duals_stacked(picked[:, 3:])

    def _remember(self, keys, p, w, contacts):
        """Warm starts and the sliding directions for the next step's contact frames."""
        if not keys:
            self._warm, self._hint = self._no_warm, {}
            return
        rows = np.concatenate([p.reshape(-1, 3), self.qp.duals_per_contact(self.qp.y, len(keys))], axis=1)
        self._warm = (dict(zip(keys, range(len(keys)))), np.concatenate([rows, self._no_warm[1]]))
        # sliding velocity w_T = t1 w_t1 + t2 w_t2 (world) of the contacts that slip faster than 1 mm/s
        w_T = contacts.frame[:, :, 1:] @ w.reshape(-1, 3)[:, 1:, None]
        sliding = np.flatnonzero((w_T * w_T).sum(axis=(1, 2)) > 1e-12)
        self._hint = {keys[i]: w_T[i, :, 0] for i in sliding.tolist()}

    def _potential(self, terms) -> float:
        return float(-self.chain.mass @ (terms.com @ self.model.gravity))

    def _integrate(self, q: np.ndarray, u: np.ndarray) -> np.ndarray:
        """q (+) dt u: :func:`cobra_ref.kinematics.integrate` (the reference, equal to 1e-15 in
        tests/test_stepper_physics.py) with the revolute joints in one vector operation."""
        dt, chain = self.s.dt, self.chain
        q_next = q.copy()
        q_next[chain.rev_q] += dt * u[chain.rev_v]
        for _, iq, iv in chain.free:
            q_next[iq:iq + 3] += dt * u[iv:iv + 3]
            quat = quat_mul(q[iq + 3:iq + 7], quat_exp(dt * u[iv + 3:iv + 6]))
            q_next[iq + 3:iq + 7] = quat / np.linalg.norm(quat)
        return q_next

    def reset(self):
        self._warm, self._hint = self._no_warm, {}
        self.timing = dict.fromkeys(PHASES, 0.0)


def _finite(values: np.ndarray, t: float) -> np.ndarray:
    """The reference's values, or a SimulationError naming the time they stop being finite."""
    values = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(values)):
        raise SimulationError(f"the joint reference is not finite at t = {t:.4f} s: {values}")
    return values


# LAPACK's Cholesky factor and solves, called directly (scipy.linalg's wrappers cost more
# than the 12 x 12 solves themselves)
_potrf, _potrs, _trtrs = get_lapack_funcs(("potrf", "potrs", "trtrs"), (np.zeros(1),))


def _cholesky(A: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor L of a symmetric positive definite A = L L^T."""
    L, info = _potrf(A, lower=1, clean=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"the mass matrix of the free coordinates is not positive definite (info {info})")
    return L
