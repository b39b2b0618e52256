"""The time stepper (cobra_ref.fast.stepper) on the smallest models: a ball and a box on the ground.

One step of [COBRA] eq. (1) with the impulses of eq. (5)-(6) (semi-implicit Euler)::

    M (u+ - u) = dt (tau - h) + J_c^T p,     q+ = q (+) dt u+.

For one free rigid body at rest or sliding, this is hand-solvable: gravity adds -g dt to the
velocity each step, the contact impulse takes out exactly what the Signorini-Coulomb law of
eq. (2) allows, and the position advances with the NEW velocity.

The models. Each "single rigid body" here is built as two coincident halves (each with
half the mass and half the inertia, centres of mass at the same point) joined by one revolute
joint that the prescribed servo holds at 0: u+ of that joint is (0 - 0) / dt = 0 every step,
the halves move as one body of the full mass and inertia (checked first, below), and the
stepper's free coordinates are exactly the body's 6. (This also exercises the prescribed
servo; a lone free body with no joint at all is stepped by its own test at the end.)

Settings: StepSettings() defaults, dt = 1e-3 s, beta = 0.2; ContactQP regularization
REG = 1e-6 (P = G + REG mean(diag G) I, contact_qp module docstring).
"""


import numpy as np
import pytest

from cobra_ref.fast.chain import ChainModel
from cobra_ref.model import BoxGeom, Model, SphereSet
from cobra_ref.simulate import simulate
from cobra_ref.fast.stepper import StepSettings, Stepper

GRAVITY = 9.81  # [m/s^2]
DT = 1e-3  # [s]
REG = 1e-6  # ContactQP's default regularization factor
BETA = StepSettings().beta  # fraction of a penetration removed per step

BALL_MASS, BALL_RADIUS = 1.0, 0.1  # [kg], [m]
BOX_MASS, BOX_SIDE = 0.5, 0.1  # [kg], [m]
NO_SPHERES = SphereSet(body=np.zeros(0, dtype=int), center=np.zeros((0, 3)), radius=np.zeros(0))
BOTTOM_FRONT, BOTTOM_REAR = (4, 6), (0, 2)  # box_corners order: signs (x, y, z), z = -1, x = +1 / -1


def _locked_rigid_body(name, mass, I_com, spheres, boxes=(), mu=1.0, gravity=(0.0, 0.0, -GRAVITY), n_locks=1):
    """One rigid body as n_locks + 1 coincident pieces on a free joint, locked by prescribed joints.

    Piece k has mass m / (n_locks + 1) and inertia I_com / (n_locks + 1) about the common
    origin (= centre of mass); joints alternate Rz, Ry like COBRA's. Geometry hangs on piece 0.
    """
    n = n_locks + 1
    return Model(
        name=name,
        body_names=tuple(f"{name}{k}" for k in range(n)),
        joint_names=("free",) + tuple(f"lock{k}" for k in range(n_locks)),
        parent=tuple(range(-1, n - 1)),
        joint_type=("free",) + tuple("Rz" if k % 2 == 0 else "Ry" for k in range(n_locks)),
        tree_pos=(np.zeros(3),) * n,
        tree_rot=(np.eye(3),) * n,
        mass=(mass / n,) * n,
        com=(np.zeros(3),) * n,
        I_com=(np.asarray(I_com) / n,) * n,
        gravity=np.asarray(gravity, dtype=float),
        q_limit=(np.inf,) * n,
        tau_limit=(np.inf,) * n,
        spheres=spheres,
        boxes=boxes,
        mu=mu,
    )


def _hold(n_joints):
    """Joint reference for simulate / Stepper.step: every joint held at 0 (q, qd, qdd)."""
    return lambda t: (np.zeros(n_joints),) * 3


def _ball_inertia():
    return 0.4 * BALL_MASS * BALL_RADIUS**2 * np.eye(3)  # solid sphere, 2/5 m r^2


def _box_inertia():
    return BOX_MASS * BOX_SIDE**2 / 6 * np.eye(3)  # cube, m a^2 / 6


def _ball(**kw):
    spheres = SphereSet(body=np.zeros(1, dtype=int), center=np.zeros((1, 3)), radius=np.array([BALL_RADIUS]))
    return _locked_rigid_body("ball", BALL_MASS, _ball_inertia(), spheres, **kw)


def _box(**kw):
    return _locked_rigid_body("box", BOX_MASS, _box_inertia(), NO_SPHERES,
                              (BoxGeom(body=0, half=np.full(3, BOX_SIDE / 2)),), **kw)


def _at_rest_on_ground(model, height, v=(0.0, 0.0, 0.0)):
    """q: body origin at (0, 0, height), identity orientation, locks at 0; qd: linear velocity v."""
    q = np.zeros(model.nq)
    q[:7] = [0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0]
    qd = np.zeros(model.nv)
    qd[:3] = v
    return q, qd


def _run(model, q, qd, n_steps, settings=StepSettings()):
    """Stepper.step n_steps times from t = 0; returns the final (q, qd) and the step results."""
    stepper, reference, results = Stepper(model, settings), _hold(model.nv - 6), []
    for k in range(n_steps):
        res = stepper.step(q, qd, k * settings.dt, reference)
        q, qd = res.q, res.qd
        results.append(res)
    return q, qd, results


def _impulses_on_the_ground(res):
    """Sum over the contacts of one step of the impulse on the body, world frame [N s]."""
    p3 = res.p.reshape(-1, 3)
    return np.einsum("kij,kj->i", res.contacts.frame, p3)


# ------------------------------------------------------------------------------ the models


@pytest.mark.parametrize("build, mass, inertia", [(_ball, BALL_MASS, _ball_inertia), (_box, BOX_MASS, _box_inertia)])
def test_locked_halves_have_the_mass_matrix_of_one_rigid_body(build, mass, inertia, rng):
    """M of the free coordinates = blockdiag(m 1, I_com) at any orientation (MuJoCo's free joint).

    With qd = [v of the origin (world), w (body)] and the centre of mass at the origin,
    T = 1/2 m |v|^2 + 1/2 w^T I_com w for every orientation, so M_free = blockdiag(m 1, I_com);
    the two halves add up to m and I_com. This is the precondition of every test below.
    """
    model = build()
    q, _ = _at_rest_on_ground(model, 0.3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    M = ChainModel(model).terms(q, np.zeros(model.nv)).M
    expected = np.zeros((6, 6))
    expected[:3, :3], expected[3:, 3:] = mass * np.eye(3), inertia()
    np.testing.assert_allclose(M[:6, :6], expected, atol=1e-14)


# ------------------------------------------------------------------------------- the ball


def test_ball_resting_on_the_plane_receives_weight_times_dt_and_does_not_drift():
    """A ball at rest on the plane gets p_N = m g dt per step and stays put for 10 s (10 000 steps).

    Each step: free velocity c_N = -g dt, the QP returns p_N = m g dt and u+ = 0 (hand solution
    of test_contact_qp's point mass: the contact point is below the centre of mass, so G_NN =
    1/m). Two small effects of the regularization eps = REG mean(diag G) (a "tiny uniform
    compliance") are predicted, not measured:

    * mean(diag G) = (G_NN + 2 G_tt) / 3 with G_tt = 1/m + r^2 / I = 3.5 / m, so at first
      p_N = m g dt / (1 + eps / G_NN) = m g dt (1 - 2.7e-6): rtol 4e-6 on every step;
    * the ball sinks until the stabilization beta delta / dt pushes back the eps p_N that the
      regularization lets through: delta = eps p_N dt / beta = 1.3e-10 m (checked to 1 %).

    So the drift over 10 s is 1.3e-10 m vertically, exactly zero horizontally, orientation
    unchanged: all below the 1e-6 m asked for. Runtime about 10 s.
    """
    model = _ball()
    q0, qd0 = _at_rest_on_ground(model, BALL_RADIUS)
    q, qd, results = _run(model, q0, qd0, 10_000)
    p_N = np.array([res.p[0] for res in results])
    assert all(res.contacts.m == 1 for res in results)
    np.testing.assert_allclose(p_N, BALL_MASS * GRAVITY * DT, rtol=4e-6)
    G_NN, G_tt = 1 / BALL_MASS, 1 / BALL_MASS + BALL_RADIUS**2 / _ball_inertia()[0, 0]
    eps = REG * (G_NN + 2 * G_tt) / 3
    sink = eps * BALL_MASS * GRAVITY * DT * DT / BETA
    np.testing.assert_allclose(q0[2] - q[2], sink, rtol=1e-2, err_msg="sink = eps p_N dt / beta")
    assert np.linalg.norm(q[:3] - q0[:3]) < 1e-6
    np.testing.assert_allclose(q[3:7], q0[3:7], atol=1e-12)
    np.testing.assert_allclose(qd, 0.0, atol=1e-12)


# -------------------------------------------------------------------------------- the box


def test_box_sliding_at_1_m_per_s_on_mu_1_stops_after_v0_squared_over_2_mu_g():
    """Coulomb friction decelerates a sliding box by mu g: it stops after v0^2 / (2 mu g) = 51.0 mm.

    Continuum: within 2 %. Discrete (semi-implicit Euler, the step's exact hand solution): the
    friction impulse mu m g dt takes mu g dt off the speed each step until the last, partial
    step sticks (v_{k+1} = max(v_k - mu g dt, 0)), and x advances by dt v_{k+1}, so
    x = dt sum_k v_{k+1} = 50.47 mm: 1 % short of the continuum (about v0 dt / 2), to 1e-5.

    Loads: sliding at mu = 1 puts the cube exactly at its tipping limit. Moments about the
    centre of mass (half side a/2 both in height and half-width): N_front - N_rear = mu N,
    so the rear corners carry N (1 - mu) / 2 = 0 and the front ones all of m g dt; the box
    stays flat.

    At that limit the split of p_N between the 4 corners is undetermined, and the friction fixed
    point needs more than the stepper's default 10 iterates: with fp_max = 50 the discrete
    solution holds to 1e-5; with the default it is 1e-4 short (measured), still within 2 %.
    """
    mu, v0 = 1.0, 1.0
    model = _box(mu=mu)
    q0, qd0 = _at_rest_on_ground(model, BOX_SIDE / 2, v=(v0, 0.0, 0.0))
    q_default = _run(model, q0, qd0, 200)[0]
    q, qd, results = _run(model, q0, qd0, 200, StepSettings(fp_max=50))
    continuum = v0**2 / (2 * mu * GRAVITY)
    v, x = v0, 0.0
    while v > 0:
        v = max(v - mu * GRAVITY * DT, 0.0)
        x += DT * v
    distance = q[0] - q0[0]
    np.testing.assert_allclose(distance, continuum, rtol=0.02)
    np.testing.assert_allclose(distance, x, rtol=1e-5)
    np.testing.assert_allclose(qd[:6], 0.0, atol=1e-9, err_msg="the box has stopped")
    np.testing.assert_allclose(q_default[0] - q0[0], x, rtol=1e-3)
    np.testing.assert_allclose(q[3:7], [1, 0, 0, 0], atol=1e-9, err_msg="the box stays flat")
    weight_dt = BOX_MASS * GRAVITY * DT
    for k, res in enumerate(results[:90]):  # sliding steps (the box stops at step 102)
        p_N = dict(zip(res.contacts.feature.tolist(), res.p[0::3]))
        front = sum(p_N.get(c, 0.0) for c in BOTTOM_FRONT)
        rear = sum(p_N.get(c, 0.0) for c in BOTTOM_REAR)
        np.testing.assert_allclose([front, rear], [weight_dt, 0.0], atol=1e-5 * weight_dt, err_msg=f"at step {k}")


def _box_on_incline(theta, mu, duration=1.0):
    """The box resting on a plane inclined by theta, emulated by tilting gravity.

    In the plane's frame gravity is g (sin theta, 0, -cos theta): the downhill direction is +x.
    """
    model = _box(mu=mu, gravity=GRAVITY * np.array([np.sin(theta), 0.0, -np.cos(theta)]))
    q0, qd0 = _at_rest_on_ground(model, BOX_SIDE / 2)
    q, qd, results = _run(model, q0, qd0, int(round(duration / DT)))
    return q0, q, qd, results


def test_box_on_a_20_degree_incline_with_mu_half_sticks():
    """tan 20 deg = 0.36 < mu = 0.5: static friction holds the box ([COBRA] eq. (2), stick branch).

    Each step the friction impulse cancels the downhill impulse exactly, sum p_T = -m g sin
    theta dt, with normal impulse m g cos theta dt, inside the pyramid (0.36 < 0.5). The velocity
    stays 0 up to the regularization's eps p_T ~ 1e-9 m/s, so over 1 s the box moves < 1e-6 m.
    """
    theta, mu = np.radians(20.0), 0.5
    q0, q, qd, results = _box_on_incline(theta, mu)
    assert np.linalg.norm(q[:3] - q0[:3]) < 1e-6
    weight_dt = BOX_MASS * GRAVITY * DT
    for k in (0, len(results) // 2, len(results) - 1):
        np.testing.assert_allclose(_impulses_on_the_ground(results[k]),
                                   [-weight_dt * np.sin(theta), 0.0, weight_dt * np.cos(theta)],
                                   atol=1e-5 * weight_dt, err_msg=f"at step {k}")


def test_box_on_a_35_degree_incline_with_mu_half_slides_with_g_sin_minus_mu_cos():
    """tan 35 deg = 0.70 > mu = 0.5: the box slides with a = g (sin theta - mu cos theta) = 1.61 m/s^2.

    Per step, gravity adds g sin theta dt downhill and kinetic friction mu N dt = mu g cos theta dt
    takes it back uphill (t1 follows the slip, so the 4-facet pyramid is exact along it): the
    velocity after n steps is exactly n dt a. Measured a = v(1 s) / 1 s: within 2 % of the
    continuum value as asked, and within 1e-5 (the REG = 1e-6 bias, x 10) of the same formula,
    since semi-implicit Euler is exact for a constant force. Position: x = a T (T + dt) / 2.
    """
    theta, mu, T = np.radians(35.0), 0.5, 1.0
    q0, q, qd, _ = _box_on_incline(theta, mu, T)
    a = GRAVITY * (np.sin(theta) - mu * np.cos(theta))
    a_measured = qd[0] / T
    np.testing.assert_allclose(a_measured, a, rtol=0.02)
    np.testing.assert_allclose(a_measured, a, rtol=1e-5)
    np.testing.assert_allclose(q[0] - q0[0], a * T * (T + DT) / 2, rtol=1e-5)
    np.testing.assert_allclose(qd[1:6], 0.0, atol=1e-9, err_msg="straight downhill, no rotation")


def test_sliding_box_loses_its_kinetic_energy_to_the_work_of_the_contact_impulses():
    """Energy bookkeeping of simulate(): KE lost = -sum of work_contacts (notes: simulate docstring).

    Per step, Delta KE = u_mid . M (u+ - u) exactly (u_mid = (u + u+) / 2, M constant for a free
    rigid body in these coordinates) and M (u+ - u) = -dt h + J_c^T p, so
    Delta KE = -dt u_mid . h + p . J_c u_mid = (work of gravity) + work_contacts. Gravity does no
    work on a box sliding horizontally (v_z stays ~1e-15 m/s) and the gyroscopic part of h is
    w x I w, orthogonal to w. Hence 1/2 m v0^2 - KE_end = -sum work_contacts; asked within 2 %,
    the identity holds to rounding, so it is checked to 1e-6. The box stops after 102 steps.
    """
    mu, v0 = 1.0, 1.0
    model = _box(mu=mu)
    q0, qd0 = _at_rest_on_ground(model, BOX_SIDE / 2, v=(v0, 0.0, 0.0))
    traj = simulate(model, _hold(1), 0.2, StepSettings(dt=DT), q0=q0, qd0=qd0)
    ke_0 = 0.5 * BOX_MASS * v0**2
    np.testing.assert_allclose(traj.steps["kinetic"][0], ke_0, rtol=1e-12)
    v_end, w_end = traj.qd[-1, :3], traj.qd[-1, 3:6]
    ke_end = 0.5 * BOX_MASS * v_end @ v_end + 0.5 * w_end @ _box_inertia() @ w_end
    work = traj.steps["work_contacts"]
    assert np.all(work <= 1e-12), "contact impulses dissipate, never add energy"
    np.testing.assert_allclose(ke_0 - ke_end, -work.sum(), rtol=0.02)
    np.testing.assert_allclose(ke_0 - ke_end, -work.sum(), rtol=1e-6)
    np.testing.assert_allclose(ke_end, 0.0, atol=1e-12, err_msg="all of it is lost: the box stopped")


# ---------------------------------------------------------- models the stepper cannot run yet


def _single_body_ball():
    """The ball as ONE free body: joint_type ('free',), no revolute joint at all."""
    return Model(
        name="ball", body_names=("ball",), joint_names=("free",), parent=(-1,), joint_type=("free",),
        tree_pos=(np.zeros(3),), tree_rot=(np.eye(3),), mass=(BALL_MASS,), com=(np.zeros(3),),
        I_com=(_ball_inertia(),), gravity=np.array([0.0, 0.0, -GRAVITY]), q_limit=(np.inf,),
        tau_limit=(np.inf,),
        spheres=SphereSet(body=np.zeros(1, dtype=int), center=np.zeros((1, 3)), radius=np.array([BALL_RADIUS])),
    )


def test_the_steppers_integration_equals_kinematics_integrate(rng):
    """Stepper._integrate (revolute joints in one vector operation) against the reference
    kinematics.integrate on COBRA with the box: random unit-quaternion states and velocities."""
    from cobra_ref.kinematics import integrate
    from cobra_ref.robots import cobra_model

    model = cobra_model()
    stepper = Stepper(model)
    for _ in range(5):
        q = rng.normal(size=model.nq)
        for s in (model.q_idx[0], model.q_idx[model.boxes[0].body]):
            q[s.start + 3:s.stop] /= np.linalg.norm(q[s.start + 3:s.stop])
        u = rng.normal(size=model.nv)
        np.testing.assert_allclose(stepper._integrate(q, u), integrate(model, q, u, stepper.s.dt), atol=1e-15)


def test_stepper_steps_a_ball_that_has_no_revolute_joint():
    """The smallest model, one free body, should step like the locked one: p_N = m g dt."""
    model = _single_body_ball()
    stepper = Stepper(model)
    q, qd = np.array([0.0, 0.0, BALL_RADIUS, 1.0, 0.0, 0.0, 0.0]), np.zeros(6)
    res = stepper.step(q, qd, 0.0, _hold(0))
    np.testing.assert_allclose(res.p[0], BALL_MASS * GRAVITY * DT, rtol=4e-6)


@pytest.mark.parametrize("n_locks", [1, 2])
def test_simulate_logs_one_torque_column_per_joint_of_the_model(n_locks):
    """Trajectory.tau should have one column per actuated joint (StepResult.tau's length)."""
    model = _ball(n_locks=n_locks)
    q0, qd0 = _at_rest_on_ground(model, BALL_RADIUS)
    traj = simulate(model, _hold(n_locks), 0.01, StepSettings(dt=DT), q0=q0, qd0=qd0)
    assert traj.tau.shape == (10, n_locks)


# ------------------------------------------------------------------- a sphere pushing the box


def _pusher_and_box(mu, pusher_mass=0.5, pusher_radius=0.03, mu_robot_box=None):
    """A sphere (a locked two-piece body, as above) and the box (body 2, its own free joint)."""
    pusher = _locked_rigid_body("pusher", pusher_mass, 0.4 * pusher_mass * pusher_radius**2 * np.eye(3),
                                SphereSet(body=np.zeros(1, dtype=int), center=np.zeros((1, 3)),
                                          radius=np.array([pusher_radius])), mu=mu)
    box = _box(mu=mu, n_locks=0)
    fields = ("body_names", "joint_names", "joint_type", "tree_pos", "tree_rot", "mass", "com", "I_com",
              "q_limit", "tau_limit")
    merged = {k: getattr(pusher, k) + getattr(box, k) for k in fields}
    return Model(name="pusher_box", parent=pusher.parent + (-1,), gravity=pusher.gravity, spheres=pusher.spheres,
                 boxes=(BoxGeom(body=2, half=np.full(3, BOX_SIDE / 2)),), mu=mu, mu_robot_box=mu_robot_box,
                 **merged)


@pytest.mark.parametrize("ratio", [0.5, 0.95, 1.05, 1.5])
def test_a_sphere_pushing_the_box_moves_it_only_once_the_push_exceeds_mu_m_g(ratio, mu=0.5, T=0.5):
    """A hand holds a 0.5 kg sphere at the box's mid-height (its weight cancelled by tau_ext) and
    pushes it along +x with F = ratio * mu m_box g into the resting box.

    Statics: the box's ground friction can hold up to mu m_box g = 2.45 N, so for ratio < 1 the
    box stays put (displacement below 1e-6 m over 0.5 s).
    Dynamics: for ratio > 1 sphere and box move together, (m_s + m_b) a = F - mu m_b g, and the
    discrete steps (semi-implicit Euler: v_k = k a dt, x_N = dt sum v_k) give
    x_N = a dt^2 N (N + 1) / 2; within 0.2 % (the issue asks 2 %).
    The push acts at the box's centre height and mu = 0.5, so the box does not tip: moments
    about its centre of mass give N_front - N_rear = mu N, both corners pairs loaded.
    """
    model = _pusher_and_box(mu)
    m_s = model.mass[0] + model.mass[1]
    F = ratio * mu * BOX_MASS * GRAVITY
    q = np.zeros(model.nq)
    # sphere touching the box face at rest (no approach, so no impact impulse)
    q[:7] = [-(BOX_SIDE / 2 + 0.03), 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]  # sphere centre
    q[8:15] = [0.0, 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]  # box centre, resting on the ground
    qd = np.zeros(model.nv)
    tau_ext = np.zeros(model.nv)
    tau_ext[0], tau_ext[2] = F, m_s * GRAVITY  # push along x, hold the sphere's weight
    stepper, hold = Stepper(model), _hold(1)
    n_steps = int(round(T / DT))
    for k in range(n_steps):
        res = stepper.step(q, qd, k * DT, hold, tau_ext=tau_ext)
        q, qd = res.q, res.qd
    box_x = q[8]
    if ratio < 1:
        assert abs(box_x) < 1e-6, f"the box must not move for F < mu m g, moved {box_x:.2e} m"
    else:
        a = (F - mu * BOX_MASS * GRAVITY) / (m_s + BOX_MASS)
        x_expected = a * DT**2 * n_steps * (n_steps + 1) / 2
        np.testing.assert_allclose(box_x, x_expected, rtol=2e-3)
        assert abs(q[9]) < 1e-6 and abs(q[10] - BOX_SIDE / 2) < 1e-5, "straight, flat slide"


def test_a_sphere_sliding_on_the_box_feels_the_robot_box_friction_not_the_ground_friction(T=0.05):
    """Per-pair friction (assumption C22): the sphere slides on the box's top face with
    mu_robot_box = 0.2 while the box stands on ground with mu = 0.5.

    A solid sphere thrown at v0 = 0.5 m/s along x slides (it only starts rolling without slip at
    t = 2 v0 / (7 mu_rb g) = 0.073 s), so each step friction takes mu_rb g dt off its speed:
    v_N = v0 - N mu_rb g dt, 0.4019 m/s after 0.05 s (with mu = 0.5 it would be 0.2548).
    The box stays put: the sphere's friction mu_rb m_s g = 0.98 N is below the ground's
    mu (m_s + m_b) g = 4.9 N.
    """
    model = _pusher_and_box(mu=0.5, mu_robot_box=0.2)
    q = np.zeros(model.nq)
    q[:7] = [0.0, 0.0, BOX_SIDE + 0.03, 1.0, 0.0, 0.0, 0.0]  # sphere resting on the box's top face
    q[8:15] = [0.0, 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]
    qd = np.zeros(model.nv)
    qd[0] = 0.5
    stepper, hold = Stepper(model), _hold(1)
    n_steps = int(round(T / DT))
    for k in range(n_steps):
        res = stepper.step(q, qd, k * DT, hold)
        q, qd = res.q, res.qd
    np.testing.assert_allclose(qd[0], 0.5 - n_steps * 0.2 * GRAVITY * DT, atol=1e-6)
    assert abs(q[8]) < 1e-6, "the box must not move"
