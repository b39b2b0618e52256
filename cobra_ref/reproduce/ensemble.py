"""Ensembles of a gait run: the nominal run and small perturbations of its start, phase and friction.

Implements: the ensemble rule of assumption A29, stated here before any run. A gait run of the
figure command is sensitive to where and when each link first meets the box; one run shows one
outcome, an ensemble shows how far the outcome moves under perturbations below what the paper
could have controlled. Member i of gait g (``members(g, n)``):

* member 0 is the nominal run: no perturbation;
* members 1 .. n-1 are drawn, in order, from ``numpy.random.default_rng(SEED)``, each with four
  uniform draws in this order: ``box_shift`` (dx, dy) in [-5, 5] mm per world axis, ``box_turn``
  in [-2, 2] degrees (added to the box's yaw after the placement rule), ``phase`` in
  [-0.05, 0.05] rad (added to the gait's ``phase`` parameter: the gait starts slightly earlier
  or later in its cycle) and ``mu_scale`` in [0.97, 1.03] (every friction coefficient,
  robot-ground, box-ground and robot-box, multiplied by it);
* the draws do not depend on the gait, so member i of C, S, J and sidewinding has the same
  perturbation; J-mirror's member i is J's member i mirrored about the robot's start heading
  (+x): dy -> -dy and box_turn -> -box_turn, same phase and mu_scale, so that J-mirror stays
  J's reflection member by member.

The draws depend only on ``SEED`` and the index, so ``members(g, 8)[:4] == members(g, 4)``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

SEED = 20240414  # the numpy seed of the draws (the paper's arXiv month)
BOX_SHIFT = 0.005  # [m] +- per world axis
BOX_TURN = np.radians(2.0)  # [rad] +-
PHASE = 0.05  # [rad] +-
MU_SPREAD = 0.03  # mu_scale in [1 - MU_SPREAD, 1 + MU_SPREAD]
MIRRORED = {"J-mirror": "J"}  # gait: the gait whose members it mirrors


@dataclass(frozen=True)
class Member:
    """One member of a gait's ensemble: its index and its perturbation (0 everywhere, scale 1: nominal)."""

    index: int = 0
    box_shift: tuple = (0.0, 0.0)  # (dx, dy) [m], world axes, added to the box's placed centre
    box_turn: float = 0.0  # [rad] added to the placed box's yaw
    phase: float = 0.0  # [rad] added to the gait's phase parameter
    mu_scale: float = 1.0  # multiplies every coefficient of friction

    @property
    def nominal(self) -> bool:
        return self.box_shift == (0.0, 0.0) and self.box_turn == 0.0 and self.phase == 0.0 and self.mu_scale == 1.0

    def as_dict(self) -> dict:
        """The member as plain JSON (cache keys, trajectory meta, reports)."""
        return {"index": self.index, "box_shift": [float(x) for x in self.box_shift],
                "box_turn": float(self.box_turn), "phase": float(self.phase), "mu_scale": float(self.mu_scale)}


def members(gait: str, n: int) -> list[Member]:
    """The ``n`` members of ``gait``'s ensemble, member 0 nominal (module docstring).

    Implements: the ensemble rule of assumption A29 (uniform draws from ``default_rng(SEED)``;
    J-mirror mirrors J). Raises ValueError for n < 1 or a non-integer n.
    """
    if isinstance(n, bool) or not isinstance(n, (int, np.integer)) or n < 1:
        raise ValueError(f"an ensemble needs a whole number n >= 1 of members, got {n!r}")
    rng = np.random.default_rng(SEED)
    out = [Member(0)]
    for i in range(1, int(n)):
        dx, dy = rng.uniform(-BOX_SHIFT, BOX_SHIFT, 2)
        turn = rng.uniform(-BOX_TURN, BOX_TURN)
        phase = rng.uniform(-PHASE, PHASE)
        mu = rng.uniform(1.0 - MU_SPREAD, 1.0 + MU_SPREAD)
        out.append(Member(i, (float(dx), float(dy)), float(turn), float(phase), float(mu)))
    if gait in MIRRORED:
        out = [mirrored(m) for m in out]
    return out


def mirrored(member: Member) -> Member:
    """``member`` reflected about the start heading (+x): dy -> -dy, box_turn -> -box_turn.
    """
    dx, dy = member.box_shift
    return Member(member.index, (dx, -dy if dy else 0.0), -member.box_turn if member.box_turn else 0.0,
                  member.phase, member.mu_scale)
