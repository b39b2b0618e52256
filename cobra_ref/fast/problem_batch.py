"""The least-action problems of K members at once: their rows' compliances and offsets, batched.

For performance: ``least_action_problems(models, parts)`` is ``[step.least_action_problem(model,
G, *args) for ...]``, bit for bit, for the K members of a batched step
(:mod:`cobra_ref.fast.batch`). The contact law's and the servo's rows (their compliance R and
offset b, :mod:`cobra_ref.compliance`) are elementwise in the rows, so they are written for the
concatenation of every member's rows (``members.MemberRows``) by one call each; each member's H =
G + diag(R) stays its own. Batched when the members' models agree on what those rows read (the
contact's spring and damper, the servo's gains and the stiction velocity: ``same_row_laws``); each
member's friction coefficients and torque bounds are its own either way. Tested equal to
``least_action_problem`` member by member.
"""

from __future__ import annotations

import numpy as np

from ..contact import BOX_GROUND, ROBOT_BOX, ROBOT_GROUND
from ..least_action import LeastAction
from ..step import ServoStart, least_action_problem
from .members import member_rows

# the model parameters the rows' laws read (besides each member's own friction and torque bounds)
ROW_LAW_PARAMETERS = ("contact_stiffness", "contact_damping", "servo_kp", "servo_kd", "stiction_velocity")


def same_row_laws(a, b) -> bool:
    """Whether models a and b give rows the same laws (``ROW_LAW_PARAMETERS``)."""
    return all(getattr(a, name) == getattr(b, name) for name in ROW_LAW_PARAMETERS)


def least_action_problems(models, parts) -> list:
    """``step.least_action_problem(models[k], G, *args)`` for every member k, with ``parts[k]`` =
    (G, (c_free, contacts, settings, start, w_start)) (module docstring); the settings are every
    member's."""
    model = models[0]
    if not all(other is model or same_row_laws(model, other) for other in models[1:]):
        return [least_action_problem(own, G, *args) for own, (G, args) in zip(models, parts)]
    Gs = [G for G, _ in parts]
    c_free, contacts, settings, starts, w_start = zip(*(args for _, args in parts))
    dt, law = settings[0].dt, settings[0].law
    R = member_rows(np.array([c.m for c in contacts]), np.array([len(G) for G in Gs]))
    d = np.concatenate([G.diagonal() for G in Gs])
    rows_R, rows_b = np.zeros(len(d)), np.zeros(len(d))
    rows_R[R.N], rows_b[R.N] = law.normal_rows(model, np.concatenate([c.g for c in contacts]), d[R.N], dt,
                                               np.concatenate(w_start))
    rows_R[R.T1] = law.tangential_compliance(d[R.T1])
    rows_R[R.T2] = law.tangential_compliance(d[R.T2])
    rows_R[R.servo], rows_b[R.servo], lo, hi = settings[0].joint_servo.rows(model, _joined(starts), d[R.servo], dt)
    # each contact's coefficient of friction, looked up by its member and its kind
    mu_of_kind = np.empty((R.K, 3))
    mu_of_kind[:, [ROBOT_GROUND, ROBOT_BOX, BOX_GROUND]] = [(m.mu, m.mu_rb, m.mu_bg) for m in models]
    mu = mu_of_kind[R.of_contact, np.concatenate([c.kind for c in contacts]).astype(int)]
    c = np.concatenate(c_free) + rows_b
    v_s = law.stiction_velocity(model)
    return [LeastAction(G + np.diag(rows_R[R.row_slice(k)]), c[R.row_slice(k)], mu[R.contact_slice(k)],
                        lo[R.servo_slice(k)], hi[R.servo_slice(k)], v_s) for k, G in enumerate(Gs)]


def _joined(starts) -> ServoStart:
    """One ``ServoStart`` of every member's joints, one after the other (their rows in that order)."""
    first = starts[0]
    joints = first.joints._replace(tau_max=np.concatenate([s.joints.tau_max for s in starts]))
    reference = None if first.reference is None else tuple(np.concatenate(parts) for parts in
                                                           zip(*(s.reference for s in starts)))
    return ServoStart(joints, np.concatenate([s.q for s in starts]), np.concatenate([s.qd for s in starts]), reference)
