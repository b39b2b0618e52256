"""The least-action problem of one step ([COBRA] eq. (5)-(6)) on hand-built problems.

Notation (cobra_ref/least_action.py): impulses x = [p_N, p_t1, p_t2] per contact (then the
servo rows), H = G + R (Delassus matrix plus each row's compliance), c = J u_free + b. The QP is

    min_x 1/2 x^T H x + x^T c   s.t.  p_N >= 0,  ||p_T|| <= mu p_N (Coulomb's circle),

and its optimality conditions are eq. (2) at the velocity level.

Hand problems use a point mass m with its contact frame at the mass: J = I, so G = I / m, and
a mass at rest or sliding has the free contact velocity c = [-g dt, v_t1, v_t2] after one step
of free fall. Tolerances come from FP_TOL (the friction fixed point's natural residual) and
OSQP's eps, never from a run.
"""

import numpy as np
import pytest

from cobra_ref import compliance
from cobra_ref.fast.least_action import FastBoxQP
from cobra_ref.coulomb_newton import coulomb_newton
from cobra_ref.least_action import (FP_TOL, LeastAction, delassus, kkt_residuals, natural_residual,
                                    project_disk, project_friction, solve_least_action, turn, turn_tangents)
from cobra_ref.qp import EPS

GRAVITY, DT = 9.81, 1e-3


def _point_mass(mass, c, mu, R=0.0, v_s=0.0):
    """The least-action problem of one point-mass contact: H = I / m + R, c given."""
    return LeastAction(np.eye(3) / mass + np.diag(np.broadcast_to(R, 3)), np.asarray(c, dtype=float),
                       np.array([mu]), np.zeros(0), np.zeros(0), v_s)


def test_the_delassus_matrix_of_a_point_mass_is_its_inverse_mass():
    """G = J M^-1 J^T with J = I and M = m I is I / m; M^-1 J^T is returned for the velocity update."""
    G, Minv_JT = delassus(np.eye(3), 2.0 * np.eye(3))
    np.testing.assert_allclose(G, np.eye(3) / 2.0, atol=1e-16)
    np.testing.assert_allclose(Minv_JT, np.eye(3) / 2.0, atol=1e-16)


def test_a_point_mass_at_rest_receives_its_weight_times_dt(mass=2.0, mu=0.5):
    """c = [-g dt, 0, 0]: the unconstrained minimiser p = -G^-1 c = [m g dt, 0, 0] has p_N > 0
    and no friction, so it is the answer, and w = G p + c = 0: neither sinking nor lifting."""
    p, info = solve_least_action(_point_mass(mass, [-GRAVITY * DT, 0.0, 0.0], mu))
    assert info.converged and info.iterations <= 2  # from a cold start: the first bound uses pbar_N = 0
    np.testing.assert_allclose(p, [mass * GRAVITY * DT, 0.0, 0.0], atol=1e-12)


@pytest.mark.parametrize("angle", [0.0, 22.5, 30.0, 45.0, 137.0, -90.0])
def test_a_fast_slide_feels_mu_p_N_against_its_slip_in_every_direction(angle, mass=2.0, mu=0.5, speed=1.0):
    """Coulomb's circle: a slide faster than mu g dt per step is slowed by friction mu p_N
    exactly opposite to the slip, at any angle to the contact frame (a pyramid would give up to
    sqrt(2) mu p_N and a sideways component between its facets).

    The normal row does not couple to the tangential ones (G = I / m), so p_N = m g dt; stopping
    the slip would need m v > mu p_N, so p_T = -mu p_N (cos a, sin a).
    """
    a = np.radians(angle)
    c = [-GRAVITY * DT, speed * np.cos(a), speed * np.sin(a)]
    p, info = solve_least_action(_point_mass(mass, c, mu))
    p_N = mass * GRAVITY * DT
    np.testing.assert_allclose(p, [p_N, -mu * p_N * np.cos(a), -mu * p_N * np.sin(a)], atol=1e-12)
    assert info.converged and info.residual <= FP_TOL


def test_a_slow_slide_sticks_within_the_step(mass=2.0, mu=0.5):
    """A slip smaller than mu g dt is stopped within the step: p_T = -m v, inside the circle, w_T = 0."""
    v = np.array([0.3, -0.2]) * mu * GRAVITY * DT
    p, _ = solve_least_action(_point_mass(mass, [-GRAVITY * DT, *v], mu))
    np.testing.assert_allclose(p[1:], -mass * v, atol=1e-14)


def test_a_contact_moving_away_receives_no_impulse(mass=2.0, mu=0.5):
    """c_N > 0 (separating faster than gravity pulls back within the step): p = 0."""
    p, _ = solve_least_action(_point_mass(mass, [0.1, 0.5, 0.0], mu))
    np.testing.assert_allclose(p, 0.0, atol=1e-15)


def test_the_compliant_row_law_is_the_implicit_spring_damper():
    """compliance.spring_damper: w + R x + b = 0 is f = -k e(t+dt) - d (w - v_ref), x = f dt,
    e(t+dt) = e + dt w (worked for numbers: k = 100, d = 5, dt = 0.01, e = -0.02, v_ref = 0.1)."""
    k, d, dt, e, v_ref = 100.0, 5.0, 0.01, -0.02, 0.1
    R, b = compliance.spring_damper(k, d, dt, e, v_ref)
    for w in (-0.3, 0.0, 0.2):
        x = -(w + b) / R
        np.testing.assert_allclose(x / dt, -k * (e + dt * w) - d * (w - v_ref), rtol=1e-12)


def test_a_point_mass_on_compliant_ground_sinks_to_m_g_over_k(mass=2.0, mu=0.5, k=1e5, d=1e3):
    """At rest on the spring-damper (the compliant law), w = 0 and p_N = m g dt, so the law
    w + R p + b = 0 with b = k g / (k dt + d) gives the gap g = -m g / k: the static sag."""
    sag = -mass * GRAVITY / k
    R, b = compliance.spring_damper(k, d, DT, sag)
    p, _ = solve_least_action(_point_mass(mass, [-GRAVITY * DT + b, 0.0, 0.0], mu, R=np.array([R, 0, 0])))
    np.testing.assert_allclose(p[0], mass * GRAVITY * DT, rtol=1e-12)


def test_turn_is_the_rotation_of_each_contact_s_tangent_pair(rng):
    """turn(v, theta) = Q^T v with Q block diagonal (identity on normal and servo rows, a rotation
    by theta_i on contact i's tangents); turning back by -theta recovers v; turn_tangents(H) = Q^T H Q."""
    m, n = 3, 11
    theta = rng.uniform(-np.pi, np.pi, size=m)
    Q = np.eye(n)
    for i, a in enumerate(theta):
        Q[3 * i + 1:3 * i + 3, 3 * i + 1:3 * i + 3] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]]
    v, H = rng.normal(size=n), rng.normal(size=(n, n))
    np.testing.assert_allclose(turn(v, theta, m), Q.T @ v, atol=1e-15)
    np.testing.assert_allclose(turn(turn(v, theta, m), -theta, m), v, atol=1e-15)
    np.testing.assert_allclose(turn_tangents(H, theta, m), Q.T @ H @ Q, atol=1e-14)


def test_project_disk_by_hand():
    """(3, 4) onto the disk of radius 1 is (0.6, 0.8); a point inside stays; a zero radius gives 0."""
    v = np.array([[3.0, 4.0], [0.1, 0.2], [1.0, 0.0]])
    np.testing.assert_allclose(project_disk(v, np.array([1.0, 1.0, 0.0])), [[0.6, 0.8], [0.1, 0.2], [0.0, 0.0]],
                               atol=1e-16)


def test_the_natural_residual_is_zero_exactly_at_coulombs_law(mass=2.0, mu=0.5):
    """At the answer of a sliding point mass the natural residual vanishes; friction turned 10
    degrees off the slip, or 10 % short of mu p_N, or a p_N that is not the one the bound used,
    each gives a residual of that size."""
    c = np.array([-GRAVITY * DT, 0.6, 0.8])
    problem = _point_mass(mass, c, mu)
    p, _ = solve_least_action(problem)
    H = problem.H

    def residual(x, pbar_N):
        g_T = (H @ x + c)[1:]
        z = x[1:] - g_T / H[1, 1]
        return natural_residual(x[:1], x[None, 1:], z[None, :], np.array([pbar_N]), problem.mu)

    assert residual(p, p[0]) < 1e-12
    turned = p.copy()
    a = np.radians(10.0)
    turned[1:] = [[np.cos(a), -np.sin(a)], [np.sin(a), np.cos(a)]] @ p[1:]
    assert residual(turned, p[0]) > 0.05 * mu
    short = p.copy()
    short[1:] *= 0.9
    assert residual(short, p[0]) > 0.05 * mu
    assert residual(p, 1.2 * p[0]) > 0.19


def test_newtons_guess_finds_a_sliding_contacts_normal_impulse_and_friction_direction(mass=2.0, mu=0.5):
    """From the frictionless answer [m g dt, 0, 0] (the first QP when pbar_N = 0), Newton's method
    on the active set (the contact slides) returns pbar_N = m g dt and the friction angle against
    the slip (60 degrees slip: friction at -120 degrees): the next QP then has converged."""
    c = np.array([-GRAVITY * DT, 0.5, 0.5 * np.sqrt(3)])
    problem = _point_mass(mass, c, mu)
    pbar_N, theta, X = coulomb_newton(problem, np.array([mass * GRAVITY * DT, 0.0, 0.0]))
    np.testing.assert_allclose(pbar_N, [mass * GRAVITY * DT], rtol=1e-12)
    np.testing.assert_allclose(theta, [np.radians(-120.0)], atol=1e-12)


def test_a_box_on_four_corners_gets_one_force_split_and_mirrored_inputs_mirrored_impulses():
    """Four box corners on the plane and a 6-DoF box: G (12 x 12) has rank 6, so without
    regularization the corners' loads are undetermined. The rigid law's compliance R = eps G_ii
    makes the QP strictly convex: one split (the four corners share the weight equally at rest),
    and the mirror image y -> -y of a sliding box's problem (t2 rows and c_t2 negated) gives the
    mirrored impulses to rounding."""
    from cobra_ref.gaps import box_corner_plane_gaps
    from bodies import BOX_MASS, box_inertia

    half = np.full(3, 0.05)
    gaps = box_corner_plane_gaps(np.eye(3), np.array([0.0, 0.0, 0.05]), half)
    bottom = [g for g in gaps if g.g == 0.0]
    J = np.vstack([g.frame.T @ np.hstack([np.eye(3), -_skew(g.point_A - [0.0, 0.0, 0.05])]) for g in bottom])
    M = np.diag([BOX_MASS] * 3 + list(np.diag(box_inertia())))
    G, _ = delassus(J, M)
    assert np.linalg.matrix_rank(G, tol=1e-9) == 6
    H = G + compliance.RIGID_COMPLIANCE * np.diag(np.diag(G))
    at_rest = LeastAction(H, J @ np.array([0.0, 0.0, -GRAVITY * DT, 0.0, 0.0, 0.0]), np.full(4, 0.5), np.zeros(0),
                          np.zeros(0), 0.0)
    p, _ = solve_least_action(at_rest)
    # each row gives way by eps of its own velocity change within the step: the weight's share / (1 + eps)
    np.testing.assert_allclose(p[0::3], BOX_MASS * GRAVITY * DT / 4 / (1 + compliance.RIGID_COMPLIANCE) * np.ones(4),
                               rtol=1e-9)
    # sliding along (0.3, 0.2) m/s, and its mirror image
    c = J @ np.array([0.3, 0.2, -GRAVITY * DT, 0.0, 0.0, 0.0])
    problem = at_rest._replace(c=c)
    p, _ = solve_least_action(problem)
    flip = np.tile([1.0, 1.0, -1.0], 4)
    mirrored, _ = solve_least_action(problem._replace(H=flip[:, None] * H * flip[None, :], c=flip * c))
    np.testing.assert_allclose(mirrored, flip * p, atol=1e-15)


def _skew(r):
    return np.array([[0.0, -r[2], r[1]], [r[2], 0.0, -r[0]], [-r[1], r[0], 0.0]])


def test_a_servo_row_saturates_at_its_torque_bound():
    """A servo row asking for more than tau_max dt gets exactly tau_max dt (eq. (6) constraint (3)):
    H = 1 (one joint, no contact), c = -10, bound 2: the unconstrained 10 is cut to 2."""
    problem = LeastAction(np.eye(1), np.array([-10.0]), np.zeros(0), np.array([-2.0]), np.array([2.0]), 0.0)
    x, _ = solve_least_action(problem)
    np.testing.assert_allclose(x, [2.0], atol=1e-12)


def test_the_kkt_residuals_catch_friction_outside_the_circle_and_a_wrong_slip(mass=2.0, mu=0.5):
    """kkt_residuals of the answer are at rounding level; friction 10 % outside the circle shows
    as cone_residual 0.1 mu; friction turned off the slip as coulomb_residual."""
    c = np.array([-GRAVITY * DT, 1.0, 0.0])
    problem = _point_mass(mass, c, mu)
    p, _ = solve_least_action(problem)
    good = kkt_residuals(problem, p)
    assert good["cone_residual"] < 1e-15 and good["coulomb_residual"] < 1e-12 and good["complementarity"] < 1e-15
    outside = p.copy()
    outside[1] *= 1.1
    np.testing.assert_allclose(kkt_residuals(problem, outside)["cone_residual"], 0.1 * mu, rtol=1e-9)
    turned = p.copy()
    turned[1:] = [p[1] * np.cos(0.2), p[1] * np.sin(0.2)]
    assert kkt_residuals(problem, turned)["coulomb_residual"] > 0.05


def test_project_friction_keeps_the_normal_impulse_and_scales_friction_onto_its_circle():
    """(p_N, p_T) = (2, (3, 4)) with mu 0.5: p_T -> (0.6, 0.8), p_N unchanged; a negative p_N -> 0."""
    x = project_friction(np.array([2.0, 3.0, 4.0, -1.0, 1.0, 0.0]), np.array([0.5, 0.5]))
    np.testing.assert_allclose(x, [2.0, 0.6, 0.8, 0.0, 0.0, 0.0], atol=1e-16)


def _random_problem(rng, m=5, n_dof=12, law="rigid"):
    """A least-action problem from a random SPD M and J: m contacts, mixed approaching/separating."""
    A = rng.normal(size=(n_dof, n_dof))
    M = A @ A.T + n_dof * np.eye(n_dof)
    J = rng.normal(size=(3 * m, n_dof))
    G, _ = delassus(J, M)
    c = rng.normal(size=3 * m)
    c[0::3] = rng.uniform(-1.0, 0.3, size=m)
    v_s = 0.0 if law == "rigid" else 1e-3
    return LeastAction(G + compliance.RIGID_COMPLIANCE * np.diag(np.diag(G)), c, rng.uniform(0.3, 1.5, size=m),
                       np.zeros(0), np.zeros(0), v_s)


@pytest.mark.parametrize("law", ["rigid", "compliant"])
def test_random_five_contact_problems_converge_to_coulombs_law_from_a_cold_start(rng, law):
    """From zero (no warm start), the friction fixed point with Newton's guess reaches the natural
    residual FP_TOL on each of 40 random 5-contact problems, within a few QPs; the answer then
    meets eq. (2): p_N >= 0, friction in its circle, complementarity at OSQP's accuracy."""
    iterations = []
    for trial in range(40):
        problem = _random_problem(rng, law=law)
        x, info = solve_least_action(problem)
        assert info.converged, f"trial {trial}: residual {info.residual:.2e} after {info.iterations} iterates"
        iterations.append(info.iterations)
        r = kkt_residuals(problem, x)
        assert r["cone_residual"] < 1e-12 and r["coulomb_residual"] <= 10 * FP_TOL
        # g_N vanishes to OSQP's tolerance eps (1 + |c|) where p_N > 0 (x 10 margin)
        assert r["complementarity"] < 10 * EPS * (1 + np.abs(problem.c).max()) * np.abs(x).max()
    assert np.mean(iterations) < 5, iterations


def test_the_fast_box_qp_gives_the_same_least_action_answer_as_osqp(rng):
    """solve_least_action with FastBoxQP (certified solves) and with fresh OSQP solves returns the
    same impulses to OSQP's accuracy on random problems."""
    for trial in range(10):
        problem = _random_problem(rng)
        reference, _ = solve_least_action(problem)
        fast = FastBoxQP()
        fast.new_step()
        answer, _ = solve_least_action(problem, solve_qp=fast)
        np.testing.assert_allclose(answer, reference, atol=1e-5 * max(np.abs(reference).max(), 1e-12) + 10 * EPS)


def test_a_cycling_friction_fixed_point_converges_once_its_guesses_are_averaged():
    """One step of the reliability sweep (scenario 77: J-mirror, prescribed joints, mu = 1.38,
    17 contacts; stored in tests/data/cycling_step.npz) on which the plain update alternates
    between two guesses of the normal impulses (residuals 0.48 and 0.61) and Newton's method fails
    on both. From iterate FP_RELAX_AFTER on, the loop averages each new guess with the last one:
    it converges within FP_MAX, and the answer meets Coulomb's law (the natural residual of
    kkt_residuals below 1e-5). What the plain update does instead is not asserted: whether an
    unstable iteration cycles for ever or escapes its cycle late depends on the last bits of the
    library arithmetic (on one machine it cycles, on another it escapes at iterate 45)."""
    from pathlib import Path

    from cobra_ref import least_action

    data = np.load(Path(__file__).parent / "data" / "cycling_step.npz")
    problem = LeastAction(data["H"], data["c"], data["mu"], data["lo"], data["hi"], float(data["v_s"]))
    x, info = solve_least_action(problem, data["x0"])
    assert info.converged and least_action.FP_RELAX_AFTER < info.iterations <= least_action.FP_MAX, info
    assert kkt_residuals(problem, x)["coulomb_residual"] < 1e-5


def test_a_fixed_point_whose_friction_directions_cycle_converges_once_they_are_averaged_too():
    """One step of the reliability sweep (scenario 42: S, position servo, a 0.11 kg box pressed
    against the ground by two links, mu = 1.38, 17 contacts; tests/data/wedge_two_cycle_step.npz).
    Averaging the normal impulses alone does not stop its cycle: the guesses alternate with
    residuals 0.152 and 0.161 (measured for 1000 iterates). Averaging each friction direction
    with the last one as well (``mean_angle``), it converges within FP_MAX and the answer meets
    Coulomb's law (kkt_residuals' natural residual below 1e-5). That the normal impulses averaged
    alone keep cycling is measured, not asserted: an unstable path's fate depends on the last bits."""
    from pathlib import Path

    from cobra_ref import least_action

    assert np.allclose(least_action.mean_angle(np.array([0.1, 3.0, 0.5]), np.array([0.3, -3.0, 0.5 + np.pi])),
                       [0.2, np.pi, 0.5 + np.pi])  # the mean direction; across +-pi; opposite: the new one
    data = np.load(Path(__file__).parent / "data" / "wedge_two_cycle_step.npz")
    problem = LeastAction(data["H"], data["c"], data["mu"], data["lo"], data["hi"], float(data["v_s"]))
    x, info = solve_least_action(problem, data["x0"])
    assert info.converged and least_action.FP_RELAX_AFTER < info.iterations <= least_action.FP_MAX, info
    assert kkt_residuals(problem, x)["coulomb_residual"] < 1e-5


def test_a_step_whose_contacts_all_hover_converges_at_its_first_iterate(monkeypatch):
    """One step of the reliability sweep (scenario 22: J, mu = 1.47, 14 candidate contacts, the
    robot in the air; stored in tests/data/hovering_step.npz): every contact separates (c_N > 0),
    so the answer carries no contact impulse. OSQP's normal impulses are rounding, about 1e-25 N s,
    and measured against their own max p_N the natural residual is rounding over rounding (1.5-60
    for all 50 iterates). Measured against ``impulse_floor`` (a billionth of max c_N / H_NN) the
    step converges at its first iterate, with complementarity and Coulomb's residual at rounding."""
    from pathlib import Path

    from cobra_ref import least_action

    data = np.load(Path(__file__).parent / "data" / "hovering_step.npz")
    problem = LeastAction(data["H"], data["c"], data["mu"], data["lo"], data["hi"], float(data["v_s"]))
    m = problem.m
    assert np.all(problem.c[0:3 * m:3] > 0), "every contact separates"
    x, info = solve_least_action(problem, data["x0"])
    assert info.converged and info.iterations == 1, info
    assert np.abs(x[:3 * m]).max() < 1e-20
    res = kkt_residuals(problem, x)
    assert res["complementarity"] < 1e-20 and res["coulomb_residual"] < 1e-12
    monkeypatch.setattr(least_action, "impulse_floor", lambda problem: 0.0)
    _, info = solve_least_action(problem, data["x0"])
    assert not info.converged and info.residual > 1.0, info
