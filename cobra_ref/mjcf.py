"""MJCF export of a cobra_ref Model, written with xml.etree only (mujoco is not needed to write it).

Conventions, and where MuJoCo differs from cobra_ref:

* bodies, joints and the order of q / qd are identical: a free body's ``<freejoint/>`` has
  qpos = [x y z qw qx qy qz] and qvel = [world linear velocity, BODY angular velocity], which
  is cobra_ref's convention, so q and qd are passed to MuJoCo unchanged;
* spatial vectors: MuJoCo's ``cvel``/``cacc`` are angular-first like ours but expressed at the
  subtree COM in world axes; the cross-checks compare generalized quantities (M, qfrc_bias,
  point Jacobians, poses), which need no conversion;
* ``<compiler angle="radian"/>`` and w-first quaternions are written explicitly (MJCF's
  default unit is degrees);
* every body has an explicit ``<inertial>`` (MuJoCo must not infer inertia from geoms);
* contact: MuJoCo's contact is soft (solref/solimp), cobra_ref's compliant or rigid (compliance.py).
  ``solref`` (time constant 4 ms = 4 dt, critical damping) is chosen as stiff as MuJoCo's
  stability rule (time constant >= 2 dt) comfortably allows; compare rollouts in bands.
* contact filtering: robot spheres touch the ground and the box, never each other; the box
  touches the ground (contype/conaffinity bits 1 = robot, 2 = environment).
"""

from __future__ import annotations

import xml.etree.ElementTree as ET

import numpy as np

from .model import Model
from .quaternion import rot_to_quat


def _f(x) -> str:
    """Floats at full round-trip precision, space separated."""
    return " ".join(repr(float(v)) for v in np.atleast_1d(x))


_AXIS = {"Rx": "1 0 0", "Ry": "0 1 0", "Rz": "0 0 1"}
# contact bits: robot geoms (1) touch environment geoms (2); the box (2) also touches the ground
_ROBOT_BITS = {"contype": "1", "conaffinity": "2"}
_GROUND_BITS = {"contype": "2", "conaffinity": "3"}
_BOX_BITS = {"contype": "2", "conaffinity": "3"}


def to_mjcf(model: Model, timestep: float = 1e-3, kp: float = 100.0, kv: float = 2.0) -> str:
    """MJCF XML string of ``model``: same bodies, inertials, joints, contact geoms, actuators.

    Helper: the MuJoCo cross-check's model ([MJ] XML reference). Position actuators (gains ``kp``,
    ``kv``, force range +-tau_limit) drive every revolute joint; assumption A7 gives the range.
    ``timestep`` [s] must be finite and within the rule ``validation.RULES["timestep"]`` (at most
    half the contact time constant of 4 ms); a ``ValidationError`` names the value otherwise.
    """
    from .validation import RULES

    timestep = RULES["timestep"].check(timestep, "timestep")
    root = ET.Element("mujoco", model=model.name)
    root.append(ET.Comment(" written by cobra_ref.mjcf.to_mjcf; q/qd order identical to cobra_ref "))
    ET.SubElement(root, "compiler", angle="radian", autolimits="true", inertiafromgeom="false")
    ET.SubElement(root, "option", timestep=_f(timestep), gravity=_f(model.gravity), cone="pyramidal",
                  integrator="implicitfast")
    default = ET.SubElement(root, "default")
    ET.SubElement(default, "geom", friction=_f([model.mu, 0.005, 0.0001]), solref="0.004 1", condim="3")
    world = ET.SubElement(root, "worldbody")
    # per-pair friction through MuJoCo's default rule (the max of the two geoms' coefficients):
    # ground mu, robot and box geoms mu_robot_box (<= mu) -> robot-ground and box-ground get mu,
    # robot-box gets mu_robot_box, as in cobra_ref's contact solve
    ET.SubElement(world, "geom", name="ground", type="plane", size="0 0 1", **_GROUND_BITS)
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

    actuator = ET.SubElement(root, "actuator")
    for i, jt in enumerate(model.joint_type):
        if jt != "free":
            lim = model.tau_limit[i]
            extra = {"forcerange": _f([-lim, lim])} if np.isfinite(lim) else {}
            ET.SubElement(actuator, "position", name=f"act_{model.joint_names[i]}", joint=model.joint_names[i],
                          kp=_f(kp), kv=_f(kv), **extra)
    ET.indent(root)
    return ET.tostring(root, encoding="unicode")


def _add_joint(body: ET.Element, model: Model, i: int) -> None:
    jt = model.joint_type[i]
    if jt == "free":
        ET.SubElement(body, "freejoint", name=model.joint_names[i])
        return
    lim = model.q_limit[i]
    extra = {"range": _f([-lim, lim])} if np.isfinite(lim) else {}
    ET.SubElement(body, "joint", name=model.joint_names[i], type="hinge", axis=_AXIS[jt], **extra)


def _add_geoms(body: ET.Element, model: Model, i: int) -> None:
    """Contact spheres of body i (named sphere_{i}_{k}), its box, and a visual-only cylinder."""
    mine = np.flatnonzero(model.spheres.body == i)
    friction = {"friction": _f([min(model.mu_rb, model.mu), 0.005, 0.0001])}
    for k, s in enumerate(mine):
        ET.SubElement(body, "geom", name=f"sphere_{i}_{k}", type="sphere", size=_f(model.spheres.radius[s]),
                      pos=_f(model.spheres.center[s]), **_ROBOT_BITS, **friction)
    for box in model.boxes:
        if box.body == i:
            ET.SubElement(body, "geom", name=f"box_{i}", type="box", size=_f(box.half), **_BOX_BITS, **friction)
    cyl = model.visual_cylinders[i] if i < len(model.visual_cylinders) else None
    if cyl is not None:
        length, radius, x_c = cyl
        ET.SubElement(body, "geom", name=f"visual_{i}", type="cylinder", size=_f(radius), group="1",
                      fromto=_f([x_c - length / 2, 0, 0, x_c + length / 2, 0, 0]), contype="0",
                      conaffinity="0", mass="0", rgba="0.3 0.5 0.8 0.3")
