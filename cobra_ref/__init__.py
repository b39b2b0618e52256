"""cobra_ref: a plain-Python reference implementation of [COBRA] (arXiv 2404.08714).

Non-impulsive contact-implicit loco-manipulation: the 12-body, 11-joint COBRA snake pushes a
box across flat ground. The main entry points are importable from here: ``cobra_model`` (the
robot and the box), ``gait`` (a joint reference: "C", "S", "J", "J-mirror", "sidewinding"),
``initial_state`` with ``BoxPlacement`` (the settled start), ``StepSettings`` (dt, contact law,
servo), ``make_stepper`` (one step at a time), ``simulate`` (a run) and ``Trajectory`` (its
record, saved as NPZ). Build the model, a gait, simulate 0.2 s and read how far the box moved::

    >>> from cobra_ref import cobra_model, gait, simulate
    >>> model = cobra_model()                     # COBRA and the box, 25 coordinates
    >>> reference = gait("J", ramp_time=0.0)      # J rolling at full speed from t = 0
    >>> traj = simulate(model, reference, 0.2)    # 200 steps of 1 ms, the fast stepper
    >>> dx, dy = traj.box_pose[-1, :2] - traj.box_pose[0, :2]
    >>> print(f"{len(traj.t)} states; the box moved {1000 * (dx * dx + dy * dy) ** 0.5:.0f} mm")
    201 states; the box moved 8 mm

``cobra_ref.viz.plot.plot_run(traj)`` draws the box's path, the contact forces and the joint
torques. Where to go next: the README (install, the first five minutes, the commands, where each
equation of the paper lives), the runnable tutorials in ``tutorials/`` (``01_spatial_algebra`` to
``08_mujoco_like_for_like``), the command ``cobra-ref --help`` (``python -m cobra_ref``), the
planner in ``cobra_ref.planning`` (``optimize_gait``) and the paper's results in
``cobra_ref.reproduce.regenerate`` (``regenerate``). A bad argument to these functions raises
``ArgumentError`` (a ValueError) or ``ArgumentTypeError`` (a TypeError) naming it, its value and
what is allowed (the command line's rules, :mod:`cobra_ref.infra.arguments`). Notation: the
README's "Notation" table. Conventions: spatial vectors are angular-first
(``cobra_ref.spatial``); floating bases use MuJoCo's free joint (``cobra_ref.model``).
"""

from .dynamics import (
    bias_force,
    body_kinetic_energies,
    crba,
    forward_dynamics,
    kinetic_energy,
    potential_energy,
    rnea,
    spatial_momentum,
)
from .gaits import gait, gait_params
from .infra.arguments import ArgumentError, ArgumentTypeError
from .kinematics import body_jacobian, forward_kinematics, integrate, point_jacobian
from .mjcf import to_mjcf
from .model import Model, ModelError
from .params import CobraParameters
from .provenance import __version__
from .robots import chain, cobra_model, neutral_q, random_state
from .simulate import simulate
from .start import BoxPlacement, initial_state
from .step import SimulationError, StepSettings
from .steppers import make_stepper
from .trajectory import Trajectory


__all__ = [
    "ArgumentError", "ArgumentTypeError", "BoxPlacement", "CobraParameters", "Model", "ModelError", "SimulationError", "StepSettings", "Trajectory",
    "bias_force", "body_jacobian", "body_kinetic_energies", "chain", "cobra_model", "crba", "forward_dynamics",
    "forward_kinematics", "gait", "gait_params", "initial_state", "integrate", "kinetic_energy", "make_stepper",
    "neutral_q", "point_jacobian", "potential_energy", "random_state", "rnea", "simulate", "spatial_momentum",
    "to_mjcf",
]
