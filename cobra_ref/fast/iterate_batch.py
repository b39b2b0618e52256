"""The friction loop of K members at once: its first guess and its first iterate's vector work, batched.

For performance: ``solve_all(problems, starts, qps)`` is ``[least_action.solve_least_action(p, x,
qp) for ...]``, bit for bit, for the members of a batched step (:mod:`cobra_ref.fast.batch`), each
with its own ``FastBoxQP``, whose first QP of the step is solved here (``new_step`` need not be
called); the friction loop mostly ends at its first iterate. Batched, for all members in one NumPy
call each (per-member maxima as segment maxima, ``members.segment_max``):

* the first guess (:func:`cobra_ref.fast.newton_batch.first_guesses`);
* the first iterate's vector work: the box's bounds, the tangent frames' turns of c and x, the
  QP's start and OSQP's warm duals, the certified solve's held set, its active-set rounds and
  its certificate (:mod:`cobra_ref.fast.box_batch`), the natural residual and the friction's
  projection.

Each member's own: its Hessian and the turned copy the QP reads, OSQP's loose solve on its own
``FastBoxQP`` (whose OSQP instances it keeps warm), the Cholesky solves on its held sets, the
matrix-vector products. A member whose box QP the full rounds leave uncertified goes on with
``FastBoxQP.certified``, one whose loop needs more iterates with ``least_action.fixed_point``
from its second; an exception of a member's own part takes that member's place in the answer.
Tested equal to ``solve_least_action`` member by member.
"""

from __future__ import annotations

import numpy as np

from ..coulomb_newton import RELEASED, hessian
from ..least_action import FP_TOL, FixedPoint, LeastActionInfo, fixed_point, next_guess, project_disk, turn_tangents
from ..qp import BoxQPSolution
from .box_batch import held, solve_boxes
from .least_action import GUESSES, BoxQP
from .members import MemberRows, Problems, segment_max
from .newton_batch import first_guesses


def solve_all(problems, starts, qps) -> list:
    """(x, info) of ``least_action.solve_least_action(problems[k], starts[k], qps[k])`` for every
    member k, or the exception its solve raised (module docstring); every problem has rows."""
    b = Problems(problems)
    guesses = first_guesses(problems, starts, b)
    R = b.rows
    pbar_N, theta, x = (np.concatenate(part) for part in zip(*guesses))
    R_T = b.stick_slip(b.mu * pbar_N)
    Hs = [hessian(p, None, R_T[R.contact_slice(k)]) for k, p in enumerate(problems)]
    lo, hi = _bounds(b, pbar_N)
    turned = [turn_tangents(H, guess[1], p.m) for H, guess, p in zip(Hs, guesses, problems)]
    solutions = _first_qps(b, turned, _turn(R, b.c, theta), lo, hi, _turn(R, x, theta), qps)
    ok = {k for k, sol in enumerate(solutions) if not isinstance(sol, Exception)}
    x = _turn(R, np.concatenate([solutions[k].x if k in ok else np.zeros(R.n[k]) for k in range(R.K)]), -theta)
    p_N, p_T, z = _split(b, x, b.products(Hs, x) + b.c, R_T)
    residual = _natural_residuals(b, p_N, p_T, z, pbar_N)
    projected = _projected(b, x)
    out = list(solutions)
    for k in sorted(ok):
        problem, sol, rows, contacts = problems[k], solutions[k], R.row_slice(k), R.contact_slice(k)
        if residual[k] <= FP_TOL:
            out[k] = projected[rows], LeastActionInfo(True, 1, sol.iterations, sol.solves, float(residual[k]),
                                                      sol.status)
            continue
        try:  # the single member's loop from its second iterate
            start = FixedPoint(2, *next_guess(problem, x[rows], pbar_N[contacts], theta[contacts], 1),
                               sol.iterations, sol.solves)
            out[k] = fixed_point(problem, start, qps[k])
        except Exception as exc:
            out[k] = exc
    return out


def _bounds(b: Problems, pbar_N: np.ndarray):
    """(lo, hi) of every member's first iterate: ``least_action.bounds``."""
    R, radius = b.rows, b.mu * pbar_N
    lo, hi = np.zeros(len(b.c)), np.full(len(b.c), np.inf)
    lo[R.T1] = lo[R.T2] = -radius
    hi[R.T1] = hi[R.T2] = radius
    lo[R.servo], hi[R.servo] = b.lo, b.hi
    return lo, hi


def _turn(R: MemberRows, v: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """``least_action.turn`` of every member's rows of v by its contacts' angles theta."""
    out = v.copy()
    c, s = np.cos(theta), np.sin(theta)
    t1, t2 = v[R.T1], v[R.T2]
    out[R.T1], out[R.T2] = c * t1 + s * t2, -s * t1 + c * t2
    return out


def _first_qps(b: Problems, Hs, c, lo, hi, x0, qps) -> list:
    """Each member's ``FastBoxQP.__call__(H, c, lo, hi, x0)`` as the first QP of its step: OSQP's
    loose solve, then the certified solve on the held set it guesses (or the member's own rest)."""
    R = b.rows
    x0 = np.clip(x0, lo, hi)
    at_lo, at_hi = held(R, x0, lo, hi)
    y0 = np.where(at_lo | at_hi, -(b.products(Hs, x0) + c), 0.0)
    starts, duals, counts, failed = [], [], [], {}
    for k, qp in enumerate(qps):
        rows = R.row_slice(k)
        qp.first = False
        try:
            res = qp._osqp(Hs[k], c[rows], lo[rows], hi[rows], x0[rows], y0[rows], loose=True)
        except Exception as exc:
            failed[k], res = exc, None
        guessed = res is not None and res.info.status in GUESSES
        starts.append(res.x if guessed else x0[rows])
        duals.append(res.y if guessed else None)
        counts.append((res.info.iter, 1) if res is not None else (0, 1))
    x0 = np.concatenate(starts)
    has_y = np.repeat([y is not None for y in duals], R.n)
    y = np.concatenate([np.zeros(R.n[k]) if d is None else d for k, d in enumerate(duals)])
    x, certified = solve_boxes(R, Hs, c, (lo, hi), held(R, x0, lo, hi, y, has_y))
    out = []
    for k, qp in enumerate(qps):
        rows = R.row_slice(k)
        if k in failed:
            out.append(failed[k])
            continue
        if certified[k]:
            out.append(BoxQPSolution(x[rows], np.zeros(R.n[k]), counts[k][0], "solved", counts[k][1]))
            continue
        try:
            out.append(qp.certified(BoxQP(Hs[k], c[rows], lo[rows], hi[rows]), starts[k], duals[k], counts[k]))
        except Exception as exc:
            out.append(exc)
    return out


def kkt_all(problems, xs) -> list:
    """``least_action.kkt_residuals(problems[k], xs[k])`` for every member k, batched as above."""
    b = Problems(problems)
    R = b.rows
    x = np.concatenate(xs)
    p_N = np.maximum(x[R.N], 0.0)
    R_T = b.stick_slip(b.mu * p_N)
    r = b.products([hessian(p, None, R_T[R.contact_slice(k)]) for k, p in enumerate(problems)], x) + b.c
    _, p_T, z = _split(b, x, r, R_T)
    scale = np.maximum(segment_max(p_N, R.of_contact, R.K), 1e-300)
    cone = segment_max(np.maximum(np.hypot(p_T[:, 0], p_T[:, 1]) - b.mu * p_N, 0.0), R.of_contact, R.K) / scale
    complementarity = segment_max(np.abs(p_N * r[R.N]), R.of_contact, R.K)
    coulomb = _natural_residuals(b, p_N, p_T, z, p_N)
    zero = {"complementarity": 0.0, "cone_residual": 0.0, "coulomb_residual": 0.0}
    return [{"complementarity": float(complementarity[k]), "cone_residual": float(cone[k]),
             "coulomb_residual": float(coulomb[k])} if R.m[k] else dict(zero) for k in range(R.K)]


def _split(b: Problems, x, r, R_T):
    """``coulomb_newton.coulomb_split`` of every member's impulses x with residual r, from its Hessian
    with the stick-slip compliance R_T: (p_N, p_T (m, 2), z (m, 2)) concatenated."""
    R = b.rows
    a = 0.5 * ((b.H_diagonal[R.T1] + R_T) + (b.H_diagonal[R.T2] + R_T))  # the tangential diagonal of H
    p_T = np.stack([x[R.T1], x[R.T2]], axis=1)
    return x[R.N], p_T, np.stack([p_T[:, 0] - r[R.T1] / a, p_T[:, 1] - r[R.T2] / a], axis=1)


def _natural_residuals(b: Problems, p_N, p_T, z, pbar_N) -> np.ndarray:
    """(K,) ``least_action.natural_residual`` of every member's impulses (p_N, p_T) and z
    (``_split``) against its guess pbar_N, over its impulse floor."""
    R = b.rows
    # least_action.impulse_floor
    floor = RELEASED * segment_max(np.abs(b.c[R.N]) / b.H_diagonal[R.N], R.of_contact, R.K)
    scale = np.maximum(np.maximum(segment_max(p_N, R.of_contact, R.K), floor), 1e-300)
    normal = segment_max(np.abs(p_N - pbar_N), R.of_contact, R.K)
    off = p_T - project_disk(z, b.mu * np.maximum(p_N, 0.0))
    friction = segment_max(np.hypot(off[:, 0], off[:, 1]), R.of_contact, R.K)
    return np.where(friction > normal, friction, normal) / scale  # max(normal, friction), as Python takes it


def _projected(b: Problems, x: np.ndarray) -> np.ndarray:
    """``least_action.project_friction`` of every member's impulses x."""
    R, x = b.rows, x.copy()
    p_N = x[R.N]
    p_N = np.where(p_N > RELEASED * segment_max(p_N, R.of_contact, R.K)[R.of_contact], p_N, 0.0)
    x[R.N] = p_N
    p_T = project_disk(np.stack([x[R.T1], x[R.T2]], axis=1), b.mu * p_N)
    x[R.T1], x[R.T2] = p_T[:, 0], p_T[:, 1]
    return x
