"""Certified active-set solves (cobra_ref/active_set.py) against hand-solved QPs and OSQP.

The QP, in OSQP's form: min 1/2 x^T P x + q^T x  s.t.  l <= A x <= u, P positive definite.
An answer is accepted only if it satisfies the KKT conditions at OSQP's tolerances (module
docstring), so every test here checks one of two things: a certified answer is the
minimiser (against a hand solution or OSQP), and a wrong guess is refused, never returned.
"""

import numpy as np
import osqp
import pytest
from scipy import sparse

from cobra_ref.fast.active_set import WorkingSet, box_certificate, box_form, certified_solve, solve_box, solve_on_working_set
from cobra_ref.fast.contact_qp import _constraint_matrix, facet_directions

EPS = 1e-7  # ContactQP's tolerance, used here for both eps_abs and eps_rel


def test_diagonal_box_qp_is_solved_by_clipping_the_unconstrained_minimiser():
    """P = diag(d): the problem separates, x_i = clip(-q_i / d_i, lo_i, hi_i) (worked by hand).

    d = (1, 2, 4), q = (-3, 1, -2): unconstrained minimiser (3, -0.5, 0.5); with lo = (0, 0, -1)
    and hi = (2, inf, 1) the answer is (2, 0, 0.5): x_0 held at hi (gradient 2 - 3 = -1 <= 0),
    x_1 held at lo (gradient 0 + 1 = 1 >= 0), x_2 free (gradient 0).
    """
    P, q = np.diag([1.0, 2.0, 4.0]), np.array([-3.0, 1.0, -2.0])
    lo, hi = np.array([0.0, 0.0, -1.0]), np.array([2.0, np.inf, 1.0])
    x, at_lo, at_hi, g = solve_box(P, q, lo, hi, np.zeros(3), EPS, EPS)
    np.testing.assert_allclose(x, [2.0, 0.0, 0.5], atol=1e-15)
    np.testing.assert_array_equal(at_lo, [False, True, False])
    np.testing.assert_array_equal(at_hi, [True, False, False])
    np.testing.assert_allclose(g, [-1.0, 1.0, 0.0], atol=1e-15)


def test_a_coupled_box_qp_reaches_the_minimiser_from_a_wrong_start_in_a_few_rounds():
    """P = [[2, 1], [1, 2]], q = (-4, 1), x >= 0 (worked by hand).

    Unconstrained: x = P^-1 (-q) = (1/3) [[2, -1], [-1, 2]] (4, -1) = (3, -2): x_1 < 0, so x_1
    is held at 0 and 2 x_0 = 4, x_0 = 2; the gradient of x_1 there is 1 * 2 + 1 = 3 >= 0: the
    KKT point (2, 0).
    Started from (0, 5) (x_0 held, x_1 free: the wrong set), the rounds must find it.
    """
    P, q = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-4.0, 1.0])
    x, at_lo, at_hi, g = solve_box(P, q, np.zeros(2), np.full(2, np.inf), np.array([0.0, 5.0]), EPS, EPS)
    np.testing.assert_allclose(x, [2.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(g, [0.0, 3.0], atol=1e-14)


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
    P, q = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-4.0, 1.0])
    lo, hi = np.zeros(2), np.full(2, 10.0)
    no, yes = False, True

    def certified(x, at_lo, at_hi):
        return box_certificate(P, q, lo, hi, np.array(x), np.array(at_lo), np.array(at_hi), EPS, EPS)

    assert certified([2.0, 0.0], [no, yes], [no, no])
    assert not certified([3.0, -2.0], [no, no], [no, no])
    assert not certified([10.0, 0.0], [no, yes], [yes, no])
    assert not certified([1.0, 0.0], [no, yes], [no, no])
    assert not certified([0.0, 0.0], [yes, yes], [no, no])


def test_a_guess_that_is_not_the_minimiser_is_refused():
    """The same 2-variable problem through the general KKT path, with wrong working sets.

    * nothing held: the KKT solve gives the unconstrained (3, -2), which violates x_1 >= 0
      (primal infeasible): refused;
    * x_0 held at 0 as well: x = (0, 0), and P x + q + y = 0 gives y = -q = (4, -1); a lower
      bound needs y <= 0 in OSQP's sign convention, and y_0 = 4: refused;
    * only x_1 held: the minimiser (2, 0): accepted, with y = (0, -3).
    """
    P, q, A = np.array([[2.0, 1.0], [1.0, 2.0]]), np.array([-4.0, 1.0]), np.eye(2)
    l, u = np.zeros(2), np.full(2, np.inf)
    none = WorkingSet(np.array([False, False]), np.array([False, False]))
    both = WorkingSet(np.array([True, True]), np.array([False, False]))
    right = WorkingSet(np.array([False, True]), np.array([False, False]))
    assert solve_on_working_set(P, q, A, l, u, none, EPS, EPS) is None
    assert solve_on_working_set(P, q, A, l, u, both, EPS, EPS) is None
    x, y = solve_on_working_set(P, q, A, l, u, right, EPS, EPS)
    np.testing.assert_allclose(x, [2.0, 0.0], atol=1e-14)
    np.testing.assert_allclose(y, [0.0, -3.0], atol=1e-14)


def test_the_four_facet_pyramid_is_a_box_and_the_eight_facet_one_is_not():
    """K = 4: rows p_N, t1 . p_T, t2 . p_T, each one unit entry on its own column (a signed
    permutation of the 3m impulses); K = 8 adds diagonal facets (two entries per row)."""
    A4 = _constraint_matrix(3, facet_directions(4)).toarray()
    form = box_form(A4)
    assert form is not None
    np.testing.assert_array_equal(np.sort(form.col), np.arange(9))
    assert box_form(_constraint_matrix(3, facet_directions(8)).toarray()) is None


@pytest.mark.parametrize("n_facets", [4, 8])
def test_certified_solutions_equal_osqp_on_random_contact_qps(rng, n_facets, mu=0.5):
    """Random least-action QPs with fixed friction bounds: the certified answer from OSQP's
    loose (1e-4) iterate equals OSQP's tight (1e-10) solution.

    Tolerance: P is strongly convex (m = 3 contacts on 12 DoF, full rank), so a point whose
    KKT residual is r lies within r / lambda_min(P) of the minimiser; both answers satisfy
    r <= EPS (1 + |q|) at most (the certified one by its checks).
    """
    D = facet_directions(n_facets)
    accepted = 0
    for trial in range(6):
        m, n = 3, 12
        M = (lambda B: B @ B.T + n * np.eye(n))(rng.normal(size=(n, n)))
        J = rng.normal(size=(3 * m, n))
        G = J @ np.linalg.solve(M, J.T)
        P = 0.5 * (G + G.T) + 1e-6 * np.mean(np.diag(G)) * np.eye(3 * m)
        q = rng.normal(size=3 * m)
        q[0::3] = rng.uniform(-1.0, 0.3, size=m)
        A = _constraint_matrix(m, D)
        bound = np.repeat(mu * rng.uniform(0.0, 2.0, size=m), len(D))
        l = np.concatenate([np.zeros(m), -bound])
        u = np.concatenate([np.full(m, np.inf), bound])
        solutions = []
        for eps in (1e-4, 1e-10):
            solver = osqp.OSQP()
            solver.setup(P=sparse.triu(sparse.csc_matrix(P), format="csc"), q=q, A=A, l=l, u=u,
                         eps_abs=eps, eps_rel=eps, polishing=False, verbose=False, max_iter=100000)
            solutions.append(solver.solve(raise_error=False))
        loose, tight = solutions
        assert tight.info.status == "solved"
        answer = certified_solve(P, q, A.toarray(), l, u, loose.x, loose.y, EPS, EPS, box_form(A.toarray()))
        if answer is None:
            continue
        accepted += 1
        lam_min = np.linalg.eigvalsh(P)[0]
        np.testing.assert_allclose(answer[0], tight.x, atol=2 * EPS * (1 + np.abs(q).max()) / lam_min)
        # the duals too (the rows of A are independent, so they are unique): OSQP's sign convention
        np.testing.assert_allclose(answer[1], tight.y, atol=1e-5 * np.abs(tight.y).max())
    assert accepted >= 4, f"only {accepted} of 6 loose iterates led to a certified answer"
