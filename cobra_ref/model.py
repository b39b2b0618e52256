"""The Model: constant description of a kinematic tree with contact geometry. Never mutated.

A Model is a forest of rigid bodies (spatial_v2's ``model`` struct, Pinocchio's ``Model``):
body ``i`` hangs from ``parent[i]`` (``-1`` = world) through joint ``i`` of type
``joint_type[i]``; bodies are ordered so that ``parent[i] < i``.

Frames (Featherstone's convention): body ``i``'s frame is the successor frame of joint ``i``.
``tree_pos[i]`` / ``tree_rot[i]`` place joint ``i``'s predecessor frame in the parent's frame
(the MJCF ``<body pos quat>``), so ``X_tree[i] = plux(tree_rot[i]^T, tree_pos[i])``.
Each body carries ``mass[i]``, centre of mass ``com[i]`` (body frame) and rotational inertia
``I_com[i]`` about the COM (body axes); ``I[i] = mcI(mass, com, I_com)``.

Coordinates follow MuJoCo exactly, so that MuJoCo is a direct oracle:

* ``'free'``: q_i = [x, y, z, qw, qx, qy, qz] (7), qd_i = [linear velocity of the body origin in
  WORLD coordinates (3), angular velocity in BODY coordinates (3)] (6);
* ``'Rx' | 'Ry' | 'Rz'``: one angle about the body's x / y / z axis (1, 1).

For a floating base nq != nv and qd is not dq/dt: positions advance with
:func:`cobra_ref.kinematics.integrate`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .infra.validation import MODEL_NUMBERS, PARAMETER_RULES, ValidationError
from .spatial import mcI, plux

JOINT_NQ = {"free": 7, "Rx": 1, "Ry": 1, "Rz": 1}
JOINT_NV = {"free": 6, "Rx": 1, "Ry": 1, "Rz": 1}


class ModelError(ValueError):
    """A model or a state that cannot be used (the message names the problem)."""


@dataclass(frozen=True)
class SphereSet:
    """Contact spheres as struct-of-arrays: ``center[k]`` in the frame of ``body[k]``."""

    body: np.ndarray  # (ns,) int
    center: np.ndarray  # (ns, 3)
    radius: np.ndarray  # (ns,)


@dataclass(frozen=True)
class BoxGeom:
    """A box-shaped body: ``half`` half-extents along the axes of ``body``'s frame, centred at its origin."""

    body: int
    half: np.ndarray  # (3,)


@dataclass(frozen=True, eq=False)
class Model:
    """Constant description of the tree, its inertias, limits and contact geometry."""

    name: str
    body_names: tuple[str, ...]
    joint_names: tuple[str, ...]
    parent: tuple[int, ...]
    joint_type: tuple[str, ...]
    tree_pos: tuple[np.ndarray, ...]
    tree_rot: tuple[np.ndarray, ...]
    mass: tuple[float, ...]
    com: tuple[np.ndarray, ...]
    I_com: tuple[np.ndarray, ...]
    gravity: np.ndarray
    q_limit: tuple[float, ...]  # |q| <= q_limit per revolute joint (inf for free joints)
    tau_limit: tuple[float, ...]  # |tau| <= tau_limit per revolute joint (inf for free joints)
    spheres: SphereSet
    boxes: tuple[BoxGeom, ...] = ()
    # body cylinders for pictures and the MJCF's visual geoms: (length, radius, x offset) per body
    visual_cylinders: tuple[tuple[float, float, float] | None, ...] = ()
    mu: float = 1.0  # Coulomb friction of robot-ground and box-ground contacts
    mu_robot_box: float | None = None  # robot-box contacts; None = the same as mu (see mu_rb)
    mu_box_ground: float | None = None  # box-ground contacts; None = the same as mu (see mu_bg)
    # the compliant contact law and the joint servo (cobra_ref.compliance; CobraParameters' sources)
    contact_stiffness: float = 1e6  # k [N/m]
    contact_damping: float = 1e3  # d [N s/m]
    stiction_velocity: float = 1e-3  # v_s [m/s] of the smooth stick-slip friction
    servo_kp: float = 500.0  # [N m/rad]
    servo_kd: float = 5.0  # [N m s/rad]
    qd_limit: tuple[float, ...] = ()  # |qd| <= qd_limit per revolute joint, reported (empty: none)
    # derived in __post_init__
    X_tree: tuple[np.ndarray, ...] = field(init=False)
    I: tuple[np.ndarray, ...] = field(init=False)
    q_idx: tuple[slice, ...] = field(init=False)
    v_idx: tuple[slice, ...] = field(init=False)

    @property
    def mu_rb(self) -> float:
        """Friction coefficient of robot-box contacts: mu_robot_box, or mu when that is None."""
        return self.mu if self.mu_robot_box is None else self.mu_robot_box

    @property
    def mu_bg(self) -> float:
        """Friction coefficient of box-ground contacts: mu_box_ground, or mu when that is None."""
        return self.mu if self.mu_box_ground is None else self.mu_box_ground

    def __post_init__(self):
        _validate(self)
        X_tree = tuple(plux(R.T, p) for R, p in zip(self.tree_rot, self.tree_pos))
        I = tuple(mcI(m, c, Ic) for m, c, Ic in zip(self.mass, self.com, self.I_com))
        q_idx, v_idx, iq, iv = [], [], 0, 0
        for jt in self.joint_type:
            q_idx.append(slice(iq, iq + JOINT_NQ[jt]))
            v_idx.append(slice(iv, iv + JOINT_NV[jt]))
            iq, iv = iq + JOINT_NQ[jt], iv + JOINT_NV[jt]
        object.__setattr__(self, "X_tree", X_tree)
        object.__setattr__(self, "I", I)
        object.__setattr__(self, "q_idx", tuple(q_idx))
        object.__setattr__(self, "v_idx", tuple(v_idx))

    @property
    def nb(self) -> int:
        """Number of bodies."""
        return len(self.parent)

    @property
    def nq(self) -> int:
        """Length of q."""
        return sum(JOINT_NQ[j] for j in self.joint_type)

    @property
    def nv(self) -> int:
        """Length of qd (degrees of freedom)."""
        return sum(JOINT_NV[j] for j in self.joint_type)

    def body_index(self, body: int | str) -> int:
        """Index of a body given by index or name, with a clear error."""
        if isinstance(body, (int, np.integer)):
            if not 0 <= body < self.nb:
                raise ModelError(f"body index {body} out of range 0..{self.nb - 1}")
            return int(body)
        if body not in self.body_names:
            raise ModelError(f"unknown body {body!r}; bodies are {', '.join(self.body_names)}")
        return self.body_names.index(body)

    def check_q(self, q) -> np.ndarray:
        """Return q as a float array after checking length, finiteness and unit quaternions."""
        q = _as_vector(q, self.nq, "q")
        for i, jt in enumerate(self.joint_type):
            if jt == "free":
                quat = q[self.q_idx[i]][3:]
                norm = float(np.linalg.norm(quat))
                if norm == 0.0:
                    raise ModelError(f"q: zero quaternion for free body {self.body_names[i]!r}")
                if abs(norm - 1.0) > 1e-6:
                    raise ModelError(
                        f"q: non-unit quaternion for free body {self.body_names[i]!r} "
                        f"(norm {norm:.6g}); normalize it first"
                    )
        return q

    def check_qd(self, qd, name: str = "qd") -> np.ndarray:
        """Return a generalized velocity (or acceleration/force) as a checked float array."""
        return _as_vector(qd, self.nv, name)


def _as_vector(x, n: int, name: str) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    if x.shape != (n,):
        raise ModelError(f"{name}: expected shape ({n},), got {x.shape}")
    if not np.all(np.isfinite(x)):
        bad = np.flatnonzero(~np.isfinite(x)).tolist()
        raise ModelError(f"{name}: non-finite entries (NaN or inf) at indices {bad}")
    return x


def _validate(model: Model) -> None:
    """Reject a model that is not a physical tree (clear message naming body and problem)."""
    nb = len(model.parent)
    per_body = ("body_names", "joint_names", "joint_type", "tree_pos", "tree_rot", "mass", "com",
                "I_com", "q_limit", "tau_limit")
    for name in per_body:
        if len(getattr(model, name)) != nb:
            raise ModelError(f"{name} has {len(getattr(model, name))} entries, expected {nb} (one per body)")
    _check_numbers(model)
    for i in range(nb):
        who = f"body {i} ({model.body_names[i]!r})"
        if not -1 <= model.parent[i] < i:
            raise ModelError(f"{who}: parent {model.parent[i]} must be -1 or a lower index")
        if model.joint_type[i] not in JOINT_NQ:
            raise ModelError(f"{who}: unknown joint type {model.joint_type[i]!r}; use {sorted(JOINT_NQ)}")
        if not (np.isfinite(model.mass[i]) and model.mass[i] > 0):
            raise ModelError(f"{who}: mass must be positive and finite, got {model.mass[i]}")
        _check_inertia(who, np.asarray(model.I_com[i], dtype=float))
        R = np.asarray(model.tree_rot[i], dtype=float)
        if R.shape != (3, 3) or not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
            raise ModelError(f"{who}: tree_rot is not a rotation matrix")


def _check_numbers(model: Model) -> None:
    """The friction, contact-law and servo numbers by the rules ``CobraParameters`` checks them by
    (``validation.PARAMETER_RULES``, one rule set for both); None is "the same as mu" for the
    robot-box and box-ground friction."""
    for name in MODEL_NUMBERS:
        value = getattr(model, name)
        if value is None and name in ("mu_robot_box", "mu_box_ground"):
            continue
        try:
            PARAMETER_RULES[name].check(value, name)
        except ValidationError as exc:
            raise ModelError(str(exc)) from None


def _check_inertia(who: str, I_com: np.ndarray) -> None:
    if I_com.shape != (3, 3) or not np.all(np.isfinite(I_com)):
        raise ModelError(f"{who}: inertia must be a finite 3x3 matrix")
    if not np.allclose(I_com, I_com.T, atol=1e-12):
        raise ModelError(f"{who}: inertia is not symmetric")
    eig = np.linalg.eigvalsh(I_com)
    if eig[0] <= 0:
        raise ModelError(f"{who}: inertia is not positive definite (eigenvalues {eig})")
    # a rigid body's principal moments satisfy the triangle inequality (I1 + I2 >= I3)
    if eig[0] + eig[1] < eig[2] * (1 - 1e-9):
        raise ModelError(f"{who}: inertia violates the triangle inequality (eigenvalues {eig})")
