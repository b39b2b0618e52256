"""cobra_ref: a plain-Python reference implementation of [COBRA] (arXiv 2404.08714).

Non-impulsive contact-implicit loco-manipulation: the 12-body, 11-joint COBRA snake pushes a
box across flat ground. Notation: see the README's "Notation" table. Conventions: spatial
vectors are angular-first (cobra_ref.spatial); floating bases use MuJoCo's free joint
(cobra_ref.model).
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
from .kinematics import body_jacobian, forward_kinematics, integrate, point_jacobian
from .mjcf import to_mjcf
from .model import Model, ModelError
from .params import CobraParameters
from .provenance import __version__
from .robots import chain, cobra_model, neutral_q, random_state


__all__ = [
    "CobraParameters", "Model", "ModelError", "bias_force", "body_jacobian", "body_kinetic_energies",
    "chain", "cobra_model", "crba", "forward_dynamics", "forward_kinematics", "integrate",
    "kinetic_energy", "neutral_q", "point_jacobian", "potential_energy", "random_state", "rnea",
    "spatial_momentum", "to_mjcf",
]
