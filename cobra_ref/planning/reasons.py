"""What a push says about its task (:mod:`cobra_ref.planning.receding`): up front, what keeps a
goal out of reach or makes it hard (``outlook``); when the budget is spent, why it gave up
(``gave_up``); and the stall test both the loop and ``gave_up`` read (``stalled_over``): a push has
stalled when the box came less than ``STALL_MOVE`` nearer its target in ``STALL_PERIODS`` periods.
When a re-plan may offer the recoveries (``recovery_periods``, ``calm_after``) follows from it, and
when the plant has left a committed sequence's prediction (``departed``).
"""

from __future__ import annotations

import numpy as np

from .facing import FACE_TOL, facing

STALL_PERIODS, STALL_MOVE = 3, 0.003  # a push has stalled when the box came less than 3 mm nearer in 3 periods
DEPARTED = 0.02  # [m] a committed period runs only while the box lies within this of its predicted place
PUSH_SPEED = 0.3  # [m/s] about the fastest push measured: no rollout of the single-shooting searches moved the box more than 0.43 m in 1.5 s


def outlook(model, q, targets: list, budget: float) -> list:
    """What keeps the ``targets`` (world (x, y), the goal last) out of reach or hard within the
    ``budget`` [s], said before the push starts: a path longer than the fastest push covers
    (``PUSH_SPEED``), and a first target on the robot's side of the box (|phi| > 90 deg: the robot
    must turn or go round the box before it pushes, and its primitives do that slowly)."""
    notes = []
    box = model.q_idx[model.boxes[0].body].start
    path = np.vstack([q[box:box + 2]] + [np.asarray(t, dtype=float) for t in targets])
    length = float(np.sum(np.linalg.norm(np.diff(path, axis=0), axis=1)))
    if length > PUSH_SPEED * budget:
        notes.append(f"the box's way is {length:.2f} m; the fastest push measured moves it {PUSH_SPEED:g} m/s, "
                     f"{PUSH_SPEED * budget:.2f} m in the budget: out of reach")
    phi = facing(model, q, targets[0])
    if abs(phi) > np.pi / 2:
        notes.append(f"the {'first waypoint' if len(targets) > 1 else 'goal'} lies on the robot's side of the box "
                     f"(facing error {np.degrees(phi):+.0f} deg): the robot must turn or go round the box before it "
                     "pushes, which its primitives do slowly")
    return notes


def gave_up(boxes: list, ds: list) -> str:
    """The reason a push that spent its budget gives, from the box's position (``boxes``) and its
    distance [m] to its target (``ds``) at each period's start and at the end: it never moved, the
    push stalled (the box came less than ``STALL_MOVE`` nearer in the last ``STALL_PERIODS``
    periods), or it was still pushing."""
    boxes, d = np.asarray(boxes), ds[-1]
    if np.max(np.linalg.norm(boxes - boxes[0], axis=1)) < STALL_MOVE:
        return "budget spent: the robot never moved the box"
    if stalled_over(ds):
        return f"budget spent: the push stalled {100 * d:.2f} cm from its target"
    return f"budget spent: still pushing, {100 * d:.2f} cm from its target"


def stalled_over(ds: list) -> bool:
    """Whether the box came less than ``STALL_MOVE`` nearer its target over the last
    ``STALL_PERIODS`` periods, from its distances ``ds`` [m] at each period's start (the last: now)."""
    return len(ds) > STALL_PERIODS and ds[-1 - STALL_PERIODS] - ds[-1] < STALL_MOVE


def recovery_periods(calm: int, ds: list, phi: float, left: int) -> int | None:
    """The periods a recovery may take (``left``: those left in the budget) when this re-plan may
    offer the recoveries, else None: the push has stalled (``stalled_over(ds)``) or the robot faces
    away from its target (|``phi``| > ``facing.FACE_TOL``), and ``calm`` >= ``STALL_PERIODS`` re-plans
    have passed since the last one that offered them or since a recovery ran. So a stall is offered
    the recoveries at most once in ``STALL_PERIODS`` + 1 re-plans, not at every one (each offer rolls
    out a dozen sequences of five to seven periods)."""
    if calm >= STALL_PERIODS and (stalled_over(ds) or abs(phi) > FACE_TOL):
        return left
    return None


def calm_after(calm: int, mode: str, modes: tuple) -> int:
    """``calm`` after a period whose re-plan rolled out candidates of ``modes`` (none: the period ran
    from a queue) and ran one of ``mode``: 0 if recoveries were offered or one is running, else one more."""
    return 0 if mode == "recover" or "recover" in modes else calm + 1


def departed(box, expected) -> bool:
    """Whether the plant's box (x, y) after a period lies more than ``DEPARTED`` from ``expected``, where
    the rollout that chose the period put it (None: no prediction). The plant runs the rest of a
    committed sequence (a turn pair's second half, a recovery's turns) only while it has not: a turn
    that sweeps the box moves it by an amount the rollouts, in a coarser world, do not predict."""
    return expected is not None and float(np.linalg.norm(np.asarray(box) - np.asarray(expected))) > DEPARTED
