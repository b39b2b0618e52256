"""Where each primitive takes the robot alone: its travel and turn per cycle, in the body's frame.

The steering a planner has is what the primitives do to the robot, so it is measured, not
assumed. For a primitive p (:mod:`cobra_ref.planning.primitives`), the robot without the box
starts at rest in p's shape (assumption A25), runs p for ``WARM_CYCLES`` cycles (1 / |f| each;
the first holds the start's blend) and then ``cycles`` more, over which its motion is read in the
frame of its body at their start::

    axis a:   the line the link centres lie along (their principal direction), from the tail
              (link 12) towards the head (link 1)
    travel:   the displacement of the link centres' mean over the cycles, per cycle [m], and its
              angle from a [deg, counter-clockwise seen from above]
    turn:     the change of a's direction, per cycle [deg]

A lateral rolling robot travels across its axis (about -90 deg for the forward rolling of C); a
taper b tilts that direction, a negative f reverses it, and the mirrored shapes reflect it: a
primitive and its mirror travel at opposite angles and turn by opposite amounts, by symmetry
(``tests/test_locomotion.py``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..infra.executors import SerialExecutor
from ..kinematics import forward_kinematics
from ..robots import cobra_model
from ..simulate import Run
from ..start import initial_state
from ..step import StepSettings
from .primitives import ROLLING, PlanReference, Primitive

WARM_CYCLES = 1  # cycles run before the measured ones (the start's blend, then a steady gait)
TAPERS = (-1.0, -0.5, 0.0, 0.5, 1.0)  # the tapers of ``locomotion_map``


@dataclass(frozen=True)
class Travel:
    """How a primitive moves the robot alone, per cycle (module docstring)."""

    primitive: Primitive
    distance: float  # [m] the link centres' mean, per cycle
    angle: float  # [deg] of the travel from the body axis, counter-clockwise
    turn: float  # [deg] of the body axis, counter-clockwise

    def to_dict(self) -> dict:
        return {"primitive": self.primitive.to_dict(), "distance": self.distance, "angle": self.angle,
                "turn": self.turn}


def body_axis(points: np.ndarray) -> np.ndarray:
    """The unit principal direction (2,) of points (n, 2) in the plane, pointing from the last
    point's side towards the first's: the body axis of the link centres, tail to head."""
    centred = points - points.mean(axis=0)
    a = np.linalg.svd(centred, full_matrices=False)[2][0]
    return a if (centred[0] - centred[-1]) @ a >= 0 else -a


def link_centres(model, q) -> np.ndarray:
    """(nb, 2): the horizontal positions of the robot's link centres of mass."""
    kin = forward_kinematics(model, q)
    return np.array([kin.o[i][:2] + (kin.R[i] @ model.com[i])[:2] for i in range(model.nb)])


def signed_angle(a: np.ndarray, b: np.ndarray) -> float:
    """The angle [deg] from plane vector a to b, counter-clockwise, in (-180, 180]."""
    return float(np.degrees(np.arctan2(a[0] * b[1] - a[1] * b[0], a @ b)))


def travel(primitive: Primitive, cycles: int = 2, settings: StepSettings = StepSettings()) -> Travel:
    """The robot alone running ``primitive``: its ``Travel`` per cycle over ``cycles`` cycles after
    ``WARM_CYCLES`` (module docstring)."""
    if primitive.family not in ROLLING + ("sidewinding",):
        raise ValueError(f"travel is measured for moving primitives, got {primitive.family!r}")
    model = cobra_model(with_box=False)
    plan = PlanReference(primitive)
    plan.extend(primitive, 0.0)
    n_cycle = int(round(1.0 / abs(primitive.frequency) / settings.dt))
    run = Run(model, settings, *initial_state(model, plan, settings), "fast", (WARM_CYCLES + cycles) * n_cycle)
    run.advance(plan, WARM_CYCLES * n_cycle)
    before = link_centres(model, run.q)
    run.advance(plan, cycles * n_cycle)
    after = link_centres(model, run.q)
    a0, a1 = body_axis(before), body_axis(after)
    moved = after.mean(axis=0) - before.mean(axis=0)
    return Travel(primitive, float(np.linalg.norm(moved)) / cycles, signed_angle(a0, moved),
                  signed_angle(a0, a1) / cycles)


def locomotion_map(amplitude: float = 0.5, frequency: float = 0.5, tapers=TAPERS, executor=None,
                   progress=None) -> list:
    """[Travel] of every rolling family at each taper, then sidewinding forwards and backwards, all
    at ``amplitude`` and ``frequency`` (``travel``), through ``executor`` (None: in this process);
    ``progress(line)`` gets one line per primitive."""
    jobs = [Primitive(f, amplitude, frequency, taper=b) for f in ROLLING for b in tapers]
    jobs += [Primitive("sidewinding", amplitude, frequency), Primitive("sidewinding", amplitude, -frequency)]
    rows = []
    for row in (executor or SerialExecutor()).map(travel, jobs):
        rows.append(row)
        if progress is not None:
            progress(f"{len(rows)}/{len(jobs)} {row.primitive.family} b {row.primitive.taper:+.1f} "
                     f"f {row.primitive.frequency:+g}: {100 * row.distance:.1f} cm per cycle at {row.angle:+.1f} deg")
    return rows


def markdown(rows: list) -> str:
    """The rows of ``locomotion_map`` as a Markdown table, one line per primitive."""
    lines = ["| primitive | taper b | f [Hz] | travel per cycle [cm] | its angle from the body axis [deg] "
             "| turn per cycle [deg] |", "|---|---|---|---|---|---|"]
    for r in rows:
        p = r.primitive
        lines.append(f"| {p.family} | {p.taper:+.1f} | {p.frequency:+g} | {100 * r.distance:.1f} | {r.angle:+.1f} "
                     f"| {r.turn:+.2f} |")
    return "\n".join(lines) + "\n"
