"""The least-action problem of one time step: Delassus matrix, QP, and Coulomb's friction circle.

Implements: [COBRA] eq. (5)-(6) for the impulses x = f dt of one step. The rows are the m
contacts ([n, t1, t2] each, :mod:`cobra_ref.contact`) and, with the position servo, one row per
joint; :mod:`cobra_ref.compliance` gives each row its compliance R and offset b::

    G = J M^-1 J^T                                  eq. (5): Delassus matrix
    c = J qd_free + b                                eq. (5): the rows' velocity without impulses
    min_x  1/2 x^T (G + R) x + x^T c                eq. (6): least action
    s.t.   p_N >= 0,  ||p_T|| <= mu p_N              F_i of eq. (2): Coulomb's circle, per contact
           |lambda_j| <= tau_max dt                  eq. (6) constraint (3), per servo row

Its optimality conditions are eq. (2) at the velocity level. With r = (G + R) x + c, the law's
residual on each row: a contact carries p_N > 0 only where r_N = 0 (its normal law holds) and
none where r_N > 0 (it separates); friction sticks (r_T = 0) inside the circle and, on it,
opposes the slip r_T with magnitude mu p_N (``kkt_residuals`` measures each condition).

Friction (``solve_least_action``). Coulomb's law bounds friction by mu times the normal
impulse, itself an unknown, so the problem is a fixed point of QPs: each QP bounds friction by
mu pbar_N with a guess pbar_N (the De Saxce fixed point; eq. (6) with mu pbar_N in F_i), and
the guess is right when the QP's p_N equals it. OSQP solves QPs, not cones, so each circle
||p_T|| <= r = mu pbar_N is replaced by the square |p_t1'|, |p_t2'| <= r in the tangent frame
(t1', t2') turned by an angle theta_i so that t1' points along the contact's friction: the
square contains the circle and touches it at +-r t1', so a minimiser on that side of the square,
or inside the circle, is the minimiser over the circle. The loop::

    x <- the previous step's impulses;  (pbar_N, theta, x) <- guess(x)
    repeat:  x <- the box QP with (pbar_N, theta), from x      (OSQP)
             stop if the natural residual of x is below FP_TOL max(max p_N, impulse_floor)
             (pbar_N, theta, x) <- guess(x)
             from iterate FP_RELAX_AFTER on: pbar_N <- (pbar_N_last + pbar_N) / 2,
                 e(theta) <- the direction of e(theta_last) + e(theta)

``guess`` solves the exact conditions of Coulomb's law on the active set of x (which contacts
are released, which stick, which slide, which servo rows saturate) by Newton's method
(:func:`cobra_ref.coulomb_newton.coulomb_newton`): when that set is right, the next QP
reproduces its guesses and the loop stops. Where Newton's method fails or predicts normal
impulses more than ``NEWTON_MAX_GROWTH`` times the QP's (a wrong active set), the plain update
pbar_N <- p_N, theta_i <- angle of z_i is taken instead, with z_i = p_T,i - r_T,i / a_i (a_i the
mean of contact i's tangential diagonal of G + R: where its friction would go without a bound).
The plain update can cycle between two guesses; from iterate ``FP_RELAX_AFTER`` on, each new
guess is therefore averaged with the last one, pbar_N <- (pbar_N_last + pbar_N) / 2 (a
Krasnosel'skii-Mann step, which turns a 2-cycle into a contraction towards its midpoint), and
so are the friction directions (``mean_angle``). The natural residual of Coulomb's law::

    max_i max( |p_N,i - pbar_N,i|,  |p_T,i - P_{mu_i p_N,i}(z_i)| )        (P_r: onto the disk r)

is zero exactly when the bounds used the right normal impulses and every contact sticks
(z_i inside its disk: r_T = 0) or slides with friction mu p_N opposing its slip. The friction
is finally projected onto the circle of its own p_N, so ||p_T|| <= mu p_N holds on every step
exactly. If ``max_iter`` iterates do not reach the tolerance, the last iterate, projected the
same way, is the answer (a continuous function of the step's input that keeps friction), and
the step's record says so. How often each case occurs: docs/results.md, "Friction fixed point".
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from .coulomb_newton import RELEASED, coulomb_newton, coulomb_split, hessian
from .qp import solve_box_qp

FP_TOL = 1e-6  # natural residual of Coulomb's law, relative to max p_N
FP_MAX = 50  # friction fixed-point iterates per step
FP_RELAX_AFTER = 10  # from this iterate on, each new guess (pbar_N, theta) is averaged with the last one
NEWTON_MAX_GROWTH = 3.0  # a Newton guess may at most triple the sum of the normal impulses


class LeastAction(NamedTuple):
    """The least-action problem of one step (module docstring); rows: 3m contact rows, then the servo rows."""

    H: np.ndarray  # (n, n) G + R with every compliance that does not depend on pbar_N
    c: np.ndarray  # (n,) J qd_free + b
    mu: np.ndarray  # (m,) friction coefficient per contact
    lo: np.ndarray  # (n - 3m,) lower bounds of the servo rows
    hi: np.ndarray  # (n - 3m,) upper bounds of the servo rows
    stiction_velocity: float  # v_s of the smooth stick-slip friction (0: none, the rigid law)

    @property
    def m(self) -> int:
        return len(self.mu)


class LeastActionInfo(NamedTuple):
    """How the least-action problem of one step was solved."""

    converged: bool  # the friction fixed point reached FP_TOL
    iterations: int  # fixed-point iterates (one box QP each)
    qp_iterations: int  # OSQP's ADMM iterations, summed
    qp_solves: int  # OSQP solves (the fast wing certifies some iterates without OSQP)
    residual: float  # the natural residual of Coulomb's law at the end, relative to max p_N
    status: str  # OSQP's status of the last iterate


def delassus(J: np.ndarray, M: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(G, M^-1 J^T): the Delassus matrix G = J M^-1 J^T of the rows J over the coordinates of M.

    Implements: [COBRA] eq. (5), G = J_c M^-1 J_c^T, the inverse inertia the rows see.
    """
    Minv_JT = np.linalg.solve(M, J.T)
    G = J @ Minv_JT
    return 0.5 * (G + G.T), Minv_JT


def solve_least_action(problem: LeastAction, x_start=None, solve_qp=solve_box_qp, max_iter: int = FP_MAX,
                       tol: float = FP_TOL) -> tuple[np.ndarray, LeastActionInfo]:
    """The impulses x of [COBRA] eq. (6) with Coulomb's circle, and how they were found.

    Implements: [COBRA] eq. (6), its friction by the fixed point of the module docstring.
    ``x_start``: where the loop starts (the previous step's impulses; default zero);
    ``solve_qp(H, c, lo, hi, x0) -> BoxQPSolution``: the box-QP solver of each iterate (OSQP).
    """
    n = len(problem.c)
    if n == 0:  # no contact and no servo row: nothing to solve
        return np.zeros(0), LeastActionInfo(True, 0, 0, 0, 0.0, "solved")
    x = np.zeros(n) if x_start is None else np.asarray(x_start, dtype=float)
    return fixed_point(problem, FixedPoint(1, *guess(problem, x), 0, 0), solve_qp, max_iter, tol)


class FixedPoint(NamedTuple):
    """Where the friction loop of ``solve_least_action`` stands: iterate k is next, with the guess
    (pbar_N, theta) from x, and the OSQP iterations and solves so far."""

    k: int
    pbar_N: np.ndarray
    theta: np.ndarray
    x: np.ndarray
    qp_iterations: int
    qp_solves: int


def fixed_point(problem: LeastAction, start: FixedPoint, solve_qp, max_iter: int = FP_MAX,
                tol: float = FP_TOL) -> tuple[np.ndarray, LeastActionInfo]:
    """``solve_least_action``'s loop from ``start`` (module docstring): iterates until the natural
    residual is below ``tol`` or iterate ``max_iter`` is done."""
    k, pbar_N, theta, x, qp_iterations, qp_solves = start
    floor = impulse_floor(problem)
    for k in range(start.k, max_iter + 1):
        x, sol, residual = fixed_point_iterate(problem, pbar_N, theta, x, solve_qp, floor)
        qp_iterations, qp_solves = qp_iterations + sol.iterations, qp_solves + sol.solves
        # stop when the guesses are the ones this solution implies
        if residual <= tol:
            break
        pbar_N, theta, x = next_guess(problem, x, pbar_N, theta, k)
    return project_friction(x, problem.mu), LeastActionInfo(residual <= tol, k, qp_iterations, qp_solves,
                                                            residual, sol.status)


def fixed_point_iterate(problem: LeastAction, pbar_N, theta, x, solve_qp, floor: float):
    """(x, the QP's solution, the natural residual): one iterate of the friction loop, the box QP
    with the friction bound mu pbar_N in tangent frames turned by theta, solved from x."""
    m = problem.m
    H = hessian(problem, pbar_N)
    lo, hi = bounds(problem, pbar_N)
    sol = solve_qp(turn_tangents(H, theta, m), turn(problem.c, theta, m), lo, hi, turn(x, theta, m))
    x = turn(sol.x, -theta, m)
    p_N, p_T, z = coulomb_split(x, H @ x + problem.c, H, m)
    return x, sol, natural_residual(p_N, p_T, z, pbar_N, problem.mu, floor)


def next_guess(problem: LeastAction, x, pbar_N, theta, k: int):
    """The guess (pbar_N, theta, x) after iterate k left the impulses x, solved with (pbar_N, theta)."""
    last, last_theta = pbar_N, theta
    pbar_N, theta, x = guess(problem, x, theta)
    # a loop that has not converged by now cycles (the plain update can alternate between two
    # guesses): average the guess with the last one (Krasnosel'skii-Mann), the normal impulses
    # pbar_N <- (pbar_N_last + pbar_N) / 2 and each friction direction e(theta) <- the
    # direction of e(theta_last) + e(theta) (kept as it is where the two are opposite)
    if k >= FP_RELAX_AFTER:
        pbar_N = 0.5 * (last + pbar_N)
        theta = mean_angle(last_theta, theta)
    return pbar_N, theta, x


def mean_angle(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The direction of e(a) + e(b), e(t) = (cos t, sin t), elementwise; b where e(a) = -e(b).

    The averaged friction directions of the fixed point's relaxed update.
    """
    s, c = np.sin(a) + np.sin(b), np.cos(a) + np.cos(b)
    return np.where(np.hypot(s, c) > 1e-12, np.arctan2(s, c), b)


def turn(v: np.ndarray, theta: np.ndarray, m: int) -> np.ndarray:
    """v' = Q^T v: each contact's tangential pair (v_t1, v_t2) in the frame turned by theta_i.

    Q is block diagonal, a rotation by theta_i on contact i's tangent rows and the
    identity elsewhere; ``turn(v', -theta, m)`` = Q v' turns back. v: a vector, or a matrix
    turned row by row.
    """
    out = v.copy()
    shape = (m,) + (1,) * (v.ndim - 1)
    c, s = np.cos(theta).reshape(shape), np.sin(theta).reshape(shape)
    t1, t2 = v[1:3 * m:3], v[2:3 * m:3]
    out[1:3 * m:3], out[2:3 * m:3] = c * t1 + s * t2, -s * t1 + c * t2
    return out


def turn_tangents(H: np.ndarray, theta: np.ndarray, m: int) -> np.ndarray:
    """Q^T H Q for the rotation Q of ``turn``: rows, then columns turned.

    The Hessian of the least-action problem in the turned tangent frames.
    """
    return turn(turn(H, theta, m).T, theta, m).T


def bounds(problem: LeastAction, pbar_N: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lo, hi) of one iterate: p_N >= 0, |p_t1'|, |p_t2'| <= mu pbar_N, the servo rows' bounds.

    The box of the module docstring's aligned square.
    """
    m, radius = problem.m, problem.mu * pbar_N
    lo, hi = np.zeros(len(problem.c)), np.full(len(problem.c), np.inf)
    lo[1:3 * m:3] = lo[2:3 * m:3] = -radius
    hi[1:3 * m:3] = hi[2:3 * m:3] = radius
    lo[3 * m:], hi[3 * m:] = problem.lo, problem.hi
    return lo, hi


def project_disk(v: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Rows of v (k, 2) projected onto the disks of radii r (k,): v min(1, r / |v|).

    Coulomb's friction set F_i of [COBRA] eq. (2) in the tangent plane.
    """
    norm = np.hypot(v[:, 0], v[:, 1])
    scale = np.where(norm > r, r / np.where(norm > 0, norm, 1.0), 1.0)
    return v * scale[:, None]


def natural_residual(p_N, p_T, z, pbar_N, mu, floor: float = 0.0) -> float:
    """max_i max(|p_N,i - pbar_N,i|, |p_T,i - P_{mu_i p_N,i}(z_i)|) / max(max p_N, floor) (module docstring).

    Implements: the natural-map residual of the Coulomb friction problem: zero exactly at a
    solution of eq. (6) with F_i = {||p_T|| <= mu p_N}. ``floor`` [N s]: the scale below which
    an impulse is nothing (``impulse_floor``), so that a step whose candidate contacts all hover
    is measured against it rather than against its own rounding.
    """
    if len(p_N) == 0:
        return 0.0
    scale = max(float(p_N.max()), floor, 1e-300)
    normal = np.abs(p_N - pbar_N).max()
    friction = np.hypot(*(p_T - project_disk(z, mu * np.maximum(p_N, 0.0))).T).max()
    return float(max(normal, friction) / scale)


def impulse_floor(problem: LeastAction) -> float:
    """RELEASED max_i |c_N,i| / H_NN,i [N s]: a billionth of the largest impulse that would stop a
    contact's normal velocity at its own effective mass.

    The floor of ``natural_residual``. Where every candidate contact hovers, the QPs' normal
    impulses are rounding (1e-25 N s) and their residual relative to max p_N is rounding over
    rounding, of order one, however exact the answer (no impulse) is; measured against this floor
    such a step converges at its first iterate. Where contacts carry load, max p_N is far above it.
    """
    m = problem.m
    if m == 0:
        return 0.0
    c_N, H_NN = problem.c[0:3 * m:3], problem.H.diagonal()[0:3 * m:3]
    return RELEASED * float(np.max(np.abs(c_N) / H_NN))


def project_friction(x: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """x with each contact's p_N clipped at 0 and p_T projected onto its circle ||p_T|| <= mu p_N.

    The last operation on every step's impulses (module docstring). Normal impulses
    below ``RELEASED`` max p_N (a solver's rounding on a contact that carries nothing) are 0.
    """
    m = len(mu)
    x = x.copy()
    p = x[:3 * m].reshape(m, 3)
    p[:, 0] = np.where(p[:, 0] > RELEASED * p[:, 0].max(initial=0.0), p[:, 0], 0.0)
    p[:, 1:] = project_disk(p[:, 1:], mu * p[:, 0])
    return x


def guess(problem: LeastAction, x: np.ndarray, theta=None):
    """The next (pbar_N, theta) and where the next QP starts: Newton's guess on the active set of x,
    else the plain update from x.

    The update of the friction fixed point (module docstring). ``theta``: the angles x
    was solved with, kept for sticking contacts by the plain update.
    """
    return chosen_guess(problem, x, coulomb_newton(problem, x), theta)


def chosen_guess(problem: LeastAction, x: np.ndarray, newton, theta=None):
    """``guess`` given Newton's answer ``newton`` from x (``coulomb_newton``, or None): that answer
    unless it failed or grows the normal impulses more than ``NEWTON_MAX_GROWTH`` times, else the
    plain update from x."""
    m = problem.m
    p_N = np.maximum(x[0:3 * m:3], 0.0)
    if newton is not None and (p_N.sum() <= 0.0 or newton[0].sum() <= NEWTON_MAX_GROWTH * p_N.sum()):
        return newton
    H = hessian(problem, p_N)
    _, p_T, z = coulomb_split(x, H @ x + problem.c, H, m)
    theta = np.arctan2(p_T[:, 1], p_T[:, 0]) if theta is None else theta
    sliding = np.hypot(*z.T) > problem.mu * p_N
    return p_N, np.where(sliding, np.arctan2(z[:, 1], z[:, 0]), theta), x


def kkt_residuals(problem: LeastAction, x: np.ndarray) -> dict:
    """How well impulses x meet eq. (2) (the KKT conditions of eq. (6)), each a max over contacts.

    Implements: the velocity-level conditions of [COBRA] eq. (2) for the compliant or rigid law:

    * ``complementarity`` max_i |p_N,i r_N,i| [N s m/s] with r = (G + R) x + c the law's
      residual (zero in contact, >= 0 when separating);
    * ``cone_residual`` max_i (||p_T,i|| - mu_i p_N,i)_+ / max p_N: friction outside Coulomb's circle;
    * ``coulomb_residual``: the natural residual of Coulomb's law (``natural_residual`` with
      pbar_N = p_N), relative to max p_N: stick without slip, or slip against mu p_N.
    """
    m = problem.m
    if m == 0:
        return {"complementarity": 0.0, "cone_residual": 0.0, "coulomb_residual": 0.0}
    p_N = np.maximum(x[0:3 * m:3], 0.0)
    H = hessian(problem, p_N)
    r = H @ x + problem.c
    _, p_T, z = coulomb_split(x, r, H, m)
    scale = max(float(p_N.max()), 1e-300)
    cone = np.maximum(np.hypot(*p_T.T) - problem.mu * p_N, 0.0).max() / scale
    return {"complementarity": float(np.abs(p_N * r[0:3 * m:3]).max()), "cone_residual": float(cone),
            "coulomb_residual": natural_residual(p_N, p_T, z, p_N, problem.mu, impulse_floor(problem))}
