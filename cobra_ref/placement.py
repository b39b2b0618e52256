"""Where the box goes for a gait that travels: ahead of the wave, in the direction it moves.

Implements: the box placement of a travelling gait (sidewinding), assumption A31. A rolling gait
turns in place and the box goes beside its middle (``start.placed_state``); sidewinding moves
the whole body sideways while its wave sweeps a band of ground around it, so a box put beside
the middle lies inside that band and is trampled instead of pushed. The rule, stated before any
result is looked at:

* the direction d: the horizontal displacement of the robot's centre of mass over
  ``DIRECTION_PERIODS`` periods of a box-free run of the same gait from the same start
  (``travel_direction``);
* the reach e: how far ahead along d the wave carries the robot's surface, measured in the frame
  that travels with the robot's centre of mass c (so the band the wave sweeps, not the distance
  the robot travels) over the first ``ENVELOPE_PERIODS`` period of that box-free run, from the
  middle m of the start shape (the point the placement measures from)::

      e = (c(0) - m) . d + max over steps k <= T_f / dt and spheres s of (c_s(k) - c(k)) . d + r_s

  (c_s: sphere centre, r_s: its radius; the placed and the settled start are included);
* the box's near face then goes ``gap`` (5 cm, A9) beyond that reach: the placement's clearance
  is ``box_gap = e + gap - r``, r the middle link's radius (``placed_state`` puts the face at
  r + box_gap from m; ``TravelPlacement.box`` is that ``BoxPlacement``). The box is outside the band the wave sweeps, and the robot's leading side
  meets it after travelling about ``gap``, as a rolling gait's body meets its box.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .infra.validation import DEFAULT_DT
from .kinematics import forward_kinematics
from .model import Model
from .simulate import simulate
from .start import BoxPlacement, initial_state, placed_state
from .step import SimulationError, StepSettings

DIRECTION_PERIODS = 2.0  # periods of the box-free run whose centre-of-mass displacement gives d
ENVELOPE_PERIODS = 1.0  # periods over which the reach e is measured


@dataclass(frozen=True)
class TravelPlacement:
    """Where a travelling gait's box goes: ``direction`` d (unit, horizontal), ``reach`` e [m] and
    ``box_gap`` [m] for ``start.placed_state`` (module docstring)."""

    direction: tuple
    reach: float
    box_gap: float

    @property
    def box(self) -> BoxPlacement:
        """The ``start.BoxPlacement`` of this placement: direction d, clearance box_gap."""
        return BoxPlacement(gap=self.box_gap, direction=self.direction)


def _robot(model: Model) -> list[int]:
    return [i for i in range(model.nb) if all(b.body != i for b in model.boxes)]


def _middle_bodies(model: Model) -> list[int]:
    robot = _robot(model)
    return robot[len(robot) // 2 - 1:len(robot) // 2 + 1]


def _middle(model: Model, q) -> np.ndarray:
    """m: the midpoint of the centres of mass of the two middle robot bodies (``placed_state``)."""
    kin = forward_kinematics(model, q)
    return np.mean([kin.o[i] + kin.R[i] @ model.com[i] for i in _middle_bodies(model)], axis=0)


def _com(model: Model, q) -> np.ndarray:
    kin, robot = forward_kinematics(model, q), _robot(model)
    pts = np.array([kin.o[i] + kin.R[i] @ model.com[i] for i in robot])
    return np.average(pts, axis=0, weights=[model.mass[i] for i in robot])


def _reach(model: Model, q, d: np.ndarray) -> float:
    """max over the robot's spheres of (c_s - c) . d + r_s at configuration q: how far ahead of the
    centre of mass c, along the horizontal d, the robot's surface reaches."""
    kin, sph, c = forward_kinematics(model, q), model.spheres, _com(model, q)
    robot = set(_robot(model))
    return max(float((kin.o[b] + kin.R[b] @ s - c)[:2] @ d) + r
               for b, s, r in zip(sph.body, sph.center, sph.radius) if b in robot)


def travel_placement(model: Model, reference, dt: float = DEFAULT_DT, gap: float = 0.05,
                     settings: StepSettings | None = None) -> TravelPlacement:
    """The box placement of a travelling gait: d, e and box_gap of the module docstring.

    Implements: assumption A31. ``model`` is the robot without the box; one box-free run of
    ``DIRECTION_PERIODS`` periods at ``dt`` from ``start.initial_state`` under ``settings``
    (default: the high-fidelity setting at dt). Raises ``SimulationError`` when the gait does
    not move the robot (no direction to put the box in).
    """
    if model.boxes:
        raise ValueError("travel_placement needs the robot model without the box (cobra_model(with_box=False))")
    settings = settings or StepSettings(dt=dt)
    period = 1.0 / reference.frequency
    q_placed = placed_state(model, reference)
    q0, qd0 = initial_state(model, reference, settings)
    traj = simulate(model, reference, DIRECTION_PERIODS * period, settings, q0, qd0)
    d = (_com(model, traj.q[-1]) - _com(model, traj.q[0]))[:2]
    if np.linalg.norm(d) < 1e-6:
        raise SimulationError(f"the gait does not move the robot in {DIRECTION_PERIODS:g} periods; "
                              "cannot place the box in its path")
    d = d / np.linalg.norm(d)
    m = _middle(model, q_placed)
    last = int(round(ENVELOPE_PERIODS * period / settings.dt))
    e = float((_com(model, q_placed) - m)[:2] @ d) + max(_reach(model, q, d) for q in [q_placed, *traj.q[:last + 1]])
    r = max(model.spheres.radius[np.isin(model.spheres.body, _middle_bodies(model))])
    return TravelPlacement(tuple(float(v) for v in d), float(e), float(e + gap - r))
