"""One time step of COBRA, the box and the ground, built from the textbook parts: the reference step.

Implements: [COBRA] eq. (1)-(6) over one step dt, at the velocity level (semi-implicit Euler)::

    M (qd+ - qd) = dt (tau_ext - h) + J^T x            eq. (1), impulses x = f dt of the rows J
    q+ = q (+) dt qd+                                  kinematics.integrate

``step`` reads top to bottom:

1. eq. (1): M = crba(q) and h = C(q, w) w + g(q) = rnea(q, w, 0) (:mod:`cobra_ref.dynamics`), the
   velocity-product terms at the step's midpoint velocity w, extrapolated from the last step
   (``midpoint_velocity``);
2. the joints (``StepSettings.joint_servo``, :mod:`cobra_ref.compliance`): the position servo,
   the paper's position-controlled joints: every coordinate is free and each joint gets a servo
   row towards the reference at the step's start, its impulse bounded by tau_max dt; or the
   prescribed joints (Simscape's "motion provided"): each joint's qd+ is the secant to the
   reference, (q_ref(t + dt) - q) / dt, and only the base and the box are free (F); the torques
   are recovered from eq. (1);
3. eq. (1) without impulses: qd_free over the free coordinates;
4. eq. (2)-(4): the contacts and their Jacobian J_c (:mod:`cobra_ref.contact`);
5. eq. (5): the rows J = [J_c; J_servo] over F, the Delassus matrix G and c, with each row's
   compliance and offset from its law (``StepSettings.law``: compliant or rigid);
6. eq. (6): the impulses x, Coulomb's friction by a fixed point of OSQP solves
   (:mod:`cobra_ref.least_action`), started from the previous step's impulses;
7. qd+ = qd_free + M_FF^-1 J^T x, the joint torques, and q+ (``step_result``).

The faster path :class:`cobra_ref.fast.stepper.FastStepper` takes the same step with batched
dynamics and contacts and certified QP solves, and builds its result with the same
``step_result``; tests run both side by side (:mod:`cobra_ref.steppers` names them).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .compliance import CONTACT_LAWS, JOINT_SERVOS, LAWS, SERVOS
from .contact import BOX_GROUND, ROBOT_BOX, ROBOT_GROUND, Contacts, contact_jacobian, find_contacts
from .dynamics import bias_force, crba, potential_energy
from .infra import arguments
from .infra.validation import DEFAULT_DT, RULES, check_choice
from .kinematics import forward_kinematics, integrate
from .least_action import LeastAction, LeastActionInfo, delassus, kkt_residuals, solve_least_action
from .model import JOINT_NV, Model


# A33: a compliant touch-down lasts a few steps of 1 ms and is sub-stepped in two; a rigid one is
# a velocity jump within one step whatever its size, so the rigid law takes whole steps
TOUCHDOWN_SUBSTEPS = {"compliant": 2, "rigid": 1}


class SimulationError(RuntimeError):
    """A simulation that cannot go on; ``trajectory`` (if set) holds what was computed."""

    def __init__(self, message: str, trajectory=None):
        super().__init__(message)
        self.trajectory = trajectory


@dataclass(frozen=True)
class StepSettings:
    """How a step is taken: time step, contact law, joint servo, contact search margin.

    ``dt`` [s] (assumption A14; default ``DEFAULT_DT``); ``contact``: ``"compliant"`` (the
    paper's high-fidelity spring-damper contact, A12-A13) or ``"rigid"`` (eq. (2)-(6) as written,
    A15); ``servo``: ``"position"`` (the paper's position-controlled joints, A7) or
    ``"prescribed"``; ``margin`` [m]: candidate contacts are those with a gap below it;
    ``touchdown_substeps``: n > 1 takes the steps around a contact's touch-down as n steps of
    dt / n (A33, :mod:`cobra_ref.touchdown`; the steppers of ``steppers.make_stepper`` and the
    batched engine); None (the default) is the law's own, ``TOUCHDOWN_SUBSTEPS``, and ``substeps``
    the n a stepper takes. The step reads the law and the servo as objects, ``law`` and
    ``joint_servo``, resolved from the names.
    """

    dt: float = DEFAULT_DT
    contact: str = "compliant"
    servo: str = "position"
    margin: float = 0.01
    touchdown_substeps: int | None = None

    def __post_init__(self):
        """Check every setting by its rule (:mod:`cobra_ref.infra.validation`): dt within
        [DT_MIN, DT_MAX] (A14), a known contact law and servo, a margin in [0, 1] m, a whole number
        of touch-down substeps in [1, 16]; a
        ``ValidationError`` (a ValueError) names the field, the value and the allowed range; a value
        that is not a number is an ``infra.arguments.ArgumentTypeError`` (a TypeError)."""
        arguments.number("dt", self.dt, RULES["dt"])
        check_choice("contact", self.contact, LAWS)
        check_choice("servo", self.servo, SERVOS)
        arguments.number("margin", self.margin, RULES["margin"])
        if self.touchdown_substeps is not None:
            arguments.number("touchdown_substeps", self.touchdown_substeps, RULES["touchdown_substeps"])

    @property
    def substeps(self) -> int:
        """The touch-down substeps n a stepper takes: ``touchdown_substeps``, or the law's
        (``TOUCHDOWN_SUBSTEPS``, A33) where it is None."""
        if self.touchdown_substeps is None:
            return TOUCHDOWN_SUBSTEPS[self.contact]
        return self.touchdown_substeps

    @property
    def law(self):
        """The contact law object of ``contact`` (:data:`cobra_ref.compliance.CONTACT_LAWS`)."""
        return CONTACT_LAWS[self.contact]

    @property
    def joint_servo(self):
        """The joint servo object of ``servo`` (:data:`cobra_ref.compliance.JOINT_SERVOS`)."""
        return JOINT_SERVOS[self.servo]


class StepResult(NamedTuple):
    """Everything one step computed (the state after it, and what the records need); built by
    ``step_result``."""

    q: np.ndarray  # configuration after the step
    qd: np.ndarray  # velocity after the step
    tau: np.ndarray  # (n_joints,) joint torques over the step [N m]
    contacts: Contacts  # the candidates at the start of the step
    p: np.ndarray  # (3m,) contact impulses in the contact frames [N s]
    w: np.ndarray  # (3m,) contact velocities after the step, J_c qd+ [m/s]
    info: LeastActionInfo
    residuals: dict  # kkt_residuals of the impulses
    approach: np.ndarray  # (m,) normal approach speed of each contact before the step, max(0, -J_N qd) [m/s]
    G_NN: np.ndarray  # (m,) the Delassus matrix's normal diagonal [1/kg]: 1 / G_NN is the mass the contact sees
    kinetic: float  # kinetic energy at the start of the step [J]
    potential: float  # gravitational potential energy at the start of the step [J]
    elastic: float  # energy stored in compressed compliant contacts at the start of the step [J]
    work_actuators: float  # dt tau . qd_mid over the joints, qd_mid = (qd + qd+) / 2 [J]
    work_contacts: float  # x_c . J_c qd_mid: work of the contact impulses [J]
    q_ref: np.ndarray  # (n_joints,) the joints' reference at the end of the step [rad]
    memory: dict  # where the next step's friction fixed point starts (warm_start_memory)
    substeps: int = 1  # the steps of dt / substeps it was taken in (A33, touchdown.merged; 1: whole)


class JointCoordinates(NamedTuple):
    """Where the revolute joints sit in q and qd, and their limits."""

    q: np.ndarray  # (n,) indices into q
    v: np.ndarray  # (n,) indices into qd
    tau_max: np.ndarray  # (n,) [N m]
    q_max: np.ndarray  # (n,) [rad]
    qd_max: np.ndarray  # (n,) [rad/s] (inf: none)


class ServoStart(NamedTuple):
    """The joints at the step's start, from which the position servo's rows are written."""

    joints: JointCoordinates
    q: np.ndarray  # (n,) joint angles [rad]
    qd: np.ndarray  # (n,) joint rates [rad/s]
    reference: tuple | None  # (q_ref, qd_ref) at the step's start; None where the servo reads none


def servo_start(joints: JointCoordinates, q, qd, reference) -> ServoStart:
    """The ``ServoStart`` of the configuration q and velocity qd with the reference (q_ref, qd_ref) or None."""
    return ServoStart(joints, q[joints.q], qd[joints.v], reference)


class StepSystem(NamedTuple):
    """What steps 1-5 of a step computed: eq. (1) without impulses and the rows' least-action problem."""

    q: np.ndarray  # configuration at the step's start
    qd: np.ndarray  # velocity at the step's start
    M: np.ndarray  # (nv, nv) mass matrix
    h: np.ndarray  # (nv,) bias force at the midpoint velocity
    tau_ext: np.ndarray  # (nv,) generalized force held over the step
    qd_free: np.ndarray  # (nv,) velocity after the step without impulses (prescribed joints at their secant)
    F: np.ndarray | slice  # the free coordinates
    Minv_JT: np.ndarray  # (|F|, rows) M_FF^-1 J_F^T
    contacts: Contacts
    J_c: np.ndarray  # (3m, nv) contact Jacobian
    G: np.ndarray  # (rows, rows) Delassus matrix
    problem: LeastAction
    joints: JointCoordinates
    q_ref: np.ndarray  # (n_joints,) the joints' reference at the end of the step
    potential: float  # gravitational potential energy at the step's start [J]


def step(model: Model, q, qd, t: float, reference, settings: StepSettings = StepSettings(),
         previous: dict | None = None, tau_ext=None) -> StepResult:
    """One step from (q, qd) at time t with the joint reference ``reference(t) -> (q, qd, qdd)``.

    Implements: [COBRA] eq. (1)-(6) over one step (module docstring, steps 1-7). ``previous``:
    where the friction fixed point starts (``StepResult.memory`` of the last step; None: from
    zero); ``tau_ext`` (nv,): a generalized force held over the step (default none).
    """
    dt, joints, servo = settings.dt, joint_coordinates(model), settings.joint_servo
    tau_ext = np.zeros(model.nv) if tau_ext is None else np.asarray(tau_ext, dtype=float)
    q_ref, qd_ref, _ = _reference(reference, t + dt)  # the joints' reference at the end of the step
    servo_ref = _reference(reference, t)[:2] if servo.reads_start else None  # ... and at its start
    # Step 1: eq. (1), M(q) and h(q, qd)
    kin = forward_kinematics(model, q)
    M, h = crba(model, q), bias_force(model, q, midpoint_velocity(qd, previous))
    # Step 2: the joints -- free coordinates F; prescribed joints move to their reference
    qd_next = qd.copy()
    servo.prescribe(qd_next, q, q_ref, joints, dt)
    F = servo.free(model.nv, joints)
    P = np.setdiff1d(np.arange(model.nv), F)
    # Step 3: eq. (1) without impulses for the free coordinates: M_FF (qd_free - qd)_F = rhs
    rhs = dt * (tau_ext - h)[F] - M[np.ix_(F, P)] @ (qd_next[P] - qd[P])
    qd_next[F] = qd[F] + np.linalg.solve(M[np.ix_(F, F)], rhs)
    # Step 4: eq. (2)-(4), the contacts and J_c
    contacts = find_contacts(model, q, settings.margin, kin)
    J_c = contact_jacobian(model, q, contacts, kin)
    # Step 5: eq. (5), the rows J over F, the Delassus matrix G and the least-action problem
    J = np.vstack([J_c, servo.jacobian(model.nv, joints)])
    G, Minv_JT = delassus(J[:, F], M[np.ix_(F, F)])
    problem = least_action_problem(model, G, J @ qd_next, contacts, settings, servo_start(joints, q, qd, servo_ref),
                                   J_c[0::3] @ qd)
    system = StepSystem(q, qd, M, h, tau_ext, qd_next, F, Minv_JT, contacts, J_c, G, problem, joints, q_ref,
                        potential_energy(model, q))
    # Step 6: eq. (6), the impulses, starting from the previous step's
    x, info = solve_least_action(problem, warm_start(contacts, previous, len(problem.c)))
    # Step 7: the velocity after the step, the joint torques, the position
    return step_result(model, system, x, info, settings, lambda q0, qd1: integrate(model, q0, qd1, dt))


def step_result(model: Model, system: StepSystem, x: np.ndarray, info: LeastActionInfo, settings: StepSettings,
                integrate_step, residuals: dict | None = None) -> StepResult:
    """Step 7 of a step (module docstring) from the impulses x of its ``system``: the one place a
    ``StepResult`` is built, by both steppers.

    Implements: [COBRA] eq. (1) with the impulses, qd+ = qd_free + M_FF^-1 J^T x, the joint torques
    (``StepSettings.joint_servo``), the energy ledger (``energies``) and q+ =
    ``integrate_step(q, qd+)``. ``residuals``: ``kkt_residuals(system.problem, x)`` if computed already.
    """
    s, m, dt = system, system.contacts.m, settings.dt
    qd_next = s.qd_free.copy()
    qd_next[s.F] += s.Minv_JT @ x
    p = x[:3 * m]

    def recovered():  # eq. (1) solved for the joints' generalized forces
        return (s.M @ (qd_next - s.qd) / dt + s.h - s.J_c.T @ p / dt - s.tau_ext)[s.joints.v]

    tau = settings.joint_servo.torque(x[3 * m:], dt, recovered)
    return StepResult(q=integrate_step(s.q, qd_next), qd=qd_next, tau=tau, contacts=s.contacts, p=p,
                      w=s.J_c @ qd_next, info=info,
                      residuals=kkt_residuals(s.problem, x) if residuals is None else residuals,
                      approach=approach_speed(s.J_c, s.qd), G_NN=s.G.diagonal()[:3 * m:3],
                      **energies(model, s, qd_next, p, tau, settings), q_ref=s.q_ref,
                      memory=warm_start_memory(s.contacts, x, s.qd))


def joint_coordinates(model: Model) -> JointCoordinates:
    """The actuated (revolute) joints of the model, which the servo drives (a model may have none:
    a lone ball or box): their q and qd indices and limits."""
    revolute = [i for i, jt in enumerate(model.joint_type) if JOINT_NV[jt] == 1]  # one rate: Rx, Ry or Rz
    qd_limit = model.qd_limit or (np.inf,) * model.nb
    return JointCoordinates(np.array([model.q_idx[i].start for i in revolute], dtype=int),
                            np.array([model.v_idx[i].start for i in revolute], dtype=int),
                            np.array([model.tau_limit[i] for i in revolute], dtype=float),
                            np.array([model.q_limit[i] for i in revolute], dtype=float),
                            np.array([qd_limit[i] for i in revolute], dtype=float))


def least_action_problem(model: Model, G, c_free, contacts: Contacts, settings: StepSettings,
                         start: ServoStart, w_start) -> LeastAction:
    """The least-action problem of eq. (6): H = G + R and c = J qd_free + b over the rows.

    Implements: [COBRA] eq. (5)-(6) with each row's compliance R and offset b
    (:mod:`cobra_ref.compliance`): contact normals and friction under ``settings.law``, then the
    rows of ``settings.joint_servo`` (the position servo's, from ``start``: the joints' state and
    reference at the step's start), bounded by tau_max dt. ``w_start`` (m,): the contacts' normal
    rates J_N qd before the step, which the compliant law's damper reads below dt = d / k.
    """
    m, dt, law = contacts.m, settings.dt, settings.law
    d = G.diagonal()
    R_N, b_N = law.normal_rows(model, contacts.g, d[0:3 * m:3], dt, w_start)
    R, b = np.zeros(len(d)), np.zeros(len(d))
    R[0:3 * m:3], b[0:3 * m:3] = R_N, b_N
    R[1:3 * m:3] = law.tangential_compliance(d[1:3 * m:3])
    R[2:3 * m:3] = law.tangential_compliance(d[2:3 * m:3])
    R[3 * m:], b[3 * m:], lo, hi = settings.joint_servo.rows(model, start, d[3 * m:], dt)
    # each contact's coefficient of friction, looked up by its kind
    mu_of_kind = np.empty(3)
    mu_of_kind[[ROBOT_GROUND, ROBOT_BOX, BOX_GROUND]] = model.mu, model.mu_rb, model.mu_bg
    mu = mu_of_kind[contacts.kind]
    return LeastAction(G + np.diag(R), c_free + b, mu, lo, hi, law.stiction_velocity(model))


def warm_start(contacts: Contacts, previous: dict | None, n: int) -> np.ndarray:
    """x (n,) where the friction fixed point starts: each row's impulse in the previous step.

    ``previous`` (``warm_start_memory``) maps a contact key to its world impulse vector,
    read in this step's contact frame; a new contact starts at 0; the servo rows start at the
    previous step's servo impulses.
    """
    x = np.zeros(n)
    if not previous:
        return x
    for i, key in enumerate(contacts.keys()):
        if key in previous["contacts"]:
            x[3 * i:3 * i + 3] = contacts.frame[i].T @ previous["contacts"][key]
    servo = previous["servo"]
    if len(servo) == n - 3 * contacts.m:
        x[3 * contacts.m:] = servo
    return x


def warm_start_memory(contacts: Contacts, x: np.ndarray, qd: np.ndarray) -> dict:
    """What the next step reads: the world impulse vector (3,) of each contact that carried one,
    by contact key, and the servo rows' impulses (``warm_start``), and this step's starting
    velocity qd (``midpoint_velocity``): the memory of the step from one step to the next.
    """
    m = contacts.m
    P = np.einsum("kij,kj->ki", contacts.frame, x[:3 * m].reshape(m, 3))
    loaded = (x[0:3 * m:3] > 0.0).tolist()  # the contacts with a normal impulse
    return {"contacts": {key: P[i] for i, (key, on) in enumerate(zip(contacts.keys(), loaded)) if on},
            "servo": x[3 * m:].copy(), "qd": np.array(qd, dtype=float)}


def midpoint_velocity(qd: np.ndarray, previous: dict | None) -> np.ndarray:
    """w = qd + (qd - qd_prev) / 2: the step's midpoint velocity, extrapolated linearly from the
    last step's change of velocity (qd itself on a first step).

    Implements: where the velocity-product terms C(q, qd) qd of eq. (1) (Coriolis, centripetal,
    gyroscopic) are evaluated. For one tumbling rigid body their energy error is then second order
    in dt (at qd it is first order; ``tests/test_stepper_physics.py``), and so is the jointed
    chain's, with M(q) at the step's start, when a run's velocities are read as the step reads them:
    qd as the velocity half a step back (q+ = q + dt qd+), so a start at qd0 - dt qdd0 / 2
    (docs/results.md, "The chain in free flight"). w is linear in the velocities, so mirrored runs
    stay mirrored; gravity does not depend on the velocity.
    """
    qd_prev = None if not previous else previous.get("qd")
    if qd_prev is None or np.shape(qd_prev) != np.shape(qd):
        return qd
    return qd + 0.5 * (qd - qd_prev)


IMPACT_SPEED = 0.01  # [m/s] a contact that starts carrying load while approaching faster is an impact (A26)


def approach_speed(J_c: np.ndarray, qd) -> np.ndarray:
    """(m,) normal approach speed of each contact before the step, max(0, -J_N qd) [m/s].

    Implements: the gap rate g' = J_c qd of [COBRA] eq. (4) on the normal rows, where it is
    negative (closing): the paper's non-impulsive condition asks for no contact force while it is.
    """
    return np.maximum(-(J_c[0::3] @ qd), 0.0)


def energies(model: Model, system: StepSystem, qd_next, p, tau, settings: StepSettings) -> dict:
    """{kinetic, potential, elastic, work_actuators, work_contacts} of one step (StepResult): the
    energy ledger, at the midpoint velocity qd_mid = (qd + qd+) / 2, for which
    Delta KE = qd_mid . M (qd+ - qd) exactly at fixed M.

    The bodies' balance is W_act + W_contact = Delta (KE + PE). The elastic energy is
    sum 1/2 k g^2 over the compressed contacts (g < 0) of the compliant law
    (``settings.law.elastic_energy``), so the contacts dissipate -W_contact - Delta E_elastic.
    """
    s = system
    qd_mid = 0.5 * (s.qd + qd_next)
    return {"kinetic": 0.5 * float(s.qd @ s.M @ s.qd), "potential": s.potential,
            "elastic": settings.law.elastic_energy(model, s.contacts.g),
            "work_actuators": settings.dt * float(tau @ qd_mid[s.joints.v]),
            "work_contacts": float(p @ (s.J_c @ qd_mid))}


def _reference(reference, t: float):
    """The reference at t, or a SimulationError naming the time where it stops being finite."""
    values = [np.asarray(v, dtype=float) for v in reference(t)]
    if not all(np.isfinite(v).all() for v in values):
        raise SimulationError(f"the joint reference is not finite at t = {t:.4f} s: {values[0]}")
    return values
