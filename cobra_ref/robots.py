"""Model factories: the COBRA + box scene, and small toys for tutorials and tests.

COBRA's geometry (assumptions A1-A3, see :mod:`cobra_ref.params` for every number):

* bodies 0..11 = head, L1..L10, tail; joint k (J0..J10) joins body k and body k+1 and sits on
  the long axis in the middle of the 25 mm gap between the two cylinders;
* every body's x axis runs along the snake **from tail to head** (x points "forward", towards
  the head), z is "up" and y "left" in the straight, upright pose;
* even joints yaw (about body z, 'Rz'), odd joints pitch (about body y, 'Ry'): 6 yaw + 5 pitch,
  J5 = central pitch joint, J6 = central yaw joint (assumption A3);
* the head is the floating base (free joint, frame at the head's centre of mass); the other
  body frames sit at their parent joint (Featherstone), with the COM half a cylinder behind;
* the box (body 12) is a second free body, frame at its centre.

Contact spheres (assumption A16; the MJCF export uses the same ones): each cylinder of
length L and radius r gets n = max(1, round(L / 2r)) spheres of radius r on its axis, evenly
spaced: one per body link (r = 53.5 mm covers the 110 mm cylinder: its half-length is 55 mm),
two on the head, one on the tail. 13 spheres in all. A sphere on the axis with the cylinder's
radius touches the ground exactly where the cylinder would when the link lies on its side, so
rolling about the long axis is reproduced; the rounded ends are the approximation.
"""

from __future__ import annotations

import numpy as np

from .infra import arguments
from .model import BoxGeom, Model, SphereSet
from .params import CobraParameters


def _cylinder_spheres(length: float, radius: float, x_center: float) -> list[tuple[np.ndarray, float]]:
    """Evenly spaced spheres of the cylinder's radius along its axis (see module docstring)."""
    n = max(1, round(length / (2 * radius)))
    xs = x_center - length / 2 + length * (np.arange(n) + 0.5) / n
    return [(np.array([x, 0.0, 0.0]), radius) for x in xs]


def _chain_frames(lengths: list, half_gap: float) -> tuple[list, list, list, list, list, list]:
    """(names, joints, parent, jtype, tree_pos, com) of the robot's bodies: the head on a free
    joint, then one body per joint, even joints yaw (z), odd joints pitch (y) (module docstring)."""
    nb = len(lengths)
    names, joints, parent, jtype, tree_pos, com = [], [], [], [], [], []
    for i in range(nb):
        names.append("head" if i == 0 else "tail" if i == nb - 1 else f"L{i}")
        if i == 0:
            joints.append("base")
            parent.append(-1)
            jtype.append("free")
            tree_pos.append(np.zeros(3))
            com.append(np.zeros(3))
        else:
            joints.append(f"J{i - 1}")
            parent.append(i - 1)
            # even joints yaw (z), odd joints pitch (y)
            jtype.append("Rz" if (i - 1) % 2 == 0 else "Ry")
            # joint i-1 sits half a gap behind the back face of the parent's cylinder:
            # the head's frame is at its centre, every other frame at its own front joint
            back_face = -lengths[0] / 2 if i == 1 else -(half_gap + lengths[i - 1])
            tree_pos.append(np.array([back_face - half_gap, 0.0, 0.0]))
            com.append(np.array([-(half_gap + lengths[i] / 2), 0.0, 0.0]))
    return names, joints, parent, jtype, tree_pos, com


def _add_box(p: CobraParameters, bodies: dict, nb_robot: int) -> tuple:
    """Append the box, a free body with its frame at its centre, to every per-body list of
    ``bodies``; return its ``BoxGeom`` as a 1-tuple."""
    for key, value in (("names", "box"), ("joints", "box_free"), ("parent", -1), ("jtype", "free"),
                       ("tree_pos", np.zeros(3)), ("com", np.zeros(3)), ("masses", p.box_mass),
                       ("I_com", np.eye(3) * p.box_inertia), ("q_limit", np.inf), ("tau_limit", np.inf),
                       ("qd_limit", np.inf), ("visual", None)):
        bodies[key].append(value)
    return (BoxGeom(body=nb_robot, half=np.full(3, p.box_size / 2)),)


def cobra_model(params: CobraParameters | None = None, with_box: bool = True) -> Model:
    """The COBRA snake (12 bodies, 11 joints) with the box as a free body, on flat ground z = 0.

    Robot: nq = 18, nv = 17 (the paper's M is 17 x 17). With the box: nq = 25, nv = 23,
    q = [head x y z qw qx qy qz, theta_0..theta_10, box x y z qw qx qy qz]. The geometry and the
    contact spheres are the module docstring's; every number comes from ``params`` (a
    ``CobraParameters`` or None, else an ``infra.arguments.ArgumentTypeError``).
    """
    arguments.instance("params", params, CobraParameters, "CobraParameters(mu=0.8)", optional=True)
    p = params or CobraParameters()
    n = p.n_body_links
    lengths = [p.length_head] + [p.length_link] * n + [p.length_tail]
    radii = [p.radius_head] + [p.radius_link] * n + [p.radius_tail]
    inertias = [p.inertia_head] + [p.inertia_link] * n + [p.inertia_tail]
    names, joints, parent, jtype, tree_pos, com = _chain_frames(lengths, p.joint_gap / 2)
    # centre of each body's cylinder in its own frame is its COM (homogeneous cylinders)
    sph = [(i, c, r) for i in range(n + 2) for c, r in _cylinder_spheres(lengths[i], radii[i], com[i][0])]
    nb_robot = n + 2
    bodies = dict(names=names, joints=joints, parent=parent, jtype=jtype, tree_pos=tree_pos, com=com,
                  masses=[p.mass_head] + [p.mass_link] * n + [p.mass_tail],
                  I_com=[np.diag(I) for I in inertias],
                  q_limit=[np.inf] + [p.q_max] * (n + 1), tau_limit=[np.inf] + [p.tau_max] * (n + 1),
                  qd_limit=[np.inf] + [p.qd_max] * (n + 1),
                  visual=[(lengths[i], radii[i], com[i][0]) for i in range(nb_robot)])
    boxes = _add_box(p, bodies, nb_robot) if with_box else ()
    nb = len(names)
    return Model(
        name="cobra_box" if with_box else "cobra",
        body_names=tuple(names),
        joint_names=tuple(joints),
        parent=tuple(parent),
        joint_type=tuple(jtype),
        tree_pos=tuple(tree_pos),
        tree_rot=tuple(np.eye(3) for _ in range(nb)),
        mass=tuple(float(m) for m in bodies["masses"]),
        com=tuple(com),
        I_com=tuple(bodies["I_com"]),
        gravity=np.array([0.0, 0.0, -p.gravity]),
        q_limit=tuple(bodies["q_limit"]),
        tau_limit=tuple(bodies["tau_limit"]),
        qd_limit=tuple(bodies["qd_limit"]),
        spheres=SphereSet(
            body=np.array([s[0] for s in sph], dtype=int),
            center=np.array([s[1] for s in sph]),
            radius=np.array([s[2] for s in sph]),
        ),
        boxes=boxes,
        visual_cylinders=tuple(bodies["visual"]),
        mu=p.mu,
        mu_robot_box=p.mu_robot_box,
        mu_box_ground=p.mu_box_ground,
        contact_stiffness=p.contact_stiffness,
        contact_damping=p.contact_damping,
        stiction_velocity=p.stiction_velocity,
        servo_kp=p.servo_kp,
        servo_kd=p.servo_kd,
    )


def chain(n_links: int = 3, link_length: float = 0.3, link_mass: float = 1.0, radius: float = 0.03,
          floating: bool = False) -> Model:
    """A toy serial chain of uniform cylinders hanging from the world (or floating).

    Joints alternate Rz, Ry, Rz, ... like COBRA; link i's frame is at its joint, the cylinder
    extends along -x (the same layout as COBRA's links), one sphere per link at the far end.
    Used by the tutorials and tests as "the smallest model that shows the fact".
    """
    I_rod = np.diag([0.5 * link_mass * radius**2] + [link_mass * (3 * radius**2 + link_length**2) / 12] * 2)
    names = tuple(f"link{i}" for i in range(n_links))
    jtype = tuple(("free" if (floating and i == 0) else ("Rz" if i % 2 == 0 else "Ry")) for i in range(n_links))
    tree_pos = tuple(np.zeros(3) if i == 0 else np.array([-link_length, 0.0, 0.0]) for i in range(n_links))
    limits = tuple(np.inf if jt == "free" else np.pi for jt in jtype)
    return Model(
        name=f"chain{n_links}",
        body_names=names,
        joint_names=tuple(f"j{i}" for i in range(n_links)),
        parent=tuple(range(-1, n_links - 1)),
        joint_type=jtype,
        tree_pos=tree_pos,
        tree_rot=tuple(np.eye(3) for _ in range(n_links)),
        mass=(float(link_mass),) * n_links,
        com=tuple(np.array([-link_length / 2, 0.0, 0.0]) for _ in range(n_links)),
        I_com=(I_rod,) * n_links,
        gravity=np.array([0.0, 0.0, -9.81]),
        q_limit=limits,
        tau_limit=tuple(np.inf for _ in range(n_links)),
        spheres=SphereSet(
            body=np.arange(n_links),
            center=np.tile([-link_length, 0.0, 0.0], (n_links, 1)),
            radius=np.full(n_links, radius),
        ),
        visual_cylinders=tuple((link_length, radius, -link_length / 2) for _ in range(n_links)),
    )


def neutral_q(model: Model) -> np.ndarray:
    """Zero joint angles, identity quaternions, free bodies at the origin.
    """
    q = np.zeros(model.nq)
    for i, jt in enumerate(model.joint_type):
        if jt == "free":
            q[model.q_idx[i].start + 3] = 1.0
    return q


def random_state(model: Model, rng: np.random.Generator, scale: float = 1.0):
    """A random valid (q, qd): random unit quaternions, joint angles within their limits.
    """
    q = np.zeros(model.nq)
    for i, jt in enumerate(model.joint_type):
        iq = model.q_idx[i]
        if jt == "free":
            quat = rng.normal(size=4)
            q[iq] = np.concatenate([rng.normal(size=3) * scale, quat / np.linalg.norm(quat)])
        else:
            lim = min(model.q_limit[i], np.pi)
            q[iq] = rng.uniform(-lim, lim)
    qd = rng.normal(size=model.nv) * scale
    return q, qd
