"""The candidates a re-plan of the push compares (:mod:`cobra_ref.planning.receding`, step 1).

Each candidate is a sequence of primitives, one per period, the last for the rest of the horizon
(a pair: the next period and the rest). Which ones a re-plan rolls out depends on the state it
starts from (``choose_candidates``): a robot facing away from the target turns where it stands
(``facing.turning_candidates``), otherwise it pushes (``candidates``), and a stalled push near its
target, or a robot facing away from it there, may also recover (``facing.recovery_candidates``).
Pushes are predictive sampling around the rolling primitive the last plan goes on with
(``warm_start``), with the deterministic variations a push needs near its target (stops, rolling
back, gentle pushes, shorter pushes).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from .facing import FACE_TOL, GENTLE, STEER_TOL, recovery_candidates, steering_candidates, turning_candidates
from .primitives import ROLLING, Primitive

NEAR = 0.05  # [m] the gentle pushes are candidates only with the box this near its target
STILL = 0.02  # [m] and a stop for the whole horizon only this near (farther, a stop stalls the push)
RECOVER_WITHIN = 0.1  # [m] a stalled push, or a robot facing away, recovers only this near its target
FINAL = 0.1  # [m] within this of the target the noisy samples push for fewer periods and stop (``candidates``)


def choose_candidates(phi: float, d: float, moving: Primitive, rng: np.random.Generator, samples: int,
                      recover: int | None, sign_away, horizon: int = 2) -> list:
    """The candidates of one re-plan (module docstring), each with its mode: [(mode, sequence), ...]
    for the facing error ``phi`` and the box's distance ``d`` to the target. While the robot faces
    away from the target, "turn" (``facing.turning_candidates``, and the gentle pushes near the
    target), else "push" (``candidates`` for a rollout of ``horizon`` periods). Within
    ``RECOVER_WITHIN`` of the target with the box off its line, when a recovery may start
    (``recover``: the periods left in the budget, given when the push has stalled or the robot faces
    away from the target; None otherwise), "recover" (``facing.recovery_candidates`` that end within
    the budget; ``sign_away()`` gives the back-off's sign) are compared with those: a recovery runs
    only if its rollout predicts a better end than the turns or pushes (a back-off beside the box
    can drag it along). No stop is added: farther than ``STILL`` from the target, standing still
    often looks the safest choice, and the push would rest short of the goal."""
    if abs(phi) > FACE_TOL and d > STILL:  # the robot faces away from the target: it turns where it stands first
        out = [("turn", seq) for seq in turning_candidates(phi) + (gentle(moving) if d <= NEAR else [])]
    else:
        out = [("push", seq) for seq in candidates(moving, rng, samples, near=d <= NEAR, still=d <= STILL,
                                                   horizon=horizon, final=d <= FINAL)
               + steering_candidates(phi, moving)]
    if recover is not None and STILL < d <= RECOVER_WITHIN and abs(phi) > STEER_TOL:
        # a recovery must end within the budget; its rollout is weighed against the turns' and pushes':
        # beside the box a turn where the robot stands can sweep the box, and a back-off can drag it
        out += [("recover", seq) for seq in recovery_candidates(phi, sign_away()) if len(seq) - 1 <= recover]
    return out


def candidates(moving: Primitive, rng: np.random.Generator, samples: int, near: bool = True,
               still: bool = True, horizon: int = 2, final: bool = False) -> list:
    """The candidate pairs (first period, the rest of the horizon) of one re-plan from the last
    rolling primitive ``moving`` (module docstring), and ``moving`` for k = 2 .. ``horizon`` - 1
    periods then a stop (sequences of one primitive per period); the gentle pushes only when the box
    is ``near`` its target, and a stop for the whole horizon only when it is ``still`` nearer
    (farther, standing still would often look the safest choice and the push would stall). In the
    ``final`` approach each noisy sample pushes for k = ``horizon``, ``horizon`` - 1, ..., 1 periods
    in turn and then stops: a push of whole periods at one speed either falls short of the box or
    overshoots the target, and the samples' speeds and lengths together fill the gap."""
    stop, back = Primitive("stop"), replace(moving, frequency=-moving.frequency)
    # rolling back (and then on again) brings the robot back to a box it has rolled past; rolling on
    # for k periods and stopping is the last plan shifted by a period when it ended with k + 1 pushes
    out = [(moving, moving), (moving, stop)] + [(moving,) * k + (stop,) for k in range(2, horizon)]
    out += [(back, back), (back, moving)] + ([(stop, stop)] if near and still else [])
    out += [(p, p) for p in (replace(moving, family=f) for f in ROLLING) if p != moving]
    if near:  # a gentle push of every rolling shape, each way, then a stop: the small corrections near the target
        out += gentle(moving)
    for i in range(samples):
        noisy, k = _perturbed(moving, rng), horizon - i % horizon if final else horizon
        out.append((noisy, noisy) if k == horizon else (noisy,) * k + (stop,))
    return out


def warm_start(pair: tuple, moving: Primitive) -> Primitive:
    """The rolling primitive the next re-plan's candidates start from, after the plant applied the
    first period of ``pair``: the plan shifted by one period, the primitive ``pair`` goes on with
    (its last, if rolling), else its first if rolling, else ``moving``. So a push that rolls back for
    one period and then on again is warm-started with "on" (warm-started with "back", the next
    re-plan would offer "on" only for the whole horizon or after a period back, and the push would
    go back and forth short of the box)."""
    for p in (pair[-1], pair[0]):
        if p.family in ROLLING:
            return p
    return moving


def gentle(moving: Primitive) -> list:
    """The gentle pushes (``GENTLE``) of every rolling shape each way at ``moving``'s taper, each then a stop."""
    return [(Primitive(f, GENTLE[0], sign * GENTLE[1], moving.taper), Primitive("stop")) for f in ROLLING
            for sign in (1, -1)]


def _perturbed(p: Primitive, rng: np.random.Generator) -> Primitive:
    """p with amplitude, frequency (its size; its sign kept) and taper moved by Gaussian noise and
    clipped to their ranges."""
    a, f, b = rng.normal(size=3) * (0.1, 0.15, 0.3)
    amplitude = float(np.clip(p.amplitude + a, 0.25, 0.75))
    taper = float(np.clip(p.taper + b, -0.8, 0.8)) if p.family in ROLLING else 0.0
    frequency = float(np.copysign(np.clip(abs(p.frequency) + f, 0.25, 1.0), p.frequency))
    return replace(p, amplitude=amplitude, frequency=frequency, taper=taper)
