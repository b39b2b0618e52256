"""The fast stepper: the reference step of :mod:`cobra_ref.step`, with batched parts and warm starts.

For performance: ``FastStepper.step`` takes the same step as :func:`cobra_ref.step.step`,
block for block, with the same least-action problem, friction loop and step result
(:func:`cobra_ref.step.least_action_problem`, :func:`cobra_ref.least_action.solve_least_action`,
:func:`cobra_ref.step.step_result`); only the parts are faster:

* M, h, poses and Jacobians from the world-frame chain recursion (:mod:`cobra_ref.fast.chain`);
* the contact search and J_c in batches (:mod:`cobra_ref.fast.contacts`);
* G from one Cholesky factor of M_FF (LAPACK, called directly);
* the box QPs by certified active-set solves, OSQP warm and solving the first QP of every step
  (:mod:`cobra_ref.fast.least_action`); a step whose fixed point they leave unconverged is solved
  again by the reference step's loop (OSQP on every iterate);
* the configuration update as one vector operation on the joints;
* the servo's reference at the step's start read from the last step's end when the times agree.

Every part is tested equal to the readable one, and tests step both side by side. The time
each phase of a step spends in this stepper's code is summed in ``timing`` (``cobra-ref bench``;
in a batched step the parts done for all members are the batch's ``batched_seconds``).
"""

from __future__ import annotations

import time
from typing import NamedTuple

import numpy as np
from scipy.linalg import get_lapack_funcs

from ..least_action import solve_least_action
from ..model import Model
from ..quaternion import quat_exp, quat_mul
from ..step import (StepResult, StepSettings, StepSystem, _reference, joint_coordinates, least_action_problem,
                    midpoint_velocity, servo_start, step_result, warm_start)
from .chain import ChainModel
from .contacts import contact_jacobian, find_contacts
from .least_action import FastBoxQP

# the phases of a step, timed for ``cobra-ref bench``
PHASES = ("dynamics", "contacts", "qp", "rest")

# LAPACK's Cholesky factor and triangular solves, called directly (scipy.linalg's wrappers cost
# more than the 12 x 12 to 23 x 23 solves themselves)
_potrf, _potrs, _trtrs = get_lapack_funcs(("potrf", "potrs", "trtrs"), (np.zeros(1),))


class Prepared(NamedTuple):
    """A step prepared by ``FastStepper.prepare`` for ``FastStepper.finish``."""

    system: StepSystem  # the step's terms, rows and least-action problem
    x_start: np.ndarray  # where its friction loop starts: the warm start


class Rows(NamedTuple):
    """A step's terms and rows from ``FastStepper.rows``, before its least-action problem."""

    system: StepSystem  # steps 1-5 but the problem (None)
    problem_args: tuple  # (c_free, contacts, settings, servo start, w_start): least_action_problem's after G


class FastStepper:
    """Advances (q, qd) by one step (module docstring); keeps the warm start between steps."""

    name = "fast"

    def __init__(self, model: Model, settings: StepSettings = StepSettings()):
        self.model, self.settings = model, settings
        self.chain = ChainModel(model)
        self.joints = joint_coordinates(model)
        servo = settings.joint_servo
        # the free coordinates F and the prescribed P; with none prescribed F selects every row as a
        # view (slice), so the step indexes M, h and J by F without copying them
        free = servo.free(model.nv, self.joints)
        self.free = slice(None) if len(free) == model.nv else free
        self.prescribed = np.setdiff1d(np.arange(model.nv), free)
        self.servo_J = servo.jacobian(model.nv, self.joints)
        self.qp = FastBoxQP()
        self.memory = None
        self.reference_end = None  # (reference, t + dt, (q_ref, qd_ref)) of the last step
        self.timing = dict.fromkeys(PHASES, 0.0)

    def reset(self) -> None:
        """Forget the warm start and the timing: between runs on one stepper."""
        self.memory = self.reference_end = None
        self.timing = dict.fromkeys(PHASES, 0.0)

    def _start_reference(self, reference, t: float):
        """(q_ref, qd_ref) at the step's start t: the last step's end reference when it was taken
        from the same reference at exactly t, else evaluated (the same values either way)."""
        last = self.reference_end
        if last is not None and last[0] is reference and last[1] == t:
            return last[2]
        return _reference(reference, t)[:2]

    def step(self, q: np.ndarray, qd: np.ndarray, t: float, reference, tau_ext=None, terms=None,
             contacts=None, J_c=None) -> StepResult:
        """One step from (q, qd) at time t: :func:`cobra_ref.step.step`, faster (module docstring).

        ``terms``: this step's chain terms at (q, ``step.midpoint_velocity(qd, self.memory)``), and
        ``contacts`` with their Jacobian ``J_c``, if they were computed already (the batched engine,
        :mod:`cobra_ref.fast.batch`)."""
        return self.finish(self.prepare(q, qd, t, reference, tau_ext, terms, contacts, J_c))

    def prepare(self, q, qd, t: float, reference, tau_ext=None, terms=None, contacts=None, J_c=None) -> Prepared:
        """Steps 1-5 of ``step`` (same arguments): the least-action problem of the step and where its
        solve starts, with what ``finish`` needs."""
        return self.pose(self.rows(q, qd, t, reference, tau_ext, terms, contacts, J_c))

    def rows(self, q, qd, t: float, reference, tau_ext=None, terms=None, contacts=None, J_c=None) -> Rows:
        """Steps 1-4 and the rows of step 5 (``prepare``'s arguments): everything but the least-action
        problem, and what ``step.least_action_problem`` writes it from."""
        s, model, F, P = self.settings, self.model, self.free, self.prescribed
        dt, servo = s.dt, s.joint_servo
        start = time.perf_counter()
        tau_ext = np.zeros(self.chain.nv) if tau_ext is None else np.asarray(tau_ext, dtype=float)
        # Steps 1-3: eq. (1) with h at the midpoint velocity, the joints, qd_free over the free coordinates
        if terms is None:
            terms = self.chain.terms(q, midpoint_velocity(qd, self.memory))
        M, h = terms.M, terms.h
        qd_next = qd.copy()
        q_ref, qd_ref, _ = _reference(reference, t + dt)  # the joints' reference at the end of the step
        servo_ref = self._start_reference(reference, t) if servo.reads_start else None
        self.reference_end = (reference, t + dt, (q_ref, qd_ref))
        servo.prescribe(qd_next, q, q_ref, self.joints, dt)
        M_F = M[F]
        L = _cholesky(M_F[:, F])
        rhs = dt * (tau_ext - h)[F] - M_F[:, P] @ (qd_next[P] - qd[P])
        qd_next[F] = qd[F] + _potrs(L, rhs, lower=1)[0]
        dynamics = time.perf_counter()
        self.timing["dynamics"] += dynamics - start
        # Steps 4-5: contacts, J_c, the rows J over F, G = B^T B with B = L^-1 J_F^T
        if contacts is None:
            contacts = find_contacts(model, terms, s.margin)
            J_c = contact_jacobian(self.chain, terms, contacts)
        J = np.concatenate([J_c, self.servo_J])
        B = _trtrs(L, J[:, F].T, lower=1)[0]
        Minv_JT = _trtrs(L, B, lower=1, trans=1)[0]
        G = B.T @ B
        potential = float(-self.chain.mass @ (terms.com @ model.gravity))
        system = StepSystem(q, qd, M, h, tau_ext, qd_next, F, Minv_JT, contacts, J_c, G, None, self.joints, q_ref,
                            potential)
        rows = Rows(system, (J @ qd_next, contacts, s, servo_start(self.joints, q, qd, servo_ref), J_c[0::3] @ qd))
        self.timing["contacts"] += time.perf_counter() - dynamics
        return rows

    def pose(self, rows: Rows) -> Prepared:
        """The step of ``rows`` prepared with its least-action problem (``step.least_action_problem``)."""
        start = time.perf_counter()
        problem = least_action_problem(self.model, rows.system.G, *rows.problem_args)
        self.timing["contacts"] += time.perf_counter() - start
        return self.posed(rows, problem)

    def posed(self, rows: Rows, problem) -> Prepared:
        """The step of ``rows`` prepared with its least-action ``problem`` (``prepare``'s end)."""
        start = time.perf_counter()
        system = rows.system._replace(problem=problem)
        x_start = warm_start(system.contacts, self.memory, len(problem.c))
        self.timing["contacts"] += time.perf_counter() - start
        return Prepared(system, x_start)

    def finish(self, prepared: Prepared, solved=None, residuals=None) -> StepResult:
        """Steps 6-7 of ``step`` from ``prepare``'s problem: the impulses, then the step's result.
        ``solved``: (x, info) of ``least_action.solve_least_action(problem, x_start, self.qp)``, and
        ``residuals``: ``least_action.kkt_residuals(problem, x)`` of a converged x, if the batched
        step computed them."""
        system, x_start = prepared
        problem = system.problem
        start = time.perf_counter()
        # Step 6: eq. (6); where the certified solves leave the fixed point unconverged (their exact
        # active sets can send Newton's guess elsewhere than OSQP's answers do), the reference step's
        # loop, OSQP on every iterate, solves it again from the same start
        if solved is None:
            self.qp.new_step()
            solved = solve_least_action(problem, x_start, self.qp)
        x, info = solved
        if not info.converged:
            residuals = None  # of the x solved again below, not of the one given
            x, again = solve_least_action(problem, x_start)
            info = again._replace(iterations=info.iterations + again.iterations,
                                  qp_iterations=info.qp_iterations + again.qp_iterations,
                                  qp_solves=info.qp_solves + again.qp_solves)
        solved_at = time.perf_counter()
        # Step 7: velocity, torques, energy ledger, position (the reference step's step_result)
        result = step_result(self.model, system, x, info, self.settings, self._integrate, residuals)
        self.memory = result.memory
        self.timing["qp"] += solved_at - start
        self.timing["rest"] += time.perf_counter() - solved_at
        return result

    def _integrate(self, q: np.ndarray, qd: np.ndarray) -> np.ndarray:
        """q (+) dt qd: :func:`cobra_ref.kinematics.integrate` with the revolute joints in one vector operation."""
        dt, chain = self.settings.dt, self.chain
        q_next = q.copy()
        q_next[chain.rev_q] += dt * qd[chain.rev_v]
        for _, iq, iv in chain.free:
            q_next[iq:iq + 3] += dt * qd[iv:iv + 3]
            quat = quat_mul(q[iq + 3:iq + 7], quat_exp(dt * qd[iv + 3:iv + 6]))
            q_next[iq + 3:iq + 7] = quat / np.sqrt(quat.dot(quat))  # np.linalg.norm's own sum, without its checks
        return q_next


def _cholesky(A: np.ndarray) -> np.ndarray:
    """Lower Cholesky factor L of a symmetric positive definite A = L L^T."""
    L, info = _potrf(A, lower=1, clean=1)
    if info != 0:
        raise np.linalg.LinAlgError(f"the mass matrix of the free coordinates is not positive definite (info {info})")
    return L
