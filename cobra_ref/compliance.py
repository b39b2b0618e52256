"""How much each row of the least-action problem gives way: the contact law and the joint servo.

Implements: the laws of the paper's "high-fidelity" model ([COBRA] sec. "Simulation Setup"):
spring-damper normal contact, smooth stick-slip friction and position-controlled joints whose
torque is bounded by tau_max, each written over one step, in the velocity after it, as a
*compliance* R >= 0 and an *offset* b of one row of the least-action problem of eq. (6)::

    min_x 1/2 x^T (G + R) x + x^T (J qd_free + b)        (x: impulses of the rows)

Its optimality condition on an unconstrained row is w + R x + b = 0, with w = J qd+ the row's
velocity after the step. That is the law of a spring-damper acting on the row's coordinate e
(the gap, or a joint's error from its reference) with a target rate v_ref, the damper on the
velocity after the step and the spring at the point e + theta dt w of the step::

    f = -k (e + theta dt w) - d (w - v_ref),    x = f dt
    =>  w + R x + b = 0,   R = 1 / (dt (theta k dt + d)),   b = (k e - d v_ref) / (theta k dt + d)

(``spring_damper``). theta = 1 evaluates the spring at the step's end (backward Euler), which
adds a numerical damping theta k dt to d; theta = 0 at its start (the symplectic Euler of the
spring), which adds none. Stiff limits: k, d -> infinity with d / k -> 0 gives R -> 0 and
b -> e / dt at theta = 1: the row is then rigid, its coordinate reaches e = 0 in one step.

How implicit the contact spring is (``contact_theta``): theta = max(0, 1 - d / (k dt)). On a
contact whose mass m_c = 1 / G_ii is small (m_c / d << dt), the step maps the gap to
g+ = g (1 - k dt / (d + theta k dt)): with this theta the factor is 1 - k dt / d in [0, 1) for
dt <= d / k (the paper's k and d: dt <= 1 ms), and 0 above, so the gap never overshoots, and the
damping the step adds, theta k dt = max(0, k dt - d), is none at dt <= d / k and at most as
much as is needed above. For every mass the step is stable at every dt: the spring-damper's
map (g, w) -> (g+, w+) has its eigenvalues inside the unit circle when
k dt^2 (1 - 2 theta) < 4 m_c + 2 d dt, which this theta meets (tests/test_compliance.py).

The servo rows (``servo_rows``) are the same spring-damper on a joint's error, written so that
the step tracks a reference to second order in dt. The position update q+ = q + dt qd+ makes qd+
the velocity at the step's midpoint (the staggered, leapfrog reading of the step), so a force
centred on the step's start is second order: the spring acts on the error at the step's start,
e = q - q_ref(t) (theta from ``contact_theta(kp, kd, dt)``: 0 for dt <= kd / kp = 10 ms), and the
damper on the mean rate theta_d qd+ + (1 - theta_d) qd against qd_ref(t), with
theta_d = max(1/2, 1 - I / (kd dt)) (``servo_theta``; I = 1 / G_ii, the inertia the joint's row
sees). theta_d = 1/2 is the trapezoidal damper; on a light joint (I < kd dt / 2: the head's and
the tail's at 1 ms) the damper leans towards qd+ just as far as keeps the step from flipping the
error's sign, the servo's counterpart of the contact's rule. As dt -> 0 every joint has
theta_d -> 1/2 and theta -> 0, and on one servoed joint tracking a sine the error falls by four
per halving of dt (tests/test_servo.py). One joint's step is stable for every I at every dt: the
map of (e, dt qd) has its eigenvalues inside the unit circle when
kp dt^2 (1 - 2 theta) < 4 I + 2 (2 theta_d - 1) kd dt, which these thetas meet.

The rows (assumption ids refer to ``docs/assumptions.md``), each law and servo an object that
``StepSettings`` resolves once from its name (``CONTACT_LAWS``, ``JOINT_SERVOS``):

* contact normal, ``CompliantLaw`` (A12): the unilateral spring-damper of Simscape's and MuJoCo's
  contact, f = max(0, -k g - d g') while the contact penetrates (g < 0) and no force while it is
  apart (k = ``model.contact_stiffness``, d = ``model.contact_damping``). A step from t takes the
  force's impulse over the window [t - (1 - theta_d) dt, t + theta_d dt], on which the gap is
  piecewise linear: g + (s - t) w_0 before t and g + (s - t) w after it (positions at the step's
  ends, velocities between them: the staggered reading of q+ = q + dt qd+; w_0 = J_N qd is the
  rate before the step). The spring's impulse is -k (g + theta dt w) dt on a contact that
  penetrates at t (g <= 0; theta = ``contact_theta``), and the damper's is exactly -d times the
  change of the gap over the window's penetrating part::

      penetrating through the window:   -d dt (theta_d w + (1 - theta_d) w_0)
      touching within it (g_0 > 0):     -d (g + theta_d dt w),   g_0 = g - (1 - theta_d) dt w_0

  A contact apart at t (g > 0; a candidate within the search margin) that closes within the step
  gets that damper's impulse alone: the spring's, of order k dt^2 |w|, is second order and waits
  for the next step, which starts penetrating. So it carries no force while the gap at the
  window's end, g + theta_d dt w, stays positive (no force across a gap), and the law is
  continuous at touch-down (both rows give x = -theta_d d dt w as g -> 0).

  How far the window leans back (``contact_theta_d``): theta_d = 1 / (1 - exp(-h)) - 1 / h,
  h = d dt / m_c, m_c = 1 / G_ii the mass the contact's row sees. It is the weight with which the
  damper's step, x = -d dt (theta_d w + (1 - theta_d) w_0) on a free mass m_c, decays the rate by
  (1 - (1 - theta_d) h) / (1 + theta_d h) = exp(-h) per step, exactly as the damper does
  (exponential fitting). As dt -> 0, theta_d = 1/2 + h / 12 + O(h^3): the window is centred on t,
  the spring at t and the damper on the mean rate are the leapfrog's, and since the lean h / 12
  multiplies w - w_0 = O(dt) the step stays second order and converges to the unilateral
  spring-damper's ODE (tests/test_contact_ode.py; the measured errors are in docs/results.md). A
  damper on w alone (theta_d = 1) lags by half a step: first order. On a light contact (h large)
  theta_d -> 1 - 1 / h, the servo's bound below: for every h, theta_d >= max(1/2, 1 - 1 / h), which
  keeps the step stable for every mass at every dt (k dt^2 (1 - 2 theta) < 4 m_c + 2 (2 theta_d - 1) d dt)
  and a light contact's gap from flipping sign.
  ``RigidLaw``: eq. (2)-(6) as written, the gap closes in one step (b = g / dt; a
  penetration is removed at the rate beta g / dt, ``BAUMGARTE``), with the small compliance
  R = ``RIGID_COMPLIANCE`` G_ii of MuJoCo's impedance (A15), so that redundant contacts get one
  force split;
* friction, compliant (A13): the smooth stick-slip law |f_T| = mu f_N min(1, |v_T| / v_s),
  whose sticking branch f_T = -(mu f_N / v_s) v_T is the row compliance R = v_s / (mu pbar_N)
  (pbar_N: the normal impulse of the friction fixed point, :mod:`cobra_ref.least_action`);
  rigid: R = ``RIGID_COMPLIANCE`` G_ii;
* joint servo, ``PositionServo`` (A7): tau = kp (q_ref - q) + kd (qd_ref - qd), the spring at the step's start and
  the damper on the mean rate (above), both against the reference at the step's start, its
  impulse bounded by tau_max dt; ``PrescribedServo`` has no rows (its joints move to their
  reference, and their torques are recovered from eq. (1)).
"""

from __future__ import annotations

import numpy as np

RIGID_COMPLIANCE = 1e-2  # R = RIGID_COMPLIANCE * G_ii for rigid rows (MuJoCo's impedance d = 1 / (1 + 1e-2))
BAUMGARTE = 0.2  # rigid contact: fraction of a penetration removed per step


def spring_damper(k, d, dt: float, e, v_ref=0.0, theta=1.0):
    """(R, b) of a row whose law is f = -k (e + theta dt w) - d (w - v_ref) over the step.

    Implements: the module docstring's row law, R = 1 / (dt (theta k dt + d)),
    b = (k e - d v_ref) / (theta k dt + d), for arrays of rows (k, d, e, v_ref, theta broadcast).
    """
    k, d = np.asarray(k, dtype=float), np.asarray(d, dtype=float)
    damping = theta * k * dt + d  # the damper and what the step's spring adds to it
    return 1.0 / (dt * damping), (k * np.asarray(e, dtype=float) - d * np.asarray(v_ref, dtype=float)) / damping


def contact_theta(k, d, dt: float):
    """theta = max(0, 1 - d / (k dt)): where in the step the contact spring is evaluated.

    Implements: the module docstring's choice for the compliant contact (assumption A12): no
    numerical damping while dt <= d / k, and no overshoot of a light contact's gap at any dt.
    """
    return np.maximum(0.0, 1.0 - np.asarray(d, dtype=float) / (np.asarray(k, dtype=float) * dt))


def contact_theta_d(G_NN, d, dt: float):
    """theta_d = 1 / (1 - exp(-h)) - 1 / h, h = d dt / m_c, m_c = 1 / G_NN (m,): how far the
    compliant contact's window reaches past the step's start.

    Implements: the module docstring's window (assumption A12): the weight with which a damper
    step, theta_d on the rate after it and 1 - theta_d on the rate before, decays a contact's
    rate by exp(-h) per step, as the damper does; 1/2 + h / 12 as dt -> 0, and at least
    max(1/2, 1 - 1 / h) (stable, a light contact's gap never flips sign).
    """
    h = np.asarray(G_NN, dtype=float) * d * dt
    small = h < 1e-2
    # the series 1/2 + h/12 - h^3/720 + h^5/30240 where 1 / (1 - e^-h) - 1 / h loses digits
    series = 0.5 + h / 12.0 - h**3 / 720.0 + h**5 / 30240.0
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = 1.0 / -np.expm1(-h) - 1.0 / h
    return np.where(small, series, exact)


class CompliantLaw:
    """The compliant contact law (assumptions A12-A13): a spring-damper on the gap, smooth
    stick-slip friction (module docstring)."""

    name = "compliant"

    def normal_rows(self, model, g: np.ndarray, G_NN: np.ndarray, dt: float, w_start):
        """(R_N, b_N) (m,) each: the spring-damper over the step's window (module docstring) on the
        gap g of a contact that penetrates at the step's start, its spring at ``contact_theta``;
        the damper's impulse after touch-down, x = -d (g + theta_d dt w), on a contact that starts
        apart. ``w_start``: the contacts' normal rates J_N qd before the step (m,).

        Implements: the compliant normal contact law of the module docstring (A12).
        """
        k, d = model.contact_stiffness, model.contact_damping
        theta_d = contact_theta_d(G_NN, d, dt)
        # the gap at the start of the step's window [t - (1 - theta_d) dt, t + theta_d dt]
        g_lo = g - (1.0 - theta_d) * dt * np.asarray(w_start, dtype=float)
        # penetrating at the step's start: the damper over the window's penetrating part
        R, b = spring_damper(k, theta_d * d, dt, g, -(g - np.minimum(g_lo, 0.0)) / (theta_d * dt),
                             theta=contact_theta(k, d, dt))
        apart = g > 0.0
        # apart at the step's start: w + x / (theta_d d dt) + g / (theta_d dt) = 0
        return np.where(apart, 1.0 / (theta_d * d * dt), R), np.where(apart, g / (theta_d * dt), b)

    def tangential_compliance(self, G_TT: np.ndarray) -> np.ndarray:
        """0: the friction rows' compliance depends on the normal impulse (``stick_slip_compliance``)."""
        return np.zeros_like(G_TT)

    def stiction_velocity(self, model) -> float:
        """v_s [m/s] of the smooth stick-slip friction (A13)."""
        return model.stiction_velocity

    def elastic_energy(self, model, g: np.ndarray) -> float:
        """sum 1/2 k g^2 [J] over the compressed contacts (g < 0)."""
        return float(0.5 * model.contact_stiffness * np.sum(np.minimum(g, 0.0) ** 2))


class RigidLaw:
    """The rigid contact law (A15): eq. (2)-(6) as written, with MuJoCo's small compliance."""

    name = "rigid"

    def normal_rows(self, model, g: np.ndarray, G_NN: np.ndarray, dt: float, w_start):
        """(R_N, b_N) (m,) each (``w_start`` is not read): Signorini at the velocity level, a gap closing at most within the
        step (b = g / dt), a penetration removed at the rate BAUMGARTE g / dt, R = RIGID_COMPLIANCE G_NN.

        Implements: the rigid normal contact law of the module docstring (A15).
        """
        b = np.where(g >= 0.0, g, BAUMGARTE * g) / dt
        return RIGID_COMPLIANCE * G_NN, b

    def tangential_compliance(self, G_TT: np.ndarray) -> np.ndarray:
        """RIGID_COMPLIANCE G_TT: the friction rows' small compliance (A15)."""
        return RIGID_COMPLIANCE * G_TT

    def stiction_velocity(self, model) -> float:
        """0: no stick-slip law, Coulomb's friction as written."""
        return 0.0

    def elastic_energy(self, model, g: np.ndarray) -> float:
        """0: a rigid contact stores no energy."""
        return 0.0


CONTACT_LAWS = {"compliant": CompliantLaw(), "rigid": RigidLaw()}  # StepSettings.contact -> its law


STICK_SLIP_MAX = 1e3  # a stick-slip compliance is capped at STICK_SLIP_MAX G_TT (a nearly unloaded contact)


def stick_slip_compliance(v_s: float, bound: np.ndarray, G_TT: np.ndarray) -> np.ndarray:
    """R_T = min(v_s / bound, STICK_SLIP_MAX G_TT) of the smooth stick-slip friction (m,), for the
    friction bounds mu pbar_N and the tangential diagonal of the Delassus matrix G_TT.

    Implements: the sticking branch f_T = -(mu f_N / v_s) v_T of the compliant friction law
    (assumption A13) as a row compliance. The cap keeps the QP well conditioned for a contact
    that carries almost no load (its friction is bounded by that tiny load anyway); a contact
    without a bound, or without the law (v_s = 0, the rigid law), gets 0.
    """
    if v_s <= 0:
        return np.zeros_like(bound)
    loaded = bound > 0.0
    return np.where(loaded, np.minimum(v_s / np.where(loaded, bound, 1.0), STICK_SLIP_MAX * G_TT), 0.0)


def servo_theta(G_ss, kp: float, kd: float, dt: float):
    """(theta, theta_d) of the servo rows: where the spring is evaluated, contact_theta(kp, kd, dt),
    and the damper's weight on qd+, theta_d = max(1/2, 1 - I / (kd dt)), I = 1 / G_ss (n,).

    Implements: the module docstring's servo step (assumption A7): second order as dt -> 0, and
    the error's factor over a step of a light joint, 1 - (1 - theta_d) kd dt / I, never negative.
    """
    inertia = 1.0 / np.asarray(G_ss, dtype=float)
    if kd <= 0.0:  # no damper: nothing to weigh
        return contact_theta(kp, kd, dt), np.full_like(inertia, 0.5)
    return contact_theta(kp, kd, dt), np.maximum(0.5, 1.0 - inertia / (kd * dt))


def servo_rows(model, q_joint, qd_joint, q_ref, qd_ref, G_ss, dt: float):
    """(R_s, b_s): compliance and offset of the joints' servo rows (position control).

    Implements: the position-controlled revolute joint of [COBRA] sec. "Simulation Setup"
    (assumption A7), tau = kp (q_ref - q) + kd (qd_ref - qd), over the step as
    f = -kp (e + theta dt w) - kd (theta_d w + (1 - theta_d) qd - qd_ref) with e = q - q_ref, w the
    joint rate after the step, (q_ref, qd_ref) the reference at the step's start and
    (theta, theta_d) = ``servo_theta``: the row law of ``spring_damper`` with d = theta_d kd and
    v_ref = (qd_ref - (1 - theta_d) qd) / theta_d. ``G_ss``: the rows' diagonal of the Delassus
    matrix.
    """
    kp, kd = model.servo_kp, model.servo_kd
    theta, theta_d = servo_theta(G_ss, kp, kd, dt)
    v_ref = (np.asarray(qd_ref, dtype=float) - (1.0 - theta_d) * np.asarray(qd_joint, dtype=float)) / theta_d
    return spring_damper(kp, theta_d * kd, dt, np.asarray(q_joint, dtype=float) - q_ref, v_ref, theta)


class PositionServo:
    """The paper's position-controlled joints (A7): every coordinate is free and each joint gets a
    servo row towards the reference at the step's start, its impulse bounded by tau_max dt."""

    name = "position"
    reads_start = True  # its rows are written from the reference at the step's start

    def free(self, nv: int, joints) -> np.ndarray:
        """The free coordinates F: all of them."""
        return np.arange(nv)

    def prescribe(self, qd_next: np.ndarray, q, q_ref, joints, dt: float) -> None:
        """Nothing: no coordinate moves by prescription."""

    def jacobian(self, nv: int, joints) -> np.ndarray:
        """The servo rows' Jacobian: one unit row per joint rate."""
        return np.eye(nv)[joints.v]

    def rows(self, model, start, G_ss, dt: float):
        """(R_s, b_s, lo, hi) of the servo rows: ``servo_rows`` from ``start`` (the joints and their
        state at the step's start: ``joints``, ``q``, ``qd``, ``reference`` = (q_ref, qd_ref)), bounded
        by -+tau_max dt."""
        R, b = servo_rows(model, start.q, start.qd, *start.reference, G_ss, dt)
        return R, b, -start.joints.tau_max * dt, start.joints.tau_max * dt

    def torque(self, x_servo: np.ndarray, dt: float, recovered) -> np.ndarray:
        """The joint torques: the servo rows' impulses over dt (``recovered`` is not called)."""
        return x_servo / dt


class PrescribedServo:
    """Prescribed joints (Simscape's "motion provided"): each joint's rate after the step is the
    secant to its reference, (q_ref(t + dt) - q) / dt; only the base and the box are free, and the
    torques are recovered from eq. (1)."""

    name = "prescribed"
    reads_start = False  # no rows: the reference at the step's start is not read

    def free(self, nv: int, joints) -> np.ndarray:
        """The free coordinates F: all but the joints'."""
        return np.setdiff1d(np.arange(nv), joints.v)

    def prescribe(self, qd_next: np.ndarray, q, q_ref, joints, dt: float) -> None:
        """qd_next's joint rates set (in place) to the secant (q_ref - q) / dt."""
        qd_next[joints.v] = (q_ref - q[joints.q]) / dt

    def jacobian(self, nv: int, joints) -> np.ndarray:
        """No servo rows."""
        return np.zeros((0, nv))

    def rows(self, model, start, G_ss, dt: float):
        """No servo rows: empty (R_s, b_s, lo, hi)."""
        return np.zeros(0), np.zeros(0), np.zeros(0), np.zeros(0)

    def torque(self, x_servo: np.ndarray, dt: float, recovered) -> np.ndarray:
        """The joint torques recovered from eq. (1): ``recovered()``."""
        return recovered()


JOINT_SERVOS = {"position": PositionServo(), "prescribed": PrescribedServo()}  # StepSettings.servo -> its servo
LAWS, SERVOS = tuple(CONTACT_LAWS), tuple(JOINT_SERVOS)
