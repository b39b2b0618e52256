"""Where a run starts: the robot at rest in its reference's first shape, settled on the ground.

Implements: the start at rest of assumption A25. The robot is placed in the reference's t = 0
shape (a 3-D shape laid on its flattest side), its lowest sphere touching the ground, the box
beside its middle (A9); then the scene settles with the joints holding that shape, under the run's
own contact law and servo, for at least ``SETTLE_TIME`` and until no coordinate has moved faster
than ``SETTLE_SPEED`` for ``SETTLE_STILL`` in a row (at most ``SETTLE_MAX``; a shape rolling onto
its side passes through slow turning points, which one slow step would mistake for rest), so that
every sphere that carries weight rests on the ground and the run does not begin with a fall.

The settling is dynamic relaxation with kinetic damping (Cundall 1976; Barnes 1999, "Form finding
and analysis of tension structures by dynamic relaxation", sec. 3): the real model is stepped, and
whenever its kinetic energy falls (it has just passed a peak, the bottom of a swing through the
equilibrium) every velocity is set to zero. The rest states are those of the undamped model (the
damping removes no force, only the swing's energy), reached without the slow decay of the
servo-held shape's rocking on its contacts: sidewinding's 3-D shape, which first rolls onto a
stable side, settles in about 0.4 s of model time instead of 1.9 s. (A planar rolling shape only
sinks by the contacts' sag, within about ``SETTLE_TIME``.)
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .infra import arguments
from .infra.executors import one_blas_thread
from .kinematics import forward_kinematics
from .model import Model
from .quaternion import quat_exp, quat_mul
from .robots import neutral_q
from .step import StepSettings
from .steppers import STEPPERS, make_stepper

SETTLE_TIME = 0.05  # [s] the scene settles at least this long with the joints holding the start shape (A25)
SETTLE_MAX = 3.0  # [s] and at most this long
SETTLE_SPEED = 1e-2  # [m/s, rad/s] until no coordinate moves faster (below the impact speed of A26)
SETTLE_STILL = 0.05  # [s] ... for this long in a row


@dataclass(frozen=True)
class BoxPlacement:
    """Where ``placed_state`` puts the box (its docstring states the rule); checked once, here.

    ``offset`` (dx, dy) [m]: the box centre at the middle + offset, axis-aligned (None: the rule's
    side); ``gap`` [m]: the clearance between the box's near face and the middle link (A9; not
    used with ``offset``); ``direction`` (dx, dy): the side the box goes to (None: the concave
    side); ``yaw`` [rad]: the box's heading (None: the placement's own); ``shift`` (dx, dy) [m] and
    ``turn`` [rad]: added to the placed centre and yaw (an ensemble member's perturbation). Each is
    checked by the command line's rule (``validation.RULES``: box_offset, box_gap, box_yaw) or, for
    the others, as finite: an ``infra.arguments`` error (a ValueError or TypeError) names the field
    (as box_<field>), the value and what is allowed.
    """

    offset: tuple | None = None
    gap: float = 0.05
    direction: tuple | None = None
    yaw: float | None = None
    shift: tuple | None = None
    turn: float = 0.0

    def __post_init__(self):
        def put(field, value):
            object.__setattr__(self, field, value)

        # each field by the command line's rule (--box-offset, --box-gap, --box-yaw), the rest finite
        if self.offset is not None:
            put("offset", arguments.numbers("box_offset", self.offset, 2, "box_offset", ("DX", "DY")))
        put("gap", arguments.number("box_gap", self.gap, "box_gap"))
        if self.direction is not None:
            put("direction", arguments.numbers("box_direction", self.direction, 2, labels=("DX", "DY")))
            if not any(self.direction):
                raise arguments.ArgumentError("box_direction = (0, 0) has no direction (allowed: a non-zero (DX, DY))")
        if self.yaw is not None:
            put("yaw", arguments.number("box_yaw", self.yaw, "box_yaw"))
        if self.shift is not None:
            put("shift", arguments.numbers("box_shift", self.shift, 2, labels=("DX", "DY")))
        put("turn", arguments.number("box_turn", self.turn))


def check_run_arguments(model, reference, settings, stepper: str, progress=None) -> None:
    """The arguments a run starts from (``initial_state``, ``simulate``), each of its kind: a
    ``Model``, a callable reference, a ``StepSettings``, a stepper of ``steppers.STEPPERS`` and a
    callable or None ``progress``; an ``infra.arguments`` error naming the first that is not."""
    arguments.instance("model", model, Model, "cobra_model()")
    arguments.function("reference", reference, "a joint reference t -> (q, qd, qdd), e.g. gait('C')")
    arguments.instance("settings", settings, StepSettings, "StepSettings(dt=0.001)")
    arguments.choice("stepper", stepper, STEPPERS)
    arguments.function("progress", progress, "a function progress(done, total)", optional=True)


def initial_state(model: Model, reference, settings: StepSettings = StepSettings(),
                  placement: BoxPlacement = BoxPlacement(), settle: bool = True, stepper: str = "fast"):
    """(q0, qd0): the scene placed (``placed_state`` with ``placement``) and, with ``settle``,
    settled (module docstring) by a new stepper of kind ``stepper`` (``steppers.STEPPERS``).

    Implements: the start at rest (assumption A25): the joints hold the reference's t = 0
    shape while the robot and the box come to rest on the ground under ``settings``' contact
    law and servo; what is left of their motion (below SETTLE_SPEED) is returned as qd0. The
    arguments are checked first (``check_run_arguments``; ``placement`` a ``BoxPlacement``).
    """
    check_run_arguments(model, reference, settings, stepper)
    arguments.instance("placement", placement, BoxPlacement, "BoxPlacement(gap=0.05)")
    arguments.instance("settle", settle, (bool, np.bool_), "True or False")
    q = placed_state(model, reference, placement)
    qd = np.zeros(model.nv)
    if settle:
        with one_blas_thread():  # as simulate steps: the same start in a script as on the command line
            q, qd = _settle(make_stepper(stepper, model, settings), q, qd, Hold(reference(0.0)[0]))
    return q, qd


def _settle(stepper, q, qd, hold):
    """(q, qd) after the dynamic relaxation of the module docstring, stepped by ``stepper`` with
    the joints holding ``hold``."""
    relaxation = Relaxation(stepper.settings.dt)
    while True:
        result = stepper.step(q, qd, relaxation.k * stepper.settings.dt, hold)
        q = result.q
        qd, restart, settled = relaxation.after(result)
        if restart:  # a step afresh: no velocity memory, as on a first step
            stepper.memory = None
        if settled:
            return q, qd


class Relaxation:
    """The dynamic relaxation of the module docstring, one step at a time: ``after`` takes a step's
    result and says what the next step starts from; ``k`` counts the steps taken."""

    def __init__(self, dt: float):
        self.least, self.most = int(round(SETTLE_TIME / dt)), int(round(SETTLE_MAX / dt))
        self.still, self.calm = int(round(SETTLE_STILL / dt)), 0  # steps in a row below SETTLE_SPEED
        self.peak = 0.0  # the kinetic energy at the start of the last step
        self.k = 0

    def after(self, result) -> tuple:
        """(qd, restart, settled) after the step ``result``: its velocity, or zero with restart True
        where the kinetic energy has passed a peak (kinetic damping: every coordinate stops); settled
        once the scene has been still long enough, or after the most steps allowed."""
        qd, restart = result.qd, False
        if result.kinetic < self.peak:
            qd, restart, self.peak = np.zeros_like(qd), True, 0.0
        else:
            self.peak = result.kinetic
        self.calm = self.calm + 1 if np.abs(qd).max() < SETTLE_SPEED else 0
        self.k += 1
        return qd, restart, (self.k >= self.least and self.calm >= self.still) or self.k >= self.most


class Hold:
    """A reference that holds the joint angles q_0: (q_0, 0, 0) at every time."""

    def __init__(self, q0):
        self.q0 = np.asarray(q0, dtype=float)

    def __call__(self, t: float):
        zero = np.zeros_like(self.q0)
        return self.q0, zero, zero


def placed_state(model: Model, reference, placement: BoxPlacement = BoxPlacement(),
                 clearance: float = 0.0) -> np.ndarray:
    """q of the robot in the reference's t = 0 shape, head at the origin facing +x, lowest sphere
    ``clearance`` above the ground (default: touching it); the box flat on the ground beside the
    middle of the snake (assumption A9), where ``placement`` says. ``initial_state`` lets this settle.

    Box placement. The middle of the snake is the midpoint m of the two middle bodies' centres of
    mass (L5 and L6 for COBRA); its heading h is the horizontal direction from the second to the
    first, and its left side n is h turned by +90 degrees about the vertical. The box goes in the
    horizontal direction d from m, its centre at m + (r + a/2 + gap) d (r: the middle link's
    radius, a: the box's edge), turned so that one face looks back at the robot: ``placement.gap``
    (default 0.05 m, A9) is then the clearance between that face and the middle link's cylinder.
    The direction d is, in this order:

    * ``placement.direction`` = (dx, dy) if given (sidewinding pushes with its leading side:
      ``reproduce`` passes the direction the gait travels);
    * the concave side: from m to the robot's centre of mass c, when the start is bent, that is
      when c lies at least ``STRAIGHT_TOLERANCE`` (1 mm) to the side of the middle's axis
      (|(c - m) . n| >= 1 mm) and no more along the axis than across it (within 45 degrees of
      the side; farther along, the box would land on the robot's own links);
    * otherwise (a straight or nearly straight start, or a symmetric S) the side: n if the
      centre of mass is on the left or on the axis, -n if it is on the right by 1 mm or more. A
      straight start's box then sits beside the middle link on the body's left, clear of it.

    ``placement.offset`` = (dx, dy) [m] instead puts the box centre at m + (dx, dy) (world axes),
    axis-aligned; ``placement.yaw`` [rad] turns the box about the vertical to that heading (world
    axes; by default the placement's own: facing the robot, or 0 with an offset).

    After the placement, ``placement.shift`` = (dx, dy) [m] (world axes) is added to the box's
    centre and ``placement.turn`` [rad] to its yaw (an ensemble member's perturbation,
    ``reproduce.ensemble``); None and 0 leave the placement as it is.

    The robot's base is first turned so that its start shape lies on its flattest side
    (``_rest_on_flattest_side``; no turn for the planar rolling shapes).
    """
    q = neutral_q(model)
    act_q = [model.q_idx[i].start for i, jt in enumerate(model.joint_type) if jt != "free"]
    q[act_q] = reference(0.0)[0]
    q[3:7] = _rest_on_flattest_side(model, q)
    kin = forward_kinematics(model, q)
    sph = model.spheres
    bottoms = [kin.o[b][2] + (kin.R[b] @ c)[2] - r for b, c, r in zip(sph.body, sph.center, sph.radius)]
    q[2] = clearance - min(bottoms)
    if model.boxes:
        box = model.boxes[0]
        robot = [i for i in range(model.nb) if i != box.body]
        com = np.array([kin.o[i] + kin.R[i] @ model.com[i] for i in robot])
        mid_bodies = robot[len(robot) // 2 - 1:len(robot) // 2 + 1]
        middle = com[mid_bodies].mean(axis=0)
        iq = model.q_idx[box.body]
        p = placement
        if p.offset is not None:
            centre, yaw = middle[:2] + np.asarray(p.offset, dtype=float), 0.0
        else:
            d = np.asarray(p.direction, dtype=float) if p.direction is not None else \
                _concave_side(com, mid_bodies, [model.mass[i] for i in robot])
            d = d / np.linalg.norm(d)
            r = max(sph.radius[np.isin(sph.body, mid_bodies)])
            centre, yaw = middle[:2] + (r + box.half[0] + p.gap) * d, np.arctan2(d[1], d[0])
        if p.yaw is not None:
            yaw = p.yaw
        if p.shift is not None:
            centre = centre + np.asarray(p.shift, dtype=float)
        yaw = yaw + p.turn
        q[iq.start:iq.start + 3] = [centre[0], centre[1], box.half[2]]
        q[iq.start + 3:iq.start + 7] = [np.cos(yaw / 2), 0.0, 0.0, np.sin(yaw / 2)]
    return q


STRAIGHT_TOLERANCE = 1e-3  # [m] a start whose centre of mass is closer to the middle's axis has no concave side


def _concave_side(com: np.ndarray, mid_bodies, masses) -> np.ndarray:
    """The horizontal direction from the middle to the centre of mass, or the middle's side when
    that direction is not across the body (``placed_state``'s rule)."""
    middle = com[mid_bodies].mean(axis=0)
    d = (np.average(com, axis=0, weights=masses) - middle)[:2]
    h = (com[mid_bodies[0]] - com[mid_bodies[1]])[:2]
    h = h / np.linalg.norm(h)
    n = np.array([-h[1], h[0]])
    across, along = float(d @ n), float(d @ h)
    if abs(across) >= STRAIGHT_TOLERANCE and abs(along) <= abs(across):
        return d
    return -n if across <= -STRAIGHT_TOLERANCE else n


def _rest_on_flattest_side(model: Model, q) -> np.ndarray:
    """Base quaternion that turns the robot's best-fit plane horizontal (a 3-D start shape, such as
    sidewinding's, then lies on its flattest side instead of standing on its tips and falling).

    The plane through the robot bodies' centres of mass with the least variance across
    it (its normal n is the last right singular vector of the centred points); the base turns by
    the smallest rotation taking n (chosen with n_z >= 0) to z. A planar shape (every rolling
    gait at t = 0) has n = z already, so it is left as it is.
    """
    kin = forward_kinematics(model, q)
    robot = [i for i in range(model.nb) if not any(b.body == i for b in model.boxes)]
    com = np.array([kin.o[i] + kin.R[i] @ model.com[i] for i in robot])
    n = np.linalg.svd(com - com.mean(axis=0))[2][-1]
    n = n if n[2] >= 0 else -n
    axis = np.cross(n, [0.0, 0.0, 1.0])
    if np.linalg.norm(axis) < 1e-9:
        return q[3:7].copy()
    angle = np.arctan2(np.linalg.norm(axis), n[2])
    turn = quat_exp(angle * axis / np.linalg.norm(axis))
    return quat_mul(turn, q[3:7])
