"""Which code made a result: the package version and a hash of the physics source.

A cached run, a figure's stamp and an optimizer's params JSON record ``physics_hash()``: the
SHA-256 of the source of the modules a simulation executes, listed in ``PHYSICS_MODULES`` (and,
for the optimizer, the cost in ``PLANNING_MODULES``). Only those files count, so editing the
documentation, the command line, the figures or the infrastructure leaves every cache entry and
every optimum's stamp valid; editing one line of the physics invalidates them all. A new physics
module must be added to the list (``tests/test_provenance.py`` checks that every module the
steppers import is on it).
"""

from __future__ import annotations

import hashlib
import os

__version__ = "0.2.0.dev0"

# the modules a simulation runs, relative to the package folder
PHYSICS_MODULES = (
    "spatial.py", "quaternion.py", "joints.py", "model.py", "params.py", "robots.py", "kinematics.py",
    "dynamics.py", "gaps.py", "contact.py", "compliance.py", "qp.py", "least_action.py", "coulomb_newton.py",
    "step.py", "steppers.py", "start.py", "placement.py", "simulate.py", "gaits.py", "reference.py",
    "trajectory.py", "touchdown.py",
    "fast/chain.py", "fast/contacts.py", "fast/gaps.py", "fast/least_action.py", "fast/active_set.py",
    "fast/stepper.py", "batch.py", "fast/batch.py", "fast/members.py", "fast/newton_batch.py",
    "fast/problem_batch.py", "fast/iterate_batch.py", "fast/box_batch.py",
)
# ... and the optimizer's cost and rollout
PLANNING_MODULES = ("planning/cost.py", "planning/problem.py")

_PACKAGE = os.path.dirname(os.path.abspath(__file__))


def physics_hash(extra: tuple = ()) -> str:
    """SHA-256 of the source of ``PHYSICS_MODULES`` and the modules in ``extra`` (paths as listed).

    A listed module that does not exist is skipped by name (its absence is hashed too)."""
    h = hashlib.sha256()
    for name in PHYSICS_MODULES + tuple(extra):
        path = os.path.join(_PACKAGE, name)
        h.update(name.encode())
        if os.path.isfile(path):
            with open(path, "rb") as f:
                h.update(f.read())
    return h.hexdigest()


def code_version(planning: bool = False) -> dict:
    """{"version", "physics_sha256"}: what a params JSON or a cache entry records of the code."""
    return {"version": __version__,
            "physics_sha256": physics_hash(PLANNING_MODULES if planning else ())}
