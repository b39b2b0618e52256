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

A lateral rolling robot travels across its axis; a taper b tilts that direction, a negative f
reverses it, and the mirrored shapes reflect it: a primitive and its mirror travel at opposite
angles and turn by opposite amounts, by symmetry (``tests/test_locomotion.py``). With
``alternate``, the measured cycles run p and p with -f in turn (forwards, then backwards): a
primitive that turns the same way in both directions then turns the robot where it stands
(docs/planning.md measures each primitive).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..infra.executors import SerialExecutor
from ..kinematics import forward_kinematics
from ..robots import cobra_model
from ..simulate import Run
from ..start import initial_state
from ..step import StepSettings
from .primitives import ROLLING, SIDEWINDING, PlanReference, Primitive

WARM_CYCLES = 1  # cycles run before the measured ones (the start's blend, then a steady gait)
TAPERS = (-1.0, -0.5, 0.0, 0.5, 1.0)  # the tapers of ``locomotion_map``


@dataclass(frozen=True)
class Travel:
    """How a primitive moves the robot alone, per cycle (module docstring)."""

    primitive: Primitive
    alternate: bool  # the cycles ran the primitive forwards and backwards in turn
    distance: float  # [m] the link centres' mean, per cycle
    angle: float  # [deg] of the travel from the body axis, counter-clockwise
    turn: float  # [deg] of the body axis, counter-clockwise

    def to_dict(self) -> dict:
        return {"primitive": self.primitive.to_dict(), "alternate": self.alternate, "distance": self.distance,
                "angle": self.angle, "turn": self.turn}


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


def travel(primitive: Primitive, cycles: int = 2, settings: StepSettings = StepSettings(),
           alternate: bool = False) -> Travel:
    """The robot alone running ``primitive``: its ``Travel`` per cycle over ``cycles`` cycles after
    ``WARM_CYCLES`` (module docstring); with ``alternate``, those cycles run the primitive
    forwards and backwards in turn."""
    if primitive.family not in ROLLING + SIDEWINDING:
        raise ValueError(f"travel is measured for moving primitives, got {primitive.family!r}")
    model = cobra_model(with_box=False)
    plan = PlanReference(primitive)
    plan.extend(primitive, 0.0)
    n_cycle = int(round(1.0 / abs(primitive.frequency) / settings.dt))
    run = Run(model, settings, *initial_state(model, plan, settings), "fast", (WARM_CYCLES + cycles) * n_cycle)
    run.advance(plan, WARM_CYCLES * n_cycle)
    before = link_centres(model, run.q)
    for k in range(cycles):
        if alternate:  # odd cycles backwards, even ones forwards (the warm cycle ran forwards)
            plan.extend(replace(primitive, frequency=primitive.frequency * (-1) ** (k + 1)), run.t)
        run.advance(plan, n_cycle)
    after = link_centres(model, run.q)
    a0, a1 = body_axis(before), body_axis(after)
    moved = after.mean(axis=0) - before.mean(axis=0)
    return Travel(primitive, alternate, float(np.linalg.norm(moved)) / cycles, signed_angle(a0, moved),
                  signed_angle(a0, a1) / cycles)


def locomotion_map(amplitude: float = 0.5, frequency: float = 0.5, tapers=TAPERS, executor=None,
                   progress=None) -> list:
    """[Travel] of every rolling family at each taper, then both sidewinding families forwards,
    backwards and alternating (four cycles), all at ``amplitude`` and ``frequency`` (``travel``),
    through ``executor`` (None: in this process); ``progress(line)`` gets one line per primitive."""
    jobs = [(Primitive(f, amplitude, frequency, taper=b), 2, False) for f in ROLLING for b in tapers]
    jobs += [(Primitive(f, amplitude, sign * frequency), 2, False) for f in SIDEWINDING for sign in (1, -1)]
    jobs += [(Primitive(f, amplitude, frequency), 4, True) for f in SIDEWINDING]
    rows = []
    for row in (executor or SerialExecutor()).map(_travel_job, jobs):
        rows.append(row)
        if progress is not None:
            progress(f"{len(rows)}/{len(jobs)} {_name(row)}: {100 * row.distance:.1f} cm per cycle at "
                     f"{row.angle:+.1f} deg, turning {row.turn:+.2f} deg")
    return rows


def _travel_job(job: tuple) -> Travel:
    """``travel(primitive, cycles, alternate=...)`` of one ``locomotion_map`` job (picklable)."""
    primitive, cycles, alternate = job
    return travel(primitive, cycles, alternate=alternate)


def _name(row: Travel) -> str:
    p = row.primitive
    return f"{p.family} b {p.taper:+.1f} f {p.frequency:+g}" + (" alternating" if row.alternate else "")


def markdown(rows: list) -> str:
    """The rows of ``locomotion_map`` as a Markdown table, one line per primitive."""
    lines = ["| primitive | taper b | f [Hz] | travel per cycle [cm] | its angle from the body axis [deg] "
             "| turn per cycle [deg] |", "|---|---|---|---|---|---|"]
    for r in rows:
        p = r.primitive
        f = f"+-{abs(p.frequency):g}, alternating" if r.alternate else f"{p.frequency:+g}"
        lines.append(f"| {p.family} | {p.taper:+.1f} | {f} | {100 * r.distance:.1f} | {r.angle:+.1f} | {r.turn:+.2f} |")
    return "\n".join(lines) + "\n"
