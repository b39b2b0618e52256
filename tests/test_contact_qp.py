"""The least-action contact QP of one step ([COBRA] eq. (5)-(6)) on hand-built (G, c) problems.

Notation (cobra_ref/contact_qp.py): impulses p = [p_N, p_t1, p_t2] per contact, Delassus
matrix G = J_c M^-1 J_c^T, free contact velocity c, contact velocity after the step
w = G p + c. The QP is

    min_p 1/2 p^T G p + p^T c   s.t.  p_N >= 0,  |d_k . p_T| <= mu p_N   (K = 4 facets),

and its KKT conditions are the velocity-level Signorini-Coulomb law of eq. (2).

Hand problems use a point mass m with its contact frame at the mass: the contact Jacobian
is the identity, so G = M^-1 = I / m, and a resting or sliding mass under gravity has the
free contact velocity c = [-g dt, v_t1, v_t2] after one step of free fall.

Tolerances come from the solver settings, never from a run:

* ContactQP adds eps I to G, eps = REG mean(diag G) (REG = 1e-6, module docstring), so it
  solves (G + eps I) p = -c exactly where unconstrained: p is lower by the factor 1 / (1 + eps m)
  and w moves by -eps p;
* OSQP stops at eps_abs = eps_rel = OSQP_EPS = 1e-7 on its residuals;
* the friction fixed point stops when p_N changes by less than FP_TOL = 1e-8 max p_N.
"""

import numpy as np
import pytest

from cobra_ref.fast.contact_qp import (ContactQP, _cond_factored, _newton_update, coulomb_fixed_point, facet_directions,
                                  kkt_residuals)

GRAVITY = 9.81  # [m/s^2]
DT = 1e-3  # [s]
REG = 1e-6  # ContactQP's default regularization factor
OSQP_EPS = 1e-7  # ContactQP's default eps_abs = eps_rel
FP_TOL = 1e-8  # ContactQP's default fixed-point tolerance (relative to max p_N)


def _point_mass_delassus(mass):
    """G = J M^-1 J^T with J = I (contact frame at the mass) and M = m I."""
    return np.eye(3) / mass


def _random_problem(rng, m, n=12):
    """G = J M^-1 J^T from a random SPD M (n x n) and a random J (3m x n); c with mixed signs.

    Normal free velocities c_N are drawn in [-1, 0.3] m/s (most contacts approach, some
    separate); tangential ones are standard normal.
    """
    A = rng.normal(size=(n, n))
    M = A @ A.T + n * np.eye(n)
    J = rng.normal(size=(3 * m, n))
    G = J @ np.linalg.solve(M, J.T)
    G = 0.5 * (G + G.T)
    c = rng.normal(size=3 * m)
    c[0::3] = rng.uniform(-1.0, 0.3, size=m)
    return G, c


def _tolerances(G, c, p, mu):
    """Velocity and impulse tolerances implied by the solver settings (module docstring).

    tol_w: the regularization moves w by eps p and OSQP's dual residual may reach
           OSQP_EPS (1 + |c|) (eps_abs + eps_rel times the size of the data); x 10 margin.
    tol_p: OSQP's primal residual OSQP_EPS (1 + |p|), plus the fixed point's friction bound
           mu pbar_N which differs from mu p_N by up to mu FP_TOL max p_N; x 10 margin.
    """
    eps = REG * np.mean(np.diag(G))
    p_inf = float(np.abs(p).max(initial=0.0))
    tol_w = 10 * (eps * p_inf + OSQP_EPS * (1 + np.abs(c).max()))
    tol_p = 10 * (OSQP_EPS * (1 + p_inf) + mu * FP_TOL * p_inf)
    return tol_w, tol_p


def _impulse_atol(G, c, p):
    """How far OSQP's p may be from the exact minimiser of the regularized problem, plus its bias.

    For a strongly convex QP, a point whose KKT residual is r lies within r / lambda_min(G) of
    the minimiser; OSQP's residuals are below OSQP_EPS (1 + |c|). The regularization lowers p
    by up to REG |p| relative to the unregularized solution; x 2 margin on that.
    """
    return OSQP_EPS * (1 + np.abs(c).max()) / np.linalg.eigvalsh(G)[0] + 2 * REG * np.abs(p).max()


# --------------------------------------------------------------------------- hand problems


@pytest.mark.parametrize("friction", ["fixed-point", "convex"])
def test_point_mass_resting_on_the_plane_receives_weight_times_dt(friction, mass=2.0, mu=0.5):
    """A mass at rest on the plane needs the impulse m g dt over one step ([COBRA] eq. (6), 1 contact).

    G = I / m, c = [-g dt, 0, 0]. The unconstrained minimiser of 1/2 p^T G p + p^T c is
    p = -G^-1 c = [m g dt, 0, 0]; it has p_N > 0 and p_T = 0 inside the pyramid, so it is the
    constrained one too, and w = G p + c = 0: the mass neither sinks nor lifts off.
    With the regularization, (1/m + eps) p_N = g dt, eps = REG / m: p_N = m g dt / (1 + REG).
    rtol 1e-6 is tighter than OSQP's guarantee (_impulse_atol: 1e-5 relative here) but holds:
    at the first fixed-point iterate the friction rows are active (bound mu * 0), OSQP's
    solution polishing returns the exact KKT point, and the second iterate starts from it.
    """
    G, c = _point_mass_delassus(mass), np.array([-GRAVITY * DT, 0.0, 0.0])
    p, info = ContactQP(mu, friction=friction).solve(G, c)
    assert info.status == "solved"
    np.testing.assert_allclose(p[0], mass * GRAVITY * DT / (1 + REG), rtol=1e-6)
    np.testing.assert_allclose(p[1:], 0.0, atol=1e-6 * mass * GRAVITY * DT)
    np.testing.assert_allclose(G @ p + c, 0.0, atol=2 * REG * GRAVITY * DT)


@pytest.mark.parametrize("axis, sign", [(1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)])
def test_point_mass_sliding_fast_keeps_sliding_with_friction_at_mu_times_normal(axis, sign, mass=2.0, mu=0.5,
                                                                                speed=1.0):
    """Coulomb: a slide faster than mu g dt per step is slowed by mu g dt, p_T = -mu p_N along the slip.

    G = I / m, c = [-g dt, v along t_axis]. Normal: p_N = m g dt as at rest (the tangential
    rows of G do not couple to the normal one). Tangential: stopping the slip would need
    |p_T| = m |v| > mu m g dt, outside the pyramid, so p_T sits on the facet that opposes the
    slip, p_T = -mu p_N sign(v), and the mass still slides with w_T = v - mu g dt sign(v).
    Facets d_0 = t1 and d_1 = t2 (K = 4) make the pyramid exact along either axis.
    """
    G = _point_mass_delassus(mass)
    c = np.array([-GRAVITY * DT, 0.0, 0.0])
    c[axis] = sign * speed
    p, info = ContactQP(mu).solve(G, c)
    assert info.status == "solved"
    p_N = mass * GRAVITY * DT
    expected = np.zeros(3)
    expected[0], expected[axis] = p_N, -sign * mu * p_N
    np.testing.assert_allclose(p, expected, rtol=0, atol=_impulse_atol(G, c, expected))
    w = G @ p + c
    np.testing.assert_allclose(w[axis], sign * (speed - mu * GRAVITY * DT), atol=_impulse_atol(G, c, expected) / mass)
    assert p[axis] * w[axis] < 0, "friction must oppose the slip"


def test_point_mass_sliding_slower_than_mu_g_dt_sticks_within_the_step(mass=2.0, mu=0.5):
    """Coulomb: a slip v with |v| < mu g dt is stopped inside the pyramid: p_T = -m v, w_T = 0.

    G = I / m, c = [-g dt, v, 0] with v = 0.4 mu g dt. The unconstrained minimiser
    p = -G^-1 c = [m g dt, -m v, 0] has |p_T| = 0.4 mu p_N < mu p_N: it is feasible, hence
    the solution, and the contact sticks (w = 0) within this step.
    """
    v = 0.4 * mu * GRAVITY * DT
    G, c = _point_mass_delassus(mass), np.array([-GRAVITY * DT, v, 0.0])
    p, info = ContactQP(mu).solve(G, c)
    assert info.status == "solved"
    expected = np.array([mass * GRAVITY * DT, -mass * v, 0.0])
    np.testing.assert_allclose(p, expected, rtol=0, atol=_impulse_atol(G, c, expected))
    w = G @ p + c
    tol_w, _ = _tolerances(G, c, p, mu)
    np.testing.assert_allclose(w[1:], 0.0, atol=tol_w, err_msg="a sticking contact must not slip")
    assert info.stick_slip_residual <= tol_w


@pytest.mark.parametrize("c_T", [(0.0, 0.0), (0.3, -0.2)])
def test_contact_moving_away_receives_no_impulse(c_T, mass=1.0, mu=0.5):
    """Signorini: 0 <= p_N _|_ w_N >= 0. A contact separating by itself (c_N > 0) gets p = 0.

    With p = 0, w = c has w_N = c_N > 0, so p_N = 0 is forced by complementarity; the pyramid
    |p_T| <= mu p_N = 0 then forces p_T = 0 as well, whatever the tangential velocity.
    """
    G, c = _point_mass_delassus(mass), np.array([0.1, *c_T])
    p, info = ContactQP(mu).solve(G, c)
    assert info.status == "solved"
    np.testing.assert_allclose(p, 0.0, atol=_impulse_atol(G, c, p))


# ---------------------------------------------------------------- optimality conditions


def test_random_five_contact_solutions_satisfy_signorini_and_coulomb(rng, mu=0.5):
    """KKT of eq. (6) = the velocity-level law of eq. (2), checked contact by contact.

    For random problems G = J M^-1 J^T (5 contacts, 12 DoF: G is 15 x 15 of rank 12, so
    contacts are redundant as on the real robot) and w = G p + c:

    * Signorini: p_N >= 0, w_N >= 0, p_N w_N = 0;
    * pyramid: |d_k . p_T| <= mu p_N for the K = 4 facets d_0 = t1, d_1 = t2;
    * friction, component by component (the 4-facet pyramid is the box |p_ti| <= mu p_N):
      strictly inside the box w_ti = 0; on the box p_ti = -mu p_N sign(w_ti), so
      p_T . w_T <= 0 (maximal dissipation); sticking contacts (p_T strictly inside) have
      w_T = 0.

    fp_max = 300 lets the damped fixed point reach its tolerance (the default 50 does not
    always from a cold start). Over the 4 problems every branch (separating,
    sticking, sliding) must occur, so that each check has been exercised.
    """
    D = facet_directions(4)
    seen = {"separating": 0, "sticking": 0, "sliding": 0}
    for trial in range(4):
        G, c = _random_problem(rng, m=5)
        p, info = ContactQP(mu, fp_max=300).solve(G, c)
        assert info.status == "solved", f"problem {trial}: {info.status}"
        tol_w, tol_p = _tolerances(G, c, p, mu)
        w = G @ p + c
        p_N, w_N = p[0::3], w[0::3]
        p_T, w_T = np.stack([p[1::3], p[2::3]], 1), np.stack([w[1::3], w[2::3]], 1)
        assert np.all(p_N >= -tol_p), f"problem {trial}: pulling normal impulse {p_N.min()}"
        assert np.all(w_N >= -tol_w), f"problem {trial}: approaching contact w_N = {w_N.min()}"
        comp_tol = max(tol_p * np.abs(w).max(), tol_w * np.abs(p).max())
        np.testing.assert_allclose(p_N * w_N, 0.0, atol=comp_tol, err_msg=f"complementarity, problem {trial}")
        assert np.all(np.abs(p_T @ D.T) <= mu * p_N[:, None] + tol_p), f"outside the pyramid, problem {trial}"
        for k in range(5):
            if p_N[k] <= tol_p:
                seen["separating"] += 1
                continue
            on_bound = np.abs(p_T[k]) >= mu * p_N[k] - tol_p
            seen["sliding" if on_bound.any() else "sticking"] += 1
            np.testing.assert_allclose(w_T[k][~on_bound], 0.0, atol=tol_w,
                                       err_msg=f"slip inside the pyramid, contact {k}, problem {trial}")
            moving = np.abs(w_T[k]) > tol_w
            np.testing.assert_allclose(p_T[k][moving], -mu * p_N[k] * np.sign(w_T[k][moving]), atol=tol_p,
                                       err_msg=f"friction not at the facet opposing the slip, contact {k}")
            assert p_T[k] @ w_T[k] <= tol_w * np.abs(p).max(), f"friction does work > 0, contact {k}"
        comp, cone, stick = kkt_residuals(G, c, p, mu, D)
        assert comp <= comp_tol and cone <= tol_p / max(p_N.max(), 1e-12) and stick <= tol_w
    assert all(seen.values()), f"every branch must be exercised, got {seen}"


def test_default_friction_fixed_point_converges_on_random_five_contact_problems(rng, mu=0.5):
    """Same problems as the test above, default settings: the fixed point should converge.

    With the Newton update (module docstring, note friction) cold starts of such problems
    converge within 8 iterates (measured: all of 60 on the default path); the plain update
    needed 10-50. These four must converge within the default fp_max = 50.
    """
    statuses = []
    for _ in range(4):
        G, c = _random_problem(rng, m=5)
        statuses.append(ContactQP(mu).solve(G, c)[1].status)
    assert statuses == ["solved"] * 4, statuses


@pytest.mark.parametrize("fp_path", ["active-set", "osqp"])
def test_the_fixed_point_of_a_sliding_point_mass_is_one_linear_solve(fp_path, mass=2.0, mu=0.5, speed=1.0):
    """coulomb_fixed_point on the sliding point mass, worked by hand, and the solver's answer.

    P = (1/m + eps) I (eps = REG / m), c = [-g dt, v, 0] with v = 1 m/s >> mu g dt: the mass
    slides along t1, so the active set is "p_t1 held at its lower bound -mu p_N". Then

        (P p + c)_N = 0   ->  p_N = g dt / (1/m + eps)
        p_t1 + mu p_N = 0 ->  p_t1 = -mu p_N
        (P p + c)_t2 = 0  ->  p_t2 = 0

    in one linear solve, and ContactQP (either fixed-point path) returns the same impulses.
    """
    eps = REG / mass
    P, c = (1 / mass + eps) * np.eye(3), np.array([-GRAVITY * DT, speed, 0.0])
    at_lo, at_hi = np.array([False, True, False]), np.zeros(3, dtype=bool)
    p_N = GRAVITY * DT / (1 / mass + eps)
    expected = np.array([p_N, -mu * p_N, 0.0])
    np.testing.assert_allclose(coulomb_fixed_point(P, c, np.array([mu]), at_lo, at_hi), expected, rtol=1e-14)
    p, info = ContactQP(mu, fp_path=fp_path).solve(_point_mass_delassus(mass), c)
    assert info.status == "solved"
    np.testing.assert_allclose(p, expected, rtol=1e-6)


def test_a_newton_guess_that_more_than_triples_the_normal_impulses_is_not_taken(mass=2.0, mu=0.5):
    """The sliding point mass again: its fixed point has p_N = g dt / (1/m + eps), about 0.0196 N s.

    From a last iterate with that p_N the Newton guess is taken; from one with a thousandth of
    it the guess would multiply the normal impulse by 1000, so it is refused (None: the plain
    update is taken instead), the guard against wrong active sets (NEWTON_MAX_GROWTH = 3).
    """
    P, c = (1 / mass + REG / mass) * np.eye(3), np.array([-GRAVITY * DT, 1.0, 0.0])
    at_lo, at_hi = np.array([False, True, False]), np.zeros(3, dtype=bool)
    p_N = GRAVITY * DT / (1 / mass + REG / mass)
    np.testing.assert_allclose(_newton_update(P, c, np.array([mu]), at_lo, at_hi, np.array([p_N])), [p_N])
    assert _newton_update(P, c, np.array([mu]), at_lo, at_hi, np.array([1e-3 * p_N])) is None


def test_an_osqp_failure_after_the_first_iterate_keeps_the_best_iterate(rng, monkeypatch, mu=0.5):
    """OSQP failing on a later fixed-point iterate does not end the step: the best iterate so
    far is returned with the "not converged" status. The failure is injected on the second
    OSQP solve of the reference path (fp_path="osqp"); a failure on the first still raises."""
    from cobra_ref.fast import contact_qp

    G, c = _random_problem(rng, m=5)
    qp = ContactQP(mu, fp_path="osqp")
    run, calls = qp._run, []

    def failing_run(*args):
        calls.append(1)
        if len(calls) == 2:
            raise contact_qp.ContactSolveError("injected")
        return run(*args)

    monkeypatch.setattr(qp, "_run", failing_run)
    p, info = qp.solve(G, c)
    assert info.status.startswith("solved (fixed point not converged") and info.fp_iterations == 2
    comp, cone, _ = kkt_residuals(G, c, p, mu, facet_directions(4))
    assert cone <= 1e-9, "the kept iterate is clipped into the pyramid"
    calls.clear()
    monkeypatch.setattr(qp, "_run", lambda *a: (_ for _ in ()).throw(contact_qp.ContactSolveError("first")))
    with pytest.raises(contact_qp.ContactSolveError):
        qp.solve(G, c)


def test_fast_and_reference_fixed_points_give_the_same_impulses(rng, mu=0.5):
    """fp_path="active-set" (certified re-solves) against "osqp" (OSQP for every iterate).

    Same random 5-contact problems (rank-deficient G, as on the robot). Both must report the
    same status, and where both converge, the same impulses: each iterate is a QP minimiser
    within OSQP's tolerance, and the fixed point they converge to is the same, so they agree
    to the _tolerances of the test above.
    """
    compared = 0
    for trial in range(8):
        G, c = _random_problem(rng, m=5)
        p_fast, info_fast = ContactQP(mu, fp_path="active-set").solve(G, c)
        p_ref, info_ref = ContactQP(mu, fp_path="osqp").solve(G, c)
        assert info_fast.status == info_ref.status, f"problem {trial}"
        if info_ref.status != "solved":
            continue
        compared += 1
        tol_w, tol_p = _tolerances(G, c, p_ref, mu)
        np.testing.assert_allclose(p_fast, p_ref, atol=tol_p, err_msg=f"problem {trial}")
        assert info_fast.osqp_solves <= info_ref.osqp_solves
    assert compared >= 6


def test_cond_of_g_from_its_factor_equals_the_eigenvalues_of_the_full_matrix(rng):
    """cond(B B^T + eps I) from the r x r Gram matrix B^T B equals the 3m x 3m eigenproblem,
    for 3m > r (redundant contacts: smallest eigenvalue eps) and 3m < r."""
    for n, r in ((15, 12), (6, 12)):
        B = rng.normal(size=(n, r))
        eps = 1e-6 * np.trace(B @ B.T) / n
        lam = np.linalg.eigvalsh(B @ B.T + eps * np.eye(n))
        assert _cond_factored(B, eps) == pytest.approx(lam[-1] / lam[0], rel=1e-6)


def _projected_gauss_seidel(P, c, mu, tol=1e-14, max_sweeps=100_000):
    """An independent solver of the same problem: PGS on the NCP of eq. (6) with K = 4 facets.

    Row by row, r = 3 i + j: relax p_r so that w_r = (P p + c)_r = 0, then project:
    normal rows onto p_N >= 0, tangential rows onto the box |p_tj| <= mu p_N of the same
    contact (the 4-facet pyramid). Sweeps until p changes by less than tol |p|.
    """
    p = np.zeros(len(c))
    for _ in range(max_sweeps):
        p_old = p.copy()
        for r in range(len(c)):
            p[r] -= (P[r] @ p + c[r]) / P[r, r]
            i = r - r % 3
            p[r] = max(p[r], 0.0) if r == i else np.clip(p[r], -mu * p[i], mu * p[i])
        if np.abs(p - p_old).max() <= tol * max(np.abs(p).max(), 1e-300):
            return p
    raise RuntimeError("projected Gauss-Seidel did not converge")


def test_projected_gauss_seidel_and_osqp_find_the_same_impulses(rng, mu=0.5):
    """Two solvers of one problem agree: OSQP's friction fixed point and projected Gauss-Seidel.

    m = 3 contacts on 12 DoF: G (9 x 9) has full rank, so the least-action problem is strongly
    convex for fixed friction bounds and its solution unique. PGS is given exactly the matrix
    ContactQP minimises, P = G + REG mean(diag G) I (module docstring, note regularization).

    Tolerance: for a strongly convex QP a point whose KKT residual is r lies within
    r / lambda_min(P) of the minimiser; OSQP's residuals are below OSQP_EPS (1 + |c|), so
    atol = OSQP_EPS (1 + |c|) / lambda_min(P), plus the fixed point's mu FP_TOL |p|.
    """
    G, c = _random_problem(rng, m=3)
    P = G + REG * np.mean(np.diag(G)) * np.eye(9)
    lam_min = np.linalg.eigvalsh(P)[0]
    assert lam_min > 1e-3 * np.linalg.eigvalsh(P)[-1], "precondition: well-conditioned G"
    p_osqp, info = ContactQP(mu).solve(G, c)
    assert info.status == "solved"
    p_pgs = _projected_gauss_seidel(P, c, mu)
    assert p_pgs[0::3].max() > 0.1, "precondition: some contacts must be active"
    atol = OSQP_EPS * (1 + np.abs(c).max()) / lam_min + mu * FP_TOL * np.abs(p_pgs).max()
    np.testing.assert_allclose(p_osqp, p_pgs, atol=atol)


# ------------------------------------------------------------------------- convex option


def test_convex_friction_turns_a_fast_slide_into_a_jump(mass=2.0, mu=1.0, speed=1.0):
    """The documented artefact of friction="convex" (Anitescu relaxation, contact_qp docstring).

    With mu p_N inside the constraints, the KKT conditions of the sliding facet
    mu p_N + p_t1 >= 0 give w_N = mu w_t1 instead of w_N = 0. Point mass, c = [-g dt, v, 0],
    p_t1 = -mu p_N:  w_N = -g dt + p_N / m,  w_t1 = v - mu p_N / m, so

        p_N = m (mu v + g dt) / (1 + mu^2) = 1.00981 N s  for m = 2, mu = 1, v = 1,

    about 51 times m g dt: the mass leaves the ground at w_N = -g dt + p_N / m
    = mu (v - mu g dt) / (1 + mu^2) = 0.495 m/s.
    """
    G, c = _point_mass_delassus(mass), np.array([-GRAVITY * DT, speed, 0.0])
    p, info = ContactQP(mu, friction="convex").solve(G, c)
    assert info.status == "solved"
    assert p[0] > 10 * mass * GRAVITY * DT
    np.testing.assert_allclose(p[0], mass * (mu * speed + GRAVITY * DT) / (1 + mu**2), atol=_impulse_atol(G, c, p))
    w = G @ p + c  # regularized KKT: w_N - mu w_t1 = -eps (1 + mu^2) p_N ~ 2e-6 relative; rtol 1e-5
    np.testing.assert_allclose(w[0], mu * w[1], rtol=1e-5, err_msg="Anitescu: w_N = mu |w_T|")
    # the default (exact Coulomb) keeps the same mass on the ground
    p_fp, _ = ContactQP(mu).solve(G, c)
    np.testing.assert_allclose(p_fp[0], mass * GRAVITY * DT, atol=_impulse_atol(G, c, p_fp))


def test_convex_friction_pushes_a_contact_that_separates_slower_than_mu_times_its_slip(mass=1.0, mu=1.0):
    """Same artefact at a separating contact: Anitescu's w_N = mu |w_T| keeps it active.

    c = [0.1, 0.3, 0]: the contact separates at 0.1 m/s while slipping at 0.3 m/s. Exact
    Coulomb gives p = 0 (test above). The convex QP instead needs w_N = mu w_t1 with
    p_t1 = -mu p_N: 0.1 + p_N / m = mu (0.3 - mu p_N / m), so p_N = m (0.3 mu - 0.1) / (1 + mu^2)
    = 0.1 N s for m = 1, mu = 1.
    """
    G, c = _point_mass_delassus(mass), np.array([0.1, 0.3, 0.0])
    p, info = ContactQP(mu, friction="convex").solve(G, c)
    assert info.status == "solved"
    np.testing.assert_allclose(p, [0.1, -0.1, 0.0], atol=_impulse_atol(G, c, p))


# ------------------------------------------------------------------------ helpers, errors


def test_facet_directions_are_unit_normals_at_multiples_of_two_pi_over_k():
    """d_k = (cos 2 pi k / K, sin 2 pi k / K), k < K / 2: K = 4 gives t1, t2; K = 8 adds diagonals."""
    np.testing.assert_allclose(facet_directions(4), [[1, 0], [0, 1]], atol=1e-15)
    s = np.sqrt(0.5)
    np.testing.assert_allclose(facet_directions(8), [[1, 0], [s, s], [0, 1], [-s, s]], atol=1e-15)


def test_kkt_residuals_measure_complementarity_cone_and_stick_violations():
    """kkt_residuals on hand-made wrong impulses (G = I, one contact, mu = 0.5).

    * p = [1, 0, 0] with c = [1, 0, 0]: w_N = 2 while p_N = 1, complementarity |p_N w_N| = 2;
    * p = [1, 2, 0]: facet |p_t1| = 2 exceeds mu p_N = 0.5 by 1.5, relative to max p_N = 1;
    * p = [1, 0.1, 0] with c = [-1, 0.2, 0]: inside the pyramid but w_t1 = 0.3, stick residual 0.3.
    """
    G, D = np.eye(3), facet_directions(4)
    comp, _, _ = kkt_residuals(G, np.array([1.0, 0, 0]), np.array([1.0, 0, 0]), 0.5, D)
    np.testing.assert_allclose(comp, 2.0, atol=1e-15)
    _, cone, _ = kkt_residuals(G, np.array([-1.0, 0, 0]), np.array([1.0, 2.0, 0]), 0.5, D)
    np.testing.assert_allclose(cone, 1.5, atol=1e-15)
    _, _, stick = kkt_residuals(G, np.array([-1.0, 0.2, 0]), np.array([1.0, 0.1, 0]), 0.5, D)
    np.testing.assert_allclose(stick, 0.3, atol=1e-15)


def test_a_lightly_loaded_contact_sliding_at_its_bound_is_not_counted_as_sticking():
    """Two contacts (G = I, mu = 0.5): one carries p_N = 1 and sticks (w_T = 0); the other carries
    p_N = 1e-6 and slides at w_t1 = 0.1 m/s with p_t1 = -mu p_N (1 - 2e-6), on its bound to within
    1e-12 N s. "Strictly inside" is measured against the largest load (by 1e-6 mu max p_N =
    5e-7 N s), so the stick residual is 0, not 0.1 (a 10 s run reported such a contact before
    this scale was used). A contact with p_N = 1e-3 and p_t1 = 0, clearly inside, sliding at
    0.1 m/s, does count: residual 0.1.
    """
    G, D = np.eye(6), facet_directions(4)
    p = np.array([1.0, 0.0, 0.0, 1e-6, -0.5e-6 * (1 - 2e-6), 0.0])
    c = np.array([-1.0, 0.0, 0.0, -1e-6, 0.1 - p[4], 0.0])  # w = p + c: w_N = 0, w_t1 = 0.1
    _, _, stick = kkt_residuals(G, c, p, 0.5, D)
    assert stick == 0.0
    p[3:5] = 1e-3, 0.0
    c[3:5] = -1e-3, 0.1
    _, _, stick = kkt_residuals(G, c, p, 0.5, D)
    np.testing.assert_allclose(stick, 0.1, atol=1e-15)


@pytest.mark.parametrize("n_facets", [3, 2, 0, 5])
def test_facet_count_must_be_even_and_at_least_four(n_facets):
    """K facets make a regular K-gon from K/2 directions: K must be even and >= 4."""
    with pytest.raises(ValueError, match="n_facets"):
        facet_directions(n_facets)


@pytest.mark.parametrize("mu", [-1.0, np.nan, np.inf])
def test_friction_coefficient_must_be_finite_and_non_negative(mu):
    """A friction pyramid |p_T| <= mu p_N needs 0 <= mu < inf."""
    with pytest.raises(ValueError, match="mu"):
        ContactQP(mu=mu)


def test_unknown_friction_option_is_rejected():
    """Only "fixed-point" and "convex" are implemented."""
    with pytest.raises(ValueError, match="friction"):
        ContactQP(0.5, friction="exact")
