"""Certified active-set solves of box QPs (cobra_ref/fast/active_set.py) against hand-solved QPs and OSQP.

The QP: min 1/2 x^T H x + c^T x  s.t.  lo <= x <= hi, H positive definite (every least-action
iterate has this form). An answer is accepted only if it satisfies the KKT conditions at
OSQP's tolerances, so every test here checks one of two things: a certified answer is the
minimiser (against a hand solution or OSQP), and a wrong answer is refused, never returned.
"""

import numpy as np
import osqp
from scipy import sparse

from cobra_ref.fast.active_set import BoxQP, box_certificate, held_at_bounds, solve_box
from cobra_ref.fast.least_action import FastBoxQP
from cobra_ref.qp import EPS, solve_box_qp


def test_diagonal_box_qp_is_solved_by_clipping_the_unconstrained_minimiser():
    """H = diag(d): the problem separates, x_i = clip(-q_i / d_i, lo_i, hi_i) (worked by hand).

    d = (1, 2, 4), c = (-3, 1, -2): unconstrained minimiser (3, -0.5, 0.5); with lo = (0, 0, -1)
    and hi = (2, inf, 1) the answer is (2, 0, 0.5): x_0 held at hi (gradient 2 - 3 = -1 <= 0),
    x_1 held at lo (gradient 0 + 1 = 1 >= 0), x_2 free (gradient 0).
    """
    H, c = np.diag([1.0, 2.0, 4.0]), np.array([-3.0, 1.0, -2.0])
    lo, hi = np.array([0.0, 0.0, -1.0]), np.array([2.0, np.inf, 1.0])
    x, at_lo, at_hi, r = solve_box(BoxQP(H, c, lo, hi), np.zeros(3), (EPS, EPS))
    np.testing.assert_allclose(x, [2.0, 0.0, 0.5], atol=1e-15)
    np.testing.assert_array_equal(at_lo, [False, True, False])
    np.testing.assert_array_equal(at_hi, [True, False, False])
    np.testing.assert_allclose(r, [-1.0, 1.0, 0.0], atol=1e-15)


def test_a_coupled_box_qp_reaches_the_minimiser_from_a_wrong_start_in_a_few_rounds():
    """H = [[2, 1], [1, 2]], c = (-4, 1), x >= 0 (worked by hand).

    Unconstrained: x = H^-1 (-c) = (1/3) [[2, -1], [-1, 2]] (4, -1) = (3, -2): x_1 < 0, so x_1
    is held at 0 and 2 x_0 = 4, x_0 = 2; the gradient of x_1 there is 1 * 2 + 1 = 3 >= 0: the
    KKT point (2, 0).
    Started from (0, 5) (x_0 held, x_1 free: the wrong set), the rounds must find it.
    """
    H, c = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-4.0, 1.0])
    x, at_lo, at_hi, r = solve_box(BoxQP(H, c, np.zeros(2), np.full(2, np.inf)), np.array([0.0, 5.0]), (EPS, EPS))
    np.testing.assert_allclose(x, [2.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(r, [0.0, 3.0], atol=1e-14)


def test_the_box_certificate_accepts_the_minimiser_and_refuses_each_kind_of_wrong_answer():
    """The 2-variable problem above (minimiser (2, 0), x_1 held at 0, gradient (0, 3)), with
    bounds 0 <= x <= 10, and one wrong answer per check of the certificate:

    * (3, -2) with nothing held: the unconstrained minimiser, stationary but below the bound
      x_1 >= 0 (primal);
    * (10, 0) with x_0 held at its upper bound 10: its gradient 2 * 10 - 4 = 16 > 0 pushes it
      down, a wrong-sign multiplier (dual);
    * (1, 0) with x_1 held: x_0 is free but its gradient 2 - 4 = -2 is not zero (stationarity);
    * (0, 0) with x_0 and x_1 held at 0: x_0's gradient -4 < 0 would pull it up (dual).
    """
    H, c = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-4.0, 1.0])
    lo, hi = np.zeros(2), np.full(2, 10.0)
    no, yes = False, True

    def certified(x, at_lo, at_hi):
        return box_certificate(BoxQP(H, c, lo, hi), np.array(x), np.array(at_lo), np.array(at_hi), (EPS, EPS))

    assert certified([2.0, 0.0], [no, yes], [no, no])
    assert not certified([3.0, -2.0], [no, no], [no, no])
    assert not certified([10.0, 0.0], [no, yes], [yes, no])
    assert not certified([1.0, 0.0], [no, yes], [no, no])
    assert not certified([0.0, 0.0], [yes, yes], [no, no])


def test_only_finite_bounds_hold_a_variable():
    """held_at_bounds: a variable at or past a finite bound is held there; a multiplier pointing at
    an infinite bound (OSQP's tiny dual noise on p_N <= inf) holds nothing."""
    x = np.array([0.0, 2.0, 1.0, 5.0])
    lo, hi = np.array([0.0, -1.0, 0.0, 0.0]), np.array([np.inf, 2.0, np.inf, np.inf])
    y = np.array([0.0, 0.0, 1e-12, 0.0])  # a positive dual on an infinite upper bound
    at_lo, at_hi = held_at_bounds(x, lo, hi, y)
    np.testing.assert_array_equal(at_lo, [True, False, False, False])
    np.testing.assert_array_equal(at_hi, [False, True, False, False])


def _random_box_qp(rng, m=4, n_dof=12, n_servo=3):
    """A least-action-like box QP: G = J M^-1 J^T + 1e-2 diag from a random SPD M, contact bounds
    (p_N >= 0, |p_T| <= r) and servo rows bounded both ways."""
    A = rng.normal(size=(n_dof, n_dof))
    M = A @ A.T + n_dof * np.eye(n_dof)
    J = rng.normal(size=(3 * m + n_servo, n_dof))
    G = J @ np.linalg.solve(M, J.T)
    H = 0.5 * (G + G.T) + 1e-2 * np.diag(np.diag(G))
    c = rng.normal(size=len(H))
    c[0:3 * m:3] = rng.uniform(-1.0, 0.3, size=m)
    r = rng.uniform(0.0, 0.5, size=m)
    lo = np.concatenate([np.column_stack([np.zeros(m), -r, -r]).ravel(), -np.full(n_servo, 0.3)])
    hi = np.concatenate([np.column_stack([np.full(m, np.inf), r, r]).ravel(), np.full(n_servo, 0.3)])
    return H, c, lo, hi


def test_certified_solutions_equal_osqp_on_random_least_action_qps(rng):
    """From OSQP's loose (1e-4) iterate, the certified answer equals OSQP's tight (1e-10) solution.

    Tolerance: H is strongly convex, so a point whose KKT residual is r lies within
    r / lambda_min(H) of the minimiser; both answers satisfy r <= EPS (1 + |c|).
    """
    accepted = 0
    for trial in range(8):
        H, c, lo, hi = _random_box_qp(rng)
        solutions = []
        for eps in (1e-4, 1e-10):
            solver = osqp.OSQP()
            solver.setup(P=sparse.triu(sparse.csc_matrix(H), format="csc"), q=c, A=sparse.identity(len(c), format="csc"),
                         l=lo, u=hi, eps_abs=eps, eps_rel=eps, polishing=False, verbose=False, max_iter=100000)
            solutions.append(solver.solve(raise_error=False))
        loose, tight = solutions
        assert tight.info.status == "solved"
        answer = solve_box(BoxQP(H, c, lo, hi), loose.x, (EPS, EPS), guess=held_at_bounds(loose.x, lo, hi, loose.y))
        if answer is None:
            continue
        accepted += 1
        lam_min = np.linalg.eigvalsh(H)[0]
        np.testing.assert_allclose(answer[0], tight.x, atol=2 * EPS * (1 + np.abs(c).max()) / lam_min)
    assert accepted >= 6, f"only {accepted} of 8 loose iterates led to a certified answer"


def test_the_fast_box_qp_equals_a_fresh_osqp_solve(rng):
    """FastBoxQP (loose OSQP + certificate on a step's first QP, a certificate from the start on
    later ones, tight OSQP otherwise) returns the minimiser that cobra_ref.qp.solve_box_qp does."""
    fast = FastBoxQP()
    for trial in range(8):
        H, c, lo, hi = _random_box_qp(rng)
        if trial % 2 == 0:
            fast.new_step()
        reference = solve_box_qp(H, c, lo, hi)
        answer = fast(H, c, lo, hi, np.zeros(len(c)))
        lam_min = np.linalg.eigvalsh(H)[0]
        np.testing.assert_allclose(answer.x, reference.x, atol=4 * EPS * (1 + np.abs(c).max()) / lam_min)
        assert answer.solves >= (1 if trial % 2 == 0 else 0)
