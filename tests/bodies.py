"""Small models for worked examples: one free rigid body (a ball, a box), a sphere beside a box, and
COBRA tumbling in free flight.

A free body has no revolute joint, so the servo has nothing to drive and every test below is
a hand-solvable rigid body on the ground (M of its coordinates is blockdiag(m 1, I_com)).
"""

import numpy as np

from cobra_ref.kinematics import forward_kinematics
from cobra_ref.model import BoxGeom, Model, SphereSet
from cobra_ref.params import CobraParameters
from cobra_ref.robots import cobra_model, random_state
from cobra_ref.step import StepSettings
from cobra_ref.steppers import make_stepper

GRAVITY = 9.81  # [m/s^2]
BALL_MASS, BALL_RADIUS = 1.0, 0.1  # [kg], [m]
BOX_MASS, BOX_SIDE = 0.5, 0.1  # [kg], [m]
NO_SPHERES = SphereSet(body=np.zeros(0, dtype=int), center=np.zeros((0, 3)), radius=np.zeros(0))


def free_body(name, mass, I_com, spheres=NO_SPHERES, boxes=(), gravity=(0.0, 0.0, -GRAVITY), **law):
    """One rigid body on a free joint, centre of mass at its origin; ``law``: mu, contact_stiffness, ..."""
    return Model(name=name, body_names=(name,), joint_names=("free",), parent=(-1,), joint_type=("free",),
                 tree_pos=(np.zeros(3),), tree_rot=(np.eye(3),), mass=(float(mass),), com=(np.zeros(3),),
                 I_com=(np.asarray(I_com, dtype=float),), gravity=np.asarray(gravity, dtype=float),
                 q_limit=(np.inf,), tau_limit=(np.inf,), spheres=spheres, boxes=boxes, **law)


def ball_inertia(mass=BALL_MASS, radius=BALL_RADIUS):
    return 0.4 * mass * radius**2 * np.eye(3)  # solid sphere, 2/5 m r^2


def box_inertia(mass=BOX_MASS, side=BOX_SIDE):
    return mass * side**2 / 6 * np.eye(3)  # cube, m a^2 / 6


def ball(mass=BALL_MASS, radius=BALL_RADIUS, **law):
    spheres = SphereSet(body=np.zeros(1, dtype=int), center=np.zeros((1, 3)), radius=np.array([radius]))
    return free_body("ball", mass, ball_inertia(mass, radius), spheres, **law)


def box(**law):
    return free_body("box", BOX_MASS, box_inertia(), boxes=(BoxGeom(body=0, half=np.full(3, BOX_SIDE / 2)),), **law)


def at_height(model, height, v=(0.0, 0.0, 0.0), w=(0.0, 0.0, 0.0)):
    """(q, qd): the body's origin at (0, 0, height), unturned, with linear velocity v and body angular velocity w."""
    q = np.zeros(model.nq)
    q[:7] = [0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0]
    qd = np.zeros(model.nv)
    qd[:3], qd[3:6] = v, w
    return q, qd


def no_joints(t):
    """The reference of a model without revolute joints."""
    return np.zeros(0), np.zeros(0), np.zeros(0)


def run(model, q, qd, n_steps, settings=StepSettings(), stepper="fast", tau_ext=None, reference=no_joints):
    """Take n_steps steps from (q, qd) at t = 0 with a new stepper named ``stepper``
    (``steppers.STEPPERS``); returns the final (q, qd) and every StepResult."""
    stepping, results = make_stepper(stepper, model, settings), []
    for k in range(n_steps):
        res = stepping.step(q, qd, k * settings.dt, reference, tau_ext)
        q, qd = res.q, res.qd
        results.append(res)
    return q, qd, results


def sphere_and_box(mu, sphere_mass=0.5, sphere_radius=0.03, mu_robot_box=None):
    """A free sphere (body 0, a 'robot link') and the box (body 1), each on its own free joint."""
    sphere = SphereSet(body=np.zeros(1, dtype=int), center=np.zeros((1, 3)), radius=np.array([sphere_radius]))
    return Model(name="sphere_box", body_names=("sphere", "box"), joint_names=("free", "box_free"),
                 parent=(-1, -1), joint_type=("free", "free"), tree_pos=(np.zeros(3),) * 2,
                 tree_rot=(np.eye(3),) * 2, mass=(sphere_mass, BOX_MASS), com=(np.zeros(3),) * 2,
                 I_com=(ball_inertia(sphere_mass, sphere_radius), box_inertia()),
                 gravity=np.array([0.0, 0.0, -GRAVITY]), q_limit=(np.inf,) * 2, tau_limit=(np.inf,) * 2,
                 spheres=sphere, boxes=(BoxGeom(body=1, half=np.full(3, BOX_SIDE / 2)),), mu=mu,
                 mu_robot_box=mu_robot_box)


def pressed_box_state(model, reference, depth):
    """The start q with the box placed against the middle links (gap 0, ``start.placed_state``) and
    then moved ``depth`` [m] further towards them: a box pressed into the robot. (A placement's gap
    is >= 0 by its rule; a test that needs the box pressed moves it itself.)"""
    from cobra_ref.start import BoxPlacement, placed_state

    box = model.q_idx[model.boxes[0].body].start
    touching = placed_state(model, reference, BoxPlacement(gap=0.0))
    apart = placed_state(model, reference, BoxPlacement(gap=0.01))
    away = apart[box:box + 2] - touching[box:box + 2]  # from the robot towards the box, 1 cm long
    q = touching.copy()
    q[box:box + 2] -= depth * away / np.linalg.norm(away)
    return q


def cobra_in_free_flight(seed=7):
    """(model, q0, qd0): COBRA without gravity or box, joint torques under 1e-12 N m, tumbling from a
    random state (``robots.random_state``) 100 m above the ground, where no contact is a candidate."""
    model = cobra_model(CobraParameters(gravity=0.0, tau_max=1e-12), with_box=False)
    q0, qd0 = random_state(model, np.random.default_rng(seed), scale=1.0)
    q0[2] = 100.0
    return model, q0, qd0


def hold_joints(t):
    """The reference that holds COBRA's 11 joints at zero (with tau_max = 1e-12, no torque)."""
    return np.zeros(11), np.zeros(11), np.zeros(11)


def centre_of_mass(model, q):
    """(3,) the centre of mass of every body of ``model`` at q [m]."""
    kin = forward_kinematics(model, q)
    points = [kin.o[i] + kin.R[i] @ model.com[i] for i in range(model.nb)]
    return np.average(points, axis=0, weights=model.mass)
