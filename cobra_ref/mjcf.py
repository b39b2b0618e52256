"""MJCF export of a cobra_ref Model, written with xml.etree only (mujoco is not needed to write it).

``to_mjcf`` is the physics twin; ``playable_mjcf`` adds a keyframe ``start`` (a pose at rest and
the ctrl that holds it) and a checker ground, for opening the file in MuJoCo's viewer
(``cobra-ref export-mjcf``, docs/mujoco.md).

Implements: the MuJoCo twin of the model, with the compliant contact law (assumptions A12, A13,
A22), the position servo (A7) and the mapping of assumption A27 ([MJ] = MuJoCo documentation,
"Computation" / "Parameters" and "Modeling" / "Solver parameters", "Contact parameters").

Conventions, and where MuJoCo differs from cobra_ref:

* bodies, joints and the order of q / qd are identical: a free body's ``<freejoint/>`` has
  qpos = [x y z qw qx qy qz] and qvel = [world linear velocity, BODY angular velocity], which
  is cobra_ref's convention (A19), so q and qd are passed to MuJoCo unchanged;
* spatial vectors: MuJoCo's ``cvel``/``cacc`` are angular-first like ours but expressed at the
  subtree COM in world axes; the cross-checks compare generalized quantities (M, qfrc_bias,
  point Jacobians, poses), which need no conversion;
* ``<compiler angle="radian"/>`` and w-first quaternions are written explicitly (MJCF's
  default unit is degrees); every body has an explicit ``<inertial>``;
* joints: the servo is a ``<position>`` actuator with kp = ``model.servo_kp``, kv =
  ``model.servo_kd`` and force range +-tau_max (A7); the joint range is written but not
  enforced (``limited="false"``), as in cobra_ref, where A4 bounds the references, not the
  dynamics;
* contact: one explicit ``<pair>`` per pair of geoms that may touch (robot sphere-ground,
  robot sphere-box, box-ground; the geoms themselves have contype = conaffinity = 0), so each
  pair gets exactly its coefficient of friction (MuJoCo would otherwise combine two geoms'
  frictions by their maximum) and its own solref (``pair_parameters``).

The contact mapping (A27, ``docs/mujoco.md``). MuJoCo's force on a constraint row obeys
R f = a_ref - a_c ([MJ] "Parameters"), with the regularizer R = (1 - d) / d A_hat, the impedance
d (``solimp``), A_hat MuJoCo's approximation of the row's inverse mass, and the reference
acceleration a_ref = -b v - k r; in the direct solref format (-stiffness, -damping) with a
constant impedance d, b = damping / d and k = stiffness / d. Hence, on a normal row
(r: the signed distance, v its rate)::

    f = -(damping v + stiffness r) / ((1 - d) A_hat)  -  d / (1 - d) a_c / A_hat

With d = ``IMPEDANCE`` (MuJoCo's smallest, 1e-4), stiffness = k (1 - d) A_hat and
damping = c (1 - d) A_hat, this is f = -k r - c v, cobra_ref's spring-damper (A12), up to the
last term, 1e-4 of the contact's acceleration times 1 / A_hat (0 at rest; below 1 % of the force
at accelerations of 1e4 m/s^2). A_hat is MuJoCo's ``body_invweight0`` sum of the pair's bodies, which
``inverse_weights`` computes from our own M and Jacobians, so the force does not depend on the
true effective mass. The friction rows of the elliptic cone (condim 3) have R_T = R / impratio;
with ``IMPRATIO`` they are hard (R_T << A_TT) and their slip decays at the rate b_T = mu g / v_s,
the rate at which A13's sticking branch stops a body that rests on its contacts.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from .dynamics import crba
from .kinematics import forward_kinematics, point_jacobian
from .model import Model
from .quaternion import rot_to_quat
from .robots import neutral_q

IMPEDANCE = 1e-4  # d: MuJoCo's smallest impedance (mjMINIMP); its force is then the spring-damper's (A27)
IMPRATIO = 1e6  # R_T = R / IMPRATIO: hard friction rows, the cone keeps the normal force (A27)
TIMESTEP = 5e-5  # [s] MuJoCo integrates the contact force explicitly: stable and accurate below it (A27, docs/mujoco.md)
GROUND = "ground"
KEY = "start"  # the keyframe of ``playable_mjcf``
_AXIS = {"Rx": "1 0 0", "Ry": "0 1 0", "Rz": "0 0 1"}
_NO_COLLISION = {"contype": "0", "conaffinity": "0"}  # every contact comes from an explicit <pair>


def _f(x) -> str:
    """Floats at full round-trip precision, space separated."""
    return " ".join(repr(float(v)) for v in np.atleast_1d(x))


def to_mjcf(model: Model, timestep: float = TIMESTEP) -> str:
    """MJCF XML string of ``model``: same bodies, inertials, joints, contact geoms, servo and contact law.

    Implements: the MuJoCo twin of the module docstring (assumption A27): position actuators
    kp = ``model.servo_kp``, kv = ``model.servo_kd``, |force| <= tau_max (A7); elliptic cone,
    condim 3, one ``<pair>`` per touching pair with ``pair_parameters``; integrator implicitfast
    (kv implicit). ``timestep`` [s] must be finite and within ``validation.RULES["timestep"]``
    (a ``ValidationError`` names the value otherwise); the default ``TIMESTEP`` is the one
    measured stable and converged for COBRA and the box (``docs/mujoco.md``).
    """
    from .infra import arguments
    from .infra.validation import RULES

    arguments.instance("model", model, Model, "cobra_model()")
    timestep = RULES["timestep"].check(timestep, "timestep")
    root = ET.Element("mujoco", model=model.name)
    root.append(ET.Comment(" written by cobra_ref.mjcf.to_mjcf; q/qd order identical to cobra_ref "))
    ET.SubElement(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="false")
    ET.SubElement(root, "option", timestep=_f(timestep), gravity=_f(model.gravity), cone="elliptic",
                  impratio=_f(IMPRATIO), integrator="implicitfast")
    world = ET.SubElement(root, "worldbody")
    ET.SubElement(world, "geom", name=GROUND, type="plane", size="0 0 1", **_NO_COLLISION)
    ET.SubElement(world, "light", pos="0 0 3", dir="0 0 -1", directional="true")
    elements = []
    for i in range(model.nb):
        parent_el = world if model.parent[i] < 0 else elements[model.parent[i]]
        body = ET.SubElement(parent_el, "body", name=model.body_names[i], pos=_f(model.tree_pos[i]),
                             quat=_f(rot_to_quat(model.tree_rot[i])))
        elements.append(body)
        _add_joint(body, model, i)
        I_com = np.asarray(model.I_com[i])
        ET.SubElement(body, "inertial", pos=_f(model.com[i]), mass=_f(model.mass[i]),
                      fullinertia=_f([I_com[0, 0], I_com[1, 1], I_com[2, 2], I_com[0, 1], I_com[0, 2], I_com[1, 2]]))
        _add_geoms(body, model, i)
    _add_actuators(ET.SubElement(root, "actuator"), model)
    contact = ET.SubElement(root, "contact")
    for geom1, geom2, params in pair_parameters(model):
        ET.SubElement(contact, "pair", geom1=geom1, geom2=geom2, **params)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")


def _add_joint(body: ET.Element, model: Model, i: int) -> None:
    """Body i's joint: a free joint, or a hinge whose range is recorded but not enforced (A4)."""
    jt = model.joint_type[i]
    if jt == "free":
        ET.SubElement(body, "freejoint", name=model.joint_names[i])
        return
    lim = model.q_limit[i]
    extra = {"range": _f([-lim, lim]), "limited": "false"} if np.isfinite(lim) else {}
    ET.SubElement(body, "joint", name=model.joint_names[i], type="hinge", axis=_AXIS[jt], **extra)


def _add_geoms(body: ET.Element, model: Model, i: int) -> None:
    """Contact spheres of body i (named sphere_{i}_{k}), its box, and a visual-only cylinder."""
    for k, s in enumerate(np.flatnonzero(model.spheres.body == i)):
        ET.SubElement(body, "geom", name=f"sphere_{i}_{k}", type="sphere", size=_f(model.spheres.radius[s]),
                      pos=_f(model.spheres.center[s]), **_NO_COLLISION)
    for box in model.boxes:
        if box.body == i:
            ET.SubElement(body, "geom", name=f"box_{i}", type="box", size=_f(box.half), **_NO_COLLISION)
    cyl = model.visual_cylinders[i] if i < len(model.visual_cylinders) else None
    if cyl is not None:
        length, radius, x_c = cyl
        ET.SubElement(body, "geom", name=f"visual_{i}", type="cylinder", size=_f(radius), group="1",
                      fromto=_f([x_c - length / 2, 0, 0, x_c + length / 2, 0, 0]), mass="0",
                      rgba="0.3 0.5 0.8 0.3", **_NO_COLLISION)


def _add_actuators(actuator: ET.Element, model: Model) -> None:
    """One position actuator per hinge: force = kp (ctrl - q) - kv qd, clipped to +-tau_max (A7)."""
    for i, jt in enumerate(model.joint_type):
        if jt == "free":
            continue
        lim = model.tau_limit[i]
        extra = {"forcelimited": "true", "forcerange": _f([-lim, lim])} if np.isfinite(lim) else {}
        ET.SubElement(actuator, "position", name=f"act_{model.joint_names[i]}", joint=model.joint_names[i],
                      kp=_f(model.servo_kp), kv=_f(model.servo_kd), **extra)


def inverse_weights(model: Model) -> np.ndarray:
    """(nb,) each body's translational inverse weight at qpos0: MuJoCo's ``body_invweight0[:, 0]`` [1/kg].

    Implements: MuJoCo's diagonal approximation A_hat of a contact row's inverse mass ([MJ]
    "Parameters", "Diagonal approximation"): for body i, the mean of the diagonal of
    J_i M^-1 J_i^T, with J_i the (3, nv) Jacobian of its centre of mass, at zero joint angles
    (MuJoCo's qpos0; a rigid motion of the whole leaves it unchanged). A contact row between
    bodies a and b then has A_hat = w_a + w_b (the ground: 0).
    """
    q = neutral_q(model)
    kin = forward_kinematics(model, q)
    M = crba(model, q)
    w = np.zeros(model.nb)
    for i in range(model.nb):
        J_i = point_jacobian(model, q, i, model.com[i], kin)
        # w_i = trace(J_i M^-1 J_i^T) / 3
        w[i] = np.trace(J_i @ np.linalg.solve(M, J_i.T)) / 3.0
    return w


def pair_parameters(model: Model) -> list[tuple[str, str, dict]]:
    """(geom1, geom2, attributes) of every ``<pair>``: robot sphere-ground, robot sphere-box, box-ground.

    Implements: the contact mapping of assumption A27 (module docstring), per pair with
    A_hat = w_a + w_b (``inverse_weights``) and the pair's mu (A13: ``model.mu`` robot-ground,
    ``model.mu_bg`` box-ground, A22: ``model.mu_rb`` robot-box)::

        solimp         = (d, d, 0.001, 0.5, 2)                     # constant impedance d
        solref         = (-k (1 - d) A_hat, -c (1 - d) A_hat)       # normal: f = -k r - c v
        solreffriction = (0, -d mu g / v_s)                          # friction: b_T = mu g / v_s
        friction       = (mu, mu, 0, 0, 0), condim 3

    with k, c = ``model.contact_stiffness``, ``model.contact_damping``, v_s =
    ``model.stiction_velocity`` and g = |``model.gravity``|.
    """
    w = inverse_weights(model)
    sphere_geoms = [(int(b), f"sphere_{b}_{int(np.sum(model.spheres.body[:s] == b))}")
                    for s, b in enumerate(model.spheres.body)]
    pairs = [(GROUND, name, w[b], model.mu) for b, name in sphere_geoms]
    for box in model.boxes:
        pairs += [(f"box_{box.body}", name, w[b] + w[box.body], model.mu_rb) for b, name in sphere_geoms]
        pairs.append((GROUND, f"box_{box.body}", w[box.body], model.mu_bg))
    return [(geom1, geom2, _pair_attributes(model, A_hat, mu)) for geom1, geom2, A_hat, mu in pairs]


def _pair_attributes(model: Model, A_hat: float, mu: float) -> dict:
    """The attributes of one pair with inverse weight A_hat and friction mu (``pair_parameters``)."""
    d, g = IMPEDANCE, float(np.linalg.norm(model.gravity))
    b_T = mu * g / model.stiction_velocity
    return {"condim": "3", "friction": _f([mu, mu, 0.0, 0.0, 0.0]),
            "solref": _f([-model.contact_stiffness * (1 - d) * A_hat, -model.contact_damping * (1 - d) * A_hat]),
            "solreffriction": _f([0.0, -d * b_T]), "solimp": _f([d, d, 0.001, 0.5, 2.0])}


def joint_angles(model: Model, q) -> np.ndarray:
    """The hinge angles of ``q`` in actuator order (the order of ``model.joint_type``'s hinges).

    The ``ctrl`` that holds the pose ``q``: a position actuator's force kp (ctrl - q) - kv qd is
    0 at ctrl = q, qd = 0 (A7).
    """
    q = np.asarray(q, dtype=float)
    return np.array([q[model.q_idx[i].start] for i, jt in enumerate(model.joint_type) if jt != "free"])


def playable_mjcf(model: Model, q, timestep: float = TIMESTEP) -> str:
    """``to_mjcf(model)`` with what opening it in MuJoCo's viewer needs: a keyframe ``start``
    (qpos = ``q``, ctrl = its joint angles, qvel = 0), a checker-textured ground and an orange box.

    Implements: the pose ``q`` as a state MuJoCo can reset to (``mj_resetDataKeyframe``); with a
    settled ``q`` (A25) the robot and the box rest on the ground from there, the joints held
    where they are. The physics is ``to_mjcf``'s: only visual attributes and the key are added.
    """
    q = model.check_q(q)
    parser = ET.XMLParser(target=ET.TreeBuilder(insert_comments=True))
    root = ET.fromstring(to_mjcf(model, timestep), parser=parser)
    asset = ET.Element("asset")
    ET.SubElement(asset, "texture", name="floor", type="2d", builtin="checker", rgb1="0.7 0.7 0.7",
                  rgb2="0.55 0.55 0.55", width="64", height="64")
    ET.SubElement(asset, "material", name="floor", texture="floor", texrepeat="5 5", texuniform="true")
    root.insert(list(root).index(root.find("worldbody")), asset)
    for geom in root.iter("geom"):
        if geom.get("name") == GROUND:
            geom.set("material", "floor")
        elif geom.get("name", "").startswith("box_"):
            geom.set("rgba", "0.9 0.5 0.15 1")
    keyframe = ET.SubElement(root, "keyframe")
    ET.SubElement(keyframe, "key", name=KEY, qpos=_f(q), ctrl=_f(joint_angles(model, q)))
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")
