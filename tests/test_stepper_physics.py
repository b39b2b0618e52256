"""One body on the ground, stepped by both steppers: hand-solvable worked examples of eq. (1)-(6).

One step, [COBRA] eq. (1) with the impulses of eq. (5)-(6) (semi-implicit Euler)::

    M (u+ - u) = dt (tau_ext - h) + J^T x,     q+ = q (+) dt u+.

For one free rigid body at rest, sliding or rolling this is solvable by hand: gravity adds
-g dt to the velocity each step, the contact impulse takes out exactly what the contact law
allows, and Coulomb's friction (a circle, ||f_T|| <= mu f_N) opposes the slip with mu f_N.
The compliant law (the default) and the rigid law each have their hand solution; tolerances
come from the laws (compliance.py) and the solver (FP_TOL, OSQP's eps), not from a run.
"""

from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from bodies import (BALL_MASS, BALL_RADIUS, BOX_MASS, BOX_SIDE, GRAVITY, at_height, ball, ball_inertia, box,
                    box_inertia, centre_of_mass, cobra_in_free_flight, free_body, hold_joints, no_joints, run,
                    sphere_and_box)
from cobra_ref.compliance import BAUMGARTE, RIGID_COMPLIANCE
from cobra_ref.dynamics import forward_dynamics, kinetic_energy, spatial_momentum
from cobra_ref.fast.chain import ChainModel
from cobra_ref.step import StepSettings
from cobra_ref.steppers import STEPPERS, make_stepper

DT = 1e-3
RIGID, COMPLIANT = StepSettings(contact="rigid"), StepSettings(contact="compliant")


@pytest.fixture(params=STEPPERS)
def stepper(request):
    """Each hand-solvable example runs on every stepper (``steppers.STEPPERS``)."""
    return request.param


@pytest.mark.parametrize("build, mass, inertia", [(ball, BALL_MASS, ball_inertia), (box, BOX_MASS, box_inertia)])
def test_a_free_body_has_the_mass_matrix_blockdiag_m_and_I(build, mass, inertia, rng):
    """M = blockdiag(m 1, I_com) at any orientation (MuJoCo's free joint, centre of mass at the origin).

    With qd = [v of the origin (world), w (body)], T = 1/2 m |v|^2 + 1/2 w^T I_com w for every
    orientation. The precondition of every hand solution below.
    """
    model = build()
    q, _ = at_height(model, 0.3)
    quat = rng.normal(size=4)
    q[3:7] = quat / np.linalg.norm(quat)
    expected = np.zeros((6, 6))
    expected[:3, :3], expected[3:, 3:] = mass * np.eye(3), inertia()
    np.testing.assert_allclose(ChainModel(model).terms(q, np.zeros(6)).M, expected, atol=1e-14)


# ------------------------------------------------------------------------------ resting


def test_a_ball_resting_on_rigid_ground_gets_its_weight_and_sinks_only_by_the_regularization(stepper):
    """Rigid law at rest: p_N -> m g dt, and the ball sinks to delta = eps g dt^2 / beta.

    Per step the law is w_N + R p_N + b = 0 with R = eps G_NN (eps = RIGID_COMPLIANCE,
    G_NN = 1/m for a ball: the contact point is below the centre of mass) and b = beta g / dt
    for a penetration g < 0. At rest w_N = 0 and p_N = m g_acc dt, so beta g / dt = -eps g_acc dt:
    delta = eps g_acc dt^2 / beta = 4.9e-7 m (checked to 1 %, after 1 s).
    """
    model = ball()
    q0, qd0 = at_height(model, BALL_RADIUS)
    q, qd, results = run(model, q0, qd0, 1000, RIGID, stepper=stepper)
    np.testing.assert_allclose(results[-1].p[0], BALL_MASS * GRAVITY * DT, rtol=1e-6)
    np.testing.assert_allclose(q0[2] - q[2], RIGID_COMPLIANCE * GRAVITY * DT**2 / BAUMGARTE, rtol=1e-2)
    np.testing.assert_allclose(q[:2], 0.0, atol=1e-12)
    np.testing.assert_allclose(qd, 0.0, atol=1e-9)


def test_a_ball_dropped_on_compliant_ground_settles_at_the_static_sag_m_g_over_k(stepper):
    """Compliant law at rest: f_N = k delta, so the ball settles at the sag delta = m g / k.

    The default contact: k = 1e6 N/m, d = 1e3 N s/m; 1 kg gives delta = 9.81 um. Dropped from
    1 mm above the ground, it settles within 0.3 s (checked to 1 % of delta), its weight then
    carried exactly (p_N = m g dt to 1e-9).
    """
    model = ball()
    q0, qd0 = at_height(model, BALL_RADIUS + 1e-3)
    q, qd, results = run(model, q0, qd0, 300, COMPLIANT, stepper=stepper)
    sag = BALL_MASS * GRAVITY / model.contact_stiffness
    np.testing.assert_allclose(BALL_RADIUS - q[2], sag, rtol=1e-2)
    np.testing.assert_allclose(results[-1].p[0], BALL_MASS * GRAVITY * DT, rtol=1e-9)


@pytest.mark.parametrize("zeta, bounces", [(1.0, False), (0.05, True)])
def test_a_critically_damped_drop_does_not_bounce_and_a_lightly_damped_one_does(stepper, zeta, bounces, k=1e4):
    """A spring-damper of damping ratio zeta = d / (2 sqrt(k m)): critical (zeta = 1) does not
    rebound; zeta = 0.05 does (the contact lets go: the ball leaves the ground again).

    Dropped at 1 m/s onto k = 1e4 N/m (sag 1 mm, period 2 pi sqrt(m/k) = 63 ms, resolved by
    dt = 1 ms). After first touching the ground, the ball rises above the surface (gap > 0)
    again only if it bounces.
    """
    d = 2 * zeta * np.sqrt(k * BALL_MASS)
    model = ball(contact_stiffness=k, contact_damping=d)
    q0, qd0 = at_height(model, BALL_RADIUS, v=(0.0, 0.0, -1.0))
    _, _, results = run(model, q0, qd0, 300, COMPLIANT, stepper=stepper)
    heights = np.array([res.q[2] for res in results]) - BALL_RADIUS
    assert (heights.max() > 1e-4) == bounces, f"zeta = {zeta}: max height after touchdown {heights.max():.2e} m"


def test_the_compliant_contact_tends_to_the_rigid_one_as_it_stiffens(stepper):
    """Rigid contact is the k, d -> infinity limit of the compliant one (compliance module).

    A ball lands at 1 m/s and comes to rest. The compliant ground (critically damped,
    d = 2 sqrt(k m)) holds it at the sag m g / k below the surface: 1 mm, 10 um, 0.1 um for
    k = 1e4, 1e6, 1e8 N/m. The rigid law holds it at eps g dt^2 / beta = 0.5 um (its own small
    compliance). So each 100-fold stiffer contact brings the resting height 10 times closer to
    the rigid one at least, down to that 0.5 um; and the landing's total impulse is m v + m g t
    in both (to 1e-3: the softest is still settling). Both laws take whole steps (the rigid law's
    own, A33), so that the limit compares the laws and not the steps; touch-down substeps re-read
    the velocity where the step size changes, and the logged impulses then differ from the state's
    change of momentum by m (dt - dt / n) / 2 times the change of acceleration between the stretch's
    ends (tests/test_touchdown.py), here from free fall to rest.
    """
    def landed(settings, **law):
        model = ball(**law)
        q0, qd0 = at_height(model, BALL_RADIUS, v=(0.0, 0.0, -1.0))
        q, _, results = run(model, q0, qd0, 100, settings, stepper=stepper)
        return q[2], sum(res.p[0] for res in results)

    rigid_height, rigid_impulse = landed(RIGID)
    heights, impulses = zip(*(landed(replace(COMPLIANT, touchdown_substeps=1), contact_stiffness=k, contact_damping=2 * np.sqrt(k * BALL_MASS))
                              for k in (1e4, 1e6, 1e8)))
    differences = np.abs(np.array(heights) - rigid_height)
    assert differences[1] < 0.1 * differences[0] and differences[2] < 0.1 * differences[1], differences
    assert differences[2] < 1e-6
    np.testing.assert_allclose(impulses, rigid_impulse, rtol=1e-3)  # the softest still settles
    np.testing.assert_allclose(rigid_impulse, BALL_MASS * (1.0 + GRAVITY * 0.1), rtol=1e-6)


# ------------------------------------------------------------------------------ sliding


@pytest.mark.parametrize("settings", [COMPLIANT, RIGID], ids=["compliant", "rigid"])
@pytest.mark.parametrize("angle", [0.0, 22.5, 30.0, 45.0])
def test_a_sliding_box_decelerates_at_mu_g_along_its_velocity_in_every_direction(stepper, angle, settings, mu=0.5,
                                                                              v0=1.0):
    """Coulomb's circle: a box sliding at any angle to the contact frame (t1 = x) decelerates at
    exactly mu g and keeps its heading.

    The friction of each corner opposes the slip with mu f_N; the four add up to mu m g against
    the velocity, through the load's centroid (no yaw moment). A 4-facet pyramid would have
    allowed up to sqrt(2) mu m g sideways at 45 degrees and turned the box. Over 0.1 s:
    deceleration within 1 % of mu g, heading within 0.5 degree, no yaw.
    """
    direction = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle)), 0.0])
    model = box(mu=mu)
    q0, qd0 = at_height(model, BOX_SIDE / 2, v=v0 * direction)
    q, qd, results = run(model, q0, qd0, 100, settings, stepper=stepper)
    speed = np.linalg.norm(qd[:2])
    np.testing.assert_allclose((v0 - speed) / 0.1, mu * GRAVITY, rtol=1e-2)
    heading = np.degrees(np.arctan2(qd[1], qd[0]))
    assert abs(heading - angle) < 0.5, f"heading {heading:.3f} deg for a slide at {angle} deg"
    assert abs(qd[5]) < 1e-6, "no yaw rate"
    for res in results:
        p = res.p.reshape(-1, 3)
        assert np.all(np.hypot(p[:, 1], p[:, 2]) <= mu * p[:, 0] * (1 + 1e-9) + 1e-15), "inside the circle"


@pytest.mark.parametrize("settings", [COMPLIANT, RIGID], ids=["compliant", "rigid"])
def test_a_box_sliding_under_a_steady_sideways_force_follows_coulombs_law(stepper, settings, mu=0.5, v0=1.0,
                                                                          ratio=0.6):
    """A box sliding along x at v0 feels a constant force F = 0.6 mu m g along y at its centre.

    Coulomb's law (integrated here with scipy): m v' = F e_y - mu m g v / |v| while it slides,
    so the path curves towards y as the sideways force turns the velocity. The simulated
    position follows the integrated one within 2 % of the distance travelled over 0.15 s
    (a pyramid's axis-wise bound would not turn it this way).
    """
    model = box(mu=mu)
    F = ratio * mu * BOX_MASS * GRAVITY
    q0, qd0 = at_height(model, BOX_SIDE / 2, v=(v0, 0.0, 0.0))
    tau_ext = np.zeros(6)
    tau_ext[1] = F
    T, n = 0.15, 150
    q, qd, _ = run(model, q0, qd0, n, settings, tau_ext=tau_ext, stepper=stepper)

    def coulomb(t, y):
        v = y[2:]
        return [*v, *(np.array([0.0, F / BOX_MASS]) - mu * GRAVITY * v / np.linalg.norm(v))]

    exact = solve_ivp(coulomb, (0.0, T), [0.0, 0.0, v0, 0.0], rtol=1e-10, atol=1e-12).y[:, -1]
    np.testing.assert_allclose(q[:2], exact[:2], atol=0.02 * np.linalg.norm(exact[:2]))
    np.testing.assert_allclose(qd[:2], exact[2:], atol=0.02 * v0)


@pytest.mark.parametrize("settings", [COMPLIANT, RIGID], ids=["compliant", "rigid"])
@pytest.mark.parametrize("angle", [0.0, 30.0, 45.0, 90.0])
def test_a_sphere_sliding_without_spin_ends_rolling_at_five_sevenths_of_its_speed(stepper, angle, settings, mu=0.5,
                                                                               v0=1.0):
    """A solid sphere thrown at v0 without spin: friction slows its centre and spins it up until it
    rolls without slipping, at v = 5/7 v0 (angular momentum about the contact point is conserved:
    m v0 r = m v r + 2/5 m r^2 v / r), after t = 2 v0 / (7 mu g) = 0.058 s; in every direction.
    Checked after 0.1 s within 1 %, and rolling: |v - w x r| below 1e-3 of v0.
    """
    direction = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle)), 0.0])
    model = ball(mu=mu)
    q0, qd0 = at_height(model, BALL_RADIUS, v=v0 * direction)
    q, qd, _ = run(model, q0, qd0, 100, settings, stepper=stepper)
    np.testing.assert_allclose(qd[:3], 5 / 7 * v0 * direction, atol=1e-2 * v0)
    slip = qd[:3] + np.cross(qd[3:6], [0.0, 0.0, -BALL_RADIUS])  # the contact point's velocity (unturned ball)
    assert np.linalg.norm(slip[:2]) < 1e-3 * v0, f"still slipping at {slip}"


# ------------------------------------------------------------------------------ an incline


def _incline(theta_deg):
    """Gravity tilted by theta about y: the ground is an incline of theta, downhill along +x."""
    th = np.radians(theta_deg)
    return (GRAVITY * np.sin(th), 0.0, -GRAVITY * np.cos(th))


def test_a_box_on_a_rigid_incline_below_the_friction_angle_sticks(stepper):
    """tan(20 deg) = 0.36 < mu = 0.5: the rigid law holds the box (it creeps only by the
    regularization, below 1e-4 m/s after 0.3 s)."""
    model = free_body("box", BOX_MASS, box_inertia(), boxes=box().boxes, gravity=_incline(20.0), mu=0.5)
    q0, qd0 = at_height(model, BOX_SIDE / 2)
    q, qd, _ = run(model, q0, qd0, 300, RIGID, stepper=stepper)
    assert np.linalg.norm(qd[:3]) < 1e-4


def test_a_box_on_a_compliant_incline_creeps_at_the_stick_slip_velocity_the_law_gives(stepper):
    """The smooth stick-slip friction (A13) holds the box with f_T = mu f_N v / v_s: on 20 degrees
    it creeps at v = v_s tan(20 deg) / mu = 0.73 mm/s (hand solution of the law), within 1 %."""
    model = free_body("box", BOX_MASS, box_inertia(), boxes=box().boxes, gravity=_incline(20.0), mu=0.5)
    q0, qd0 = at_height(model, BOX_SIDE / 2)
    q, qd, _ = run(model, q0, qd0, 300, COMPLIANT, stepper=stepper)
    np.testing.assert_allclose(np.linalg.norm(qd[:2]), model.stiction_velocity * np.tan(np.radians(20.0)) / 0.5,
                               rtol=1e-2)


@pytest.mark.parametrize("settings", [COMPLIANT, RIGID], ids=["compliant", "rigid"])
def test_a_box_on_an_incline_steeper_than_the_friction_angle_slides_at_g_sin_minus_mu_cos(stepper, settings, mu=0.5):
    """tan(35 deg) = 0.70 > mu: the box accelerates at g (sin 35 - mu cos 35) = 1.61 m/s^2, within 1 %."""
    model = free_body("box", BOX_MASS, box_inertia(), boxes=box().boxes, gravity=_incline(35.0), mu=mu)
    q0, qd0 = at_height(model, BOX_SIDE / 2)
    _, qd, _ = run(model, q0, qd0, 200, settings, stepper=stepper)
    th = np.radians(35.0)
    np.testing.assert_allclose(qd[0] / 0.2, GRAVITY * (np.sin(th) - mu * np.cos(th)), rtol=1e-2)


# ------------------------------------------------------------------------------ energy


def _tumbling_energy_drift(dt, stepper, T=1.0, extrapolate=True):
    """|KE(T) - KE(0)| / KE(0) of a torque-free asymmetric body spun near its intermediate axis."""
    model = free_body("top", 1.0, np.diag([0.01, 0.02, 0.03]), gravity=(0.0, 0.0, 0.0))
    q, qd = at_height(model, 1.0, w=(0.1, 8.0, 0.2))
    stepping = make_stepper(stepper, model, StepSettings(dt=dt))
    ke0 = kinetic_energy(model, q, qd)
    for k in range(int(round(T / dt))):
        if not extrapolate:
            stepping.memory = None  # no memory of the last step: h at the step's starting velocity
        res = stepping.step(q, qd, k * dt, no_joints)
        q, qd = res.q, res.qd
    return abs(kinetic_energy(model, q, qd) - ke0) / ke0


def test_a_tumbling_body_keeps_its_energy_to_second_order_in_dt(stepper):
    """A torque-free body (I = diag(1, 2, 3) 0.01 kg m^2) spun at 8 rad/s near its intermediate axis
    tumbles; its kinetic energy is constant. With the gyroscopic term w x I w at the midpoint
    velocity w (``step.midpoint_velocity``) the energy error over 1 s falls 4-fold when dt halves
    (second order); at the step's starting velocity (no memory of the last step) only 2-fold:
    dKE = -dt w_mid . (w x I w) = dt^2 / 2 |w x I w|^2_{I^-1} per step, a steady first-order gain."""
    drift = {dt: _tumbling_energy_drift(dt, stepper) for dt in (2e-3, 1e-3)}
    assert drift[2e-3] / drift[1e-3] > 3.5
    assert drift[1e-3] < 1e-3
    plain = {dt: _tumbling_energy_drift(dt, stepper, extrapolate=False) for dt in (2e-3, 1e-3)}
    assert 1.8 < plain[2e-3] / plain[1e-3] < 2.2
    assert plain[1e-3] > 10 * drift[1e-3]


def _chain_line_error(dt, staggered: bool, T=0.5):
    """|c(T) - (c0 + v_c T)| [m]: how far the centre of mass of COBRA in free flight
    (``bodies.cobra_in_free_flight``) leaves its straight line, started from qd0 as given or staggered,
    from qd0 - dt qdd0 / 2 (the velocity half a step back, as the step reads it)."""
    model, q, qd0 = cobra_in_free_flight()
    c0, v_c = centre_of_mass(model, q), spatial_momentum(model, q, qd0)[3:] / sum(model.mass)
    qd = qd0 - 0.5 * dt * forward_dynamics(model, q, qd0, np.zeros(model.nv)) if staggered else qd0.copy()
    n = int(round(T / dt))
    q_end, _, _ = run(model, q, qd, n, StepSettings(dt=dt), reference=hold_joints)
    return float(np.linalg.norm(centre_of_mass(model, q_end) - (c0 + v_c * n * dt)))


def test_the_jointed_chain_in_free_flight_is_second_order_once_its_start_is_staggered():
    """COBRA tumbling in free flight from a random state: its centre of mass moves on a straight
    line. The step reads qd as the velocity half a step back (q+ = q + dt qd+), so a run that starts
    from qd0 as given starts dt qdd0 / 2 off, and its error halves with dt (first order); started from
    qd0 - dt qdd0 / 2 it falls four-fold (second order, M(q) at the step's start included)."""
    staggered = {dt: _chain_line_error(dt, True) for dt in (2e-3, 1e-3)}
    given = {dt: _chain_line_error(dt, False) for dt in (2e-3, 1e-3)}
    assert staggered[2e-3] / staggered[1e-3] > 3.5
    assert 1.6 < given[2e-3] / given[1e-3] < 2.4
    assert given[1e-3] > 2 * staggered[1e-3]


@pytest.mark.parametrize("settings", [COMPLIANT, RIGID], ids=["compliant", "rigid"])
def test_a_sliding_box_loses_its_kinetic_energy_to_the_work_of_the_contact_impulses(stepper, settings):
    """Energy ledger of one body: Delta KE + Delta PE = work of the contact impulses.

    The stepper records KE and PE at each step's start, and the contacts' work x . J_c u_mid at
    the midpoint velocity u_mid = (u + u+) / 2, for which Delta KE = u_mid . M (u+ - u) holds
    exactly (M is constant for one body). What is left per step is O(dt^2): gravity does the
    work m g dt u_mid,z while the height moves by dt u+_z. Over the slide (it stops after
    0.17 s) the ledger closes within 1 % of the energy dissipated; the contacts' work is the
    dissipation plus the change of the springs' stored energy, so it dissipates (-W - Delta
    E_elastic > 0).
    """
    model = box(mu=0.5)
    q0, qd0 = at_height(model, BOX_SIDE / 2, v=(0.8, 0.3, 0.0))
    _, _, results = run(model, q0, qd0, 200, settings, stepper=stepper)
    energy = np.array([r.kinetic + r.potential for r in results])
    work = sum(r.work_contacts for r in results[:-1])
    np.testing.assert_allclose(energy[-1] - energy[0], work, rtol=1e-2)
    assert -work - (results[-1].elastic - results[0].elastic) > 0
    assert work < -0.9 * 0.5 * BOX_MASS * (0.8**2 + 0.3**2), "most of the kinetic energy is dissipated"


# ------------------------------------------------------------------------------ a sphere and the box


@pytest.mark.parametrize("ratio", [0.5, 0.95, 1.05, 1.5])
def test_a_sphere_pushing_the_box_moves_it_only_once_the_push_exceeds_mu_m_g(stepper, ratio, mu=0.5, T=0.3):
    """A hand holds a 0.5 kg sphere at the box's mid-height (its weight cancelled) and pushes it
    along +x with F = ratio mu m_box g into the box (rigid law).

    Statics: the ground holds the box up to mu m_box g, so for ratio < 1 it stays: it only
    creeps by the rigid law's compliance (a sticking contact gives way by 1e-2 of the velocity
    its impulse causes), below 0.1 mm in 0.3 s, against 5.5 mm of sliding at ratio 1.05. Dynamics: for ratio > 1 both move, (m_s + m_b) a =
    F - mu m_b g; the discrete steps give x_N = a dt^2 N (N + 1) / 2, within 1 %.
    """
    model = sphere_and_box(mu)
    m_s = model.mass[0]
    F = ratio * mu * BOX_MASS * GRAVITY
    q = np.zeros(model.nq)
    q[:7] = [-(BOX_SIDE / 2 + 0.03), 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]  # touching the box face
    q[7:14] = [0.0, 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]
    tau_ext = np.zeros(model.nv)
    tau_ext[0], tau_ext[2] = F, m_s * GRAVITY
    n = int(round(T / DT))
    q, _, _ = run(model, q, np.zeros(model.nv), n, RIGID, tau_ext=tau_ext, stepper=stepper)
    if ratio < 1:
        assert abs(q[7]) < 1e-4, f"the box must not move for F < mu m g, moved {q[7]:.2e} m"
    else:
        a = (F - mu * BOX_MASS * GRAVITY) / (m_s + BOX_MASS)
        np.testing.assert_allclose(q[7], a * DT**2 * n * (n + 1) / 2, rtol=1e-2)


def test_a_sphere_sliding_on_the_box_feels_the_robot_box_friction_not_the_ground_friction(stepper, T=0.05):
    """Per-pair friction (assumption A22): the sphere slides on the box's top face with
    mu_robot_box = 0.2 while the box stands on ground with mu = 0.5.

    Thrown at 0.5 m/s it slides (rolling would start only at 2 v0 / (7 mu_rb g) = 0.073 s): each
    step friction takes mu_rb g dt off its speed, v = 0.4019 m/s after 0.05 s (0.2548 with mu).
    The box stays: mu_rb m_s g = 0.98 N is below the ground's mu (m_s + m_b) g = 4.9 N.
    """
    model = sphere_and_box(mu=0.5, mu_robot_box=0.2)
    q = np.zeros(model.nq)
    q[:7] = [0.0, 0.0, BOX_SIDE + 0.03, 1.0, 0.0, 0.0, 0.0]
    q[7:14] = [0.0, 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]
    qd = np.zeros(model.nv)
    qd[0] = 0.5
    n = int(round(T / DT))
    q, qd, _ = run(model, q, qd, n, RIGID, stepper=stepper)
    np.testing.assert_allclose(qd[0], 0.5 - n * 0.2 * GRAVITY * DT, rtol=1e-3)
    assert abs(q[7]) < 1e-5, "the box must not move"


# ------------------------------------------------------------------------------ both steppers


@pytest.mark.parametrize("settings", [COMPLIANT, RIGID], ids=["compliant", "rigid"])
def test_the_fast_and_the_reference_stepper_take_the_same_steps(settings):
    """The sphere pushing the box, stepped by both: the same states to 1e-9 over 0.1 s."""
    model = sphere_and_box(0.5)
    q = np.zeros(model.nq)
    q[:7] = [-(BOX_SIDE / 2 + 0.03), 0.0, BOX_SIDE / 2 + 0.01, 1.0, 0.0, 0.0, 0.0]
    q[7:14] = [0.0, 0.0, BOX_SIDE / 2, 1.0, 0.0, 0.0, 0.0]
    qd = np.zeros(model.nv)
    qd[0] = 0.8
    fast = run(model, q, qd, 100, settings, "fast")
    reference = run(model, q, qd, 100, settings, "reference")
    np.testing.assert_allclose(fast[0], reference[0], atol=1e-9)
    np.testing.assert_allclose(fast[1], reference[1], atol=1e-9)


@pytest.mark.parametrize("mu_box_ground, expected", [(0.3, 0.3), (None, 1.0)], ids=["own", "same-as-mu"])
def test_the_box_slides_on_the_ground_with_its_own_friction_coefficient(mu_box_ground, expected, v0=1.0, n=50):
    """COBRA's box, pushed away from the robot at 1 m/s, decelerates at mu_bg g: 0.3 g with
    mu_box_ground = 0.3, and mu g = 1.0 g when it is left None (the same as the robot's
    ground friction, A13). Within 1 % over 50 ms; the robot holds still, far from the box."""
    from cobra_ref.gaits import gait
    from cobra_ref.params import CobraParameters
    from cobra_ref.robots import cobra_model
    from cobra_ref.start import BoxPlacement, initial_state

    model = cobra_model(CobraParameters(mu_box_ground=mu_box_ground))
    assert model.mu_bg == expected and model.mu == 1.0 and model.mu_rb == 0.5
    ref = gait("C")
    q, qd = initial_state(model, ref, StepSettings(), BoxPlacement(offset=(0.0, 0.6)))
    iv = model.v_idx[model.boxes[0].body].start
    qd[iv:iv + 6] = [v0, 0.0, 0.0, 0.0, 0.0, 0.0]
    stepping, q_hold = make_stepper("fast", model, StepSettings()), ref(0.0)[0]
    hold = lambda t: (q_hold, 0 * q_hold, 0 * q_hold)  # noqa: E731
    for k in range(n):
        res = stepping.step(q, qd, k * 1e-3, hold)
        q, qd = res.q, res.qd
    np.testing.assert_allclose((v0 - qd[iv]) / (n * 1e-3), expected * GRAVITY, rtol=1e-2)
