"""Which way the robot can push the box, and the turning candidates that face it towards the target.

A lateral rolling robot travels across its body axis a (:mod:`cobra_ref.planning.locomotion`), so
the only direction it can push the box in is across a, towards the side the box is on. Its push
direction and the facing error phi to the target T::

    r     = a turned by -90 deg (the robot's right, where rolling at f > 0 travels)
    n     = sign((B - p) . r) r       p: the robot's link centre nearest the box centre B
    phi   = the angle from n to T - B, counter-clockwise, in (-pi, pi]

Pushing straight on along n brings the box at best to d |sin phi| of T (d = |T - B|): that lateral
miss is what the robot must turn to remove, and the nearer the box comes the larger the turn it
takes (a 3 cm miss is 9 deg of phi 20 cm out, 85 deg at 3 cm). The re-plan's cost therefore measures
the box's distance with the lateral part weighted by w_l >= 1 (``miss``)::

    m = sqrt(max(d cos phi, 0)^2 + w_l^2 (d^2 sin^2 phi + min(d cos phi, 0)^2))

which is d when the box lies on the push line ahead of T, and w_l d when no straight push brings it
nearer (|phi| >= 90 deg); for small phi it grows like d (1 + w_l^2 phi^2 / 2), which makes the planner
steer the box back onto the line while a small turn still does it.

Rolling shapes push within about 30 deg of n (C, J and J-mirror push the box at -32 to +32 deg of
the robot's heading), so for |phi| above ``FACE_TOL`` the planner turns the robot first. It turns
where it stands with sidewinding: sidewinding turns clockwise whether it winds forwards or backwards,
its mirror counter-clockwise, so forwards then backwards turns it with little travel (measured in
docs/planning.md), and the plant runs such a pair whole (``TURN_PAIR``; re-planned every period, a
re-plan can choose "backwards, then forwards" again and again, and the robot winds away) unless its
first period already faced the robot towards the target, or left the box more than
``reasons.DEPARTED`` from where the turn's rollout put it (a sweep). Such a turn turns n with a; only the
turn's drift, or the box swept by the body, can bring the box to the robot's other side.

Between ``STEER_TOL`` and ``FACE_TOL`` a pushing re-plan also offers one period of the smaller turn
before the push goes on (``steering_candidates``): a lateral miss corrected while the box is still
far. A push stalled near the target with the box off its line (``recovery_candidates``) backs off
with C (which travels towards r at f > 0, ``away``), turns, rolls back and pushes gently: sequences
of periods that a re-plan compares whole; the plant then runs the back-off and the turns without
re-planning (re-planned every period, the back-off would be taken and then, from farther away, the
turn not), and the last ``RECOVERY_TAIL`` periods are re-planned as they come, from where the box
has really gone.
"""

from __future__ import annotations

import numpy as np

from .locomotion import body_axis, link_centres
from .primitives import Primitive

FACE_TOL = np.radians(25.0)  # [rad] a re-plan turns the robot while |phi| exceeds this
STEER_TOL = np.radians(8.0)  # [rad] above this a pushing re-plan also offers a turn before the push
TURN_FREQUENCY = 1.0  # [Hz] one sidewinding cycle per period of 1 s
TURN_AMPLITUDES = (0.3, 0.5)  # [rad] the turning candidates' amplitudes
GENTLE = (0.25, 0.25)  # [rad, Hz] amplitude and frequency of a gentle push (near the target, a recovery's last)
RECOVERY_BACK = (0.25, 0.5)  # [Hz] the back-off's frequencies (C at 0.4 rad)
RECOVERY_TURNS = (1, 2, 3)  # periods of turning in a recovery
RECOVERY_TAIL = 3  # a recovery's periods after its turns: roll back, push gently, stop
TURN_PAIR = 2  # a turning re-plan's periods the plant runs whole: forwards and backwards (``turning_candidates``)
W_LATERAL = 3.0  # [m per m] the lateral miss's weight in ``miss`` (a default of ``PushOptions.w_lateral``)
W_APPROACH = 1.0  # [m per m] a turn's weight of the pushing distance: it must end with the box in reach


def push_direction(model, q) -> np.ndarray:
    """n (2,): the unit direction across the body axis towards the box (module docstring)."""
    return _push_direction(link_centres(model, q), model.boxes[0].body)


def facing(model, q, target) -> float:
    """phi [rad]: the angle from the push direction n to the box's way to ``target`` (module docstring)."""
    return _facing(link_centres(model, q), model.boxes[0].body, target)[0]


def miss(model, q, target, w_lateral: float = W_LATERAL) -> float:
    """m [m]: the box's distance to ``target`` with its part across the push direction weighted by
    ``w_lateral`` (module docstring)."""
    phi, d = _facing(link_centres(model, q), model.boxes[0].body, target)
    along, lateral = d * np.cos(phi), d * np.sin(phi)
    return float(np.hypot(max(along, 0.0), w_lateral * np.hypot(lateral, min(along, 0.0))))


def _facing(points: np.ndarray, box: int, target) -> tuple[float, float]:
    """(phi, d) of the bodies' centres ``points`` (nb, 2), the box's at row ``box``."""
    n = _push_direction(points, box)
    way = np.asarray(target, dtype=float) - points[box]
    return float(np.arctan2(n[0] * way[1] - n[1] * way[0], n @ way)), float(np.linalg.norm(way))


def _push_direction(points: np.ndarray, box: int) -> np.ndarray:
    """n of the bodies' centres ``points`` (nb, 2), the box's at row ``box``."""
    return _right_and_push(points, box)[1]


def _right_and_push(points: np.ndarray, box: int) -> tuple[np.ndarray, np.ndarray]:
    """(r, n) of the bodies' centres ``points`` (nb, 2), the box's at row ``box`` (module docstring)."""
    robot = np.delete(points, box, axis=0)
    a = body_axis(robot)
    r = np.array([a[1], -a[0]])
    nearest = robot[np.argmin(np.linalg.norm(robot - points[box], axis=1))]
    return r, (r if (points[box] - nearest) @ r >= 0 else -r)


def _turn_family(phi: float) -> str:
    """The sidewinding that turns towards ``phi``: its mirror counter-clockwise (phi > 0), else clockwise."""
    return "sidewinding-mirror" if phi > 0 else "sidewinding"


def turning_candidates(phi: float) -> list:
    """The candidate sequences of a turning re-plan for the facing error ``phi``: sidewinding-mirror
    (counter-clockwise) for phi > 0, sidewinding otherwise, at each of ``TURN_AMPLITUDES``, one
    period forwards and one backwards (or backwards, then forwards), then a stop. The plant runs a
    chosen pair whole (``TURN_PAIR``): run forwards or backwards alone, sidewinding travels far (the
    travel map in docs/planning.md), and only the two in turn leave the robot near where it stood."""
    family, stop = _turn_family(phi), Primitive("stop")
    out = []
    for amplitude in TURN_AMPLITUDES:
        ahead, back = Primitive(family, amplitude, TURN_FREQUENCY), Primitive(family, amplitude, -TURN_FREQUENCY)
        out += [(ahead, back, stop), (back, ahead, stop)]
    return out


def steering_candidates(phi: float, moving: Primitive) -> list:
    """The pairs a pushing re-plan adds for the facing error ``phi`` (|phi| > ``STEER_TOL``): one
    period of the turn towards phi at the smaller of ``TURN_AMPLITUDES``, forwards and backwards,
    then the push ``moving`` for the rest of the horizon."""
    if abs(phi) <= STEER_TOL:
        return []
    family = _turn_family(phi)
    return [(Primitive(family, TURN_AMPLITUDES[0], sign * TURN_FREQUENCY), moving) for sign in (1, -1)]


def away(model, q) -> float:
    """The sign of f with which C rolls the robot away from the box (C at f > 0 travels towards r:
    :mod:`cobra_ref.planning.locomotion`): -1 with the box on the right (n = r), else +1."""
    r, n = _right_and_push(link_centres(model, q), model.boxes[0].body)
    return -1.0 if n @ r > 0 else 1.0


def recovery_candidates(phi: float, sign_away: float) -> list:
    """The sequences (one primitive per period) of a recovery for the facing error ``phi``: C at
    0.4 rad backs off (frequency ``sign_away`` times each of ``RECOVERY_BACK``), the turn towards phi
    alternates forwards and backwards for each of ``RECOVERY_TURNS`` periods at each of
    ``TURN_AMPLITUDES``, the same C rolls back, a gentle C (``GENTLE``) pushes, and a stop ends it."""
    family = _turn_family(phi)
    gentle, stop = Primitive("C", GENTLE[0], -sign_away * GENTLE[1]), Primitive("stop")
    out = []
    for f in RECOVERY_BACK:
        back, again = Primitive("C", 0.4, sign_away * f), Primitive("C", 0.4, -sign_away * f)
        for amplitude in TURN_AMPLITUDES:
            for k in RECOVERY_TURNS:
                turns = tuple(Primitive(family, amplitude, TURN_FREQUENCY * (-1) ** i) for i in range(k))
                out.append((back,) + turns + (again, gentle, stop))
    return out
