"""Faster path for chains: M, h and Jacobians in world coordinates with batched NumPy.

For performance: the readable recursions in :mod:`cobra_ref.dynamics` stay the
reference; ``tests/test_fastdyn.py`` checks that this module gives the same M, h, poses and
Jacobians to 1e-12 at random states. Use it for the time stepper, never as the definition.

Idea: for a forest of chains (every ``parent[i]`` is ``i - 1`` or ``-1``: COBRA and the box),
the RNEA recursions are cumulative sums when everything is written in world coordinates
(the world-coordinate form of the recursions, [RBDA] ch. 5)::

    V_i = sum_{j in anc(i)} S_j qd_j                       # spatial velocities (world)
    A_i = A_0 + sum_{j in anc(i)} (S_j qdd_j + c_j),  c_j = V_j x S_j qd_j  (revolute)
    F_i = sum_{j in desc(i)} (I_j A_j + V_j x* I_j V_j)    # subtree forces
    tau_k = S_k^T F_body(k),   M[k, l] = S_k^T Ic_body(l) S_l for k <= l in one chain

with S_k the world-coordinate motion subspace: a revolute joint about unit axis z through
point o has S = [z; o x z]; the free joint (qd = [v_world; w_body]) has
S = [[0, R], [1, o x R]] and c = [0; -w_world x v_world].
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..model import Model, ModelError
from ..quaternion import quat_to_rot, quat_to_rot_rows
from ..spatial import skew, skew_rows

_AXIS = {"Rx": 0, "Ry": 1, "Rz": 2}


class ChainTerms(NamedTuple):
    """World-frame dynamics terms of one configuration and velocity."""

    R: np.ndarray  # (nb, 3, 3) body orientations
    o: np.ndarray  # (nb, 3) body origins
    S: np.ndarray  # (6, nv) world motion subspace columns
    V: np.ndarray  # (nb, 6) body spatial velocities, world coordinates at the world origin
    M: np.ndarray  # (nv, nv) joint-space inertia
    h: np.ndarray  # (nv,) bias force C qd + g
    com: np.ndarray  # (nb, 3) body centres of mass, world


class ChainModel:
    """Precomputed index arrays of a chain-forest Model (built once, then constant)."""

    def __init__(self, model: Model):
        for i, parent in enumerate(model.parent):
            if parent not in (-1, i - 1):
                raise ModelError(f"fastdyn needs chains (parent[i] in {{i-1, -1}}); body {i} has parent {parent}")
        self.model = model
        nb, nv = model.nb, model.nv
        self.nb, self.nv = nb, nv  # Model computes these on each access
        self.root = np.array([i if model.parent[i] < 0 else -1 for i in range(nb)])
        for i in range(nb):
            if self.root[i] < 0:
                self.root[i] = self.root[i - 1]
        self.dof_body = np.concatenate([[i] * (s.stop - s.start) for i, s in enumerate(model.v_idx)]).astype(int)
        self.last_dof = np.array([s.stop - 1 for s in model.v_idx])
        # moves[b, k]: dof k moves body b (k in the range from b's chain root to b's own last dof)
        self.moves = np.zeros((nb, model.nv))
        for b in range(nb):
            self.moves[b, model.v_idx[self.root[b]].start:self.last_dof[b] + 1] = 1.0
        # same_chain[k, l]: dofs k and l belong to the same chain (else M[k, l] = 0)
        root_of_dof = self.root[self.dof_body]
        self.same_chain = root_of_dof[:, None] == root_of_dof[None, :]
        self.upper = np.triu(np.ones((nv, nv), dtype=bool))
        self.mass = np.array(model.mass)
        self.com = np.array(model.com)
        self.I_com = np.array(model.I_com)
        self.tree_pos = np.array(model.tree_pos)
        self.tree_rot = np.array(model.tree_rot)
        self.a_0 = np.concatenate([np.zeros(3), -model.gravity])
        self.rev_body = np.array([i for i, jt in enumerate(model.joint_type) if jt != "free"], dtype=int)
        self.rev_q = np.array([model.q_idx[i].start for i in self.rev_body], dtype=int)
        self.rev_v = np.array([model.v_idx[i].start for i in self.rev_body], dtype=int)
        rev_axis = np.array([_AXIS[model.joint_type[i]] for i in self.rev_body], dtype=int)
        self.rev_axis = rev_axis
        self.rev_j, self.rev_k = (rev_axis + 1) % 3, (rev_axis + 2) % 3
        # free joints: (body, first q index, first dof); their S columns [0, R; 1, o x R] keep
        # the identity block in a template
        self.free = [(i, model.q_idx[i].start, model.v_idx[i].start)
                     for i, jt in enumerate(model.joint_type) if jt == "free"]
        self.free_dofs = np.array([k for _, _, v in self.free for k in range(v, v + 6)], dtype=int)
        self.S_template = np.zeros((6, nv))
        for _, _, v in self.free:
            self.S_template[3:, v:v + 3] = np.eye(3)
        self.upper_same_chain = self.upper & self.same_chain
        # the chains' root bodies after the first (their sums restart there)
        self.chain_starts = [i for i in range(1, nb) if model.parent[i] < 0]
        self.tree_rot_cols = (self.tree_rot[self.rev_body, :, self.rev_j], self.tree_rot[self.rev_body, :, self.rev_k])
        self._precompute_indices()

    def _precompute_indices(self):
        """Constant index arrays and factors of ``terms``: the elements that fancy indexing would
        read, as slices and flat ``take`` indices (fewer NumPy calls per step, the same numbers)."""
        model, rev = self.model, self.rev_body
        # index arrays that are contiguous ranges become slices (views of the same elements)
        self._rev_q, self._rev_v = _index(self.rev_q), _index(self.rev_v)
        self._rev_body, self._rev_parent = _index(rev), _index(rev - 1)
        self.tree_rot_rev, self.tree_pos_rev = self.tree_rot[rev], self.tree_pos[rev]
        # R_rel's columns j and k, flat in (nrev, 3, 3), are c a + s b with a = [col_j, col_k] and
        # b = [col_k, -col_j] (c col_k + s (-col_j) is c col_k - s col_j, bit for bit)
        cols_j, cols_k = self.tree_rot_cols
        flat = np.arange(len(rev))[:, None] * 9 + np.arange(3) * 3
        self.rel_flat = np.hstack([flat + self.rev_j[:, None], flat + self.rev_k[:, None]])
        self.rel_a, self.rel_b = np.hstack([cols_j, cols_k]), np.hstack([cols_k, -cols_j])
        # the chain product: (body, first q index of a free joint or -1, row of R_rel or -1); a
        # revolute chain root has no parent rotation (terms raises ValueError, as it always has)
        self.pose_plan = [(i, model.q_idx[i].start, -1) if jt == "free" else (i, -1, int(np.flatnonzero(rev == i)[0]))
                          for i, jt in enumerate(model.joint_type)]
        self.revolute_root = any(model.parent[i] < 0 for i in rev)
        # the world joint axes z = R[rev, :, axis] flat in R (nb, 3, 3), and the components of o x z
        # (component r of a x b is a[P1] b[P2] - a[P2] b[P1]) flat in R and o (nb, 3)
        P1, P2 = np.array([1, 2, 0]), np.array([2, 0, 1])
        axis_flat = rev[:, None] * 9 + self.rev_axis[:, None]
        self.axis_flat = axis_flat + np.arange(3) * 3
        self.axis_flat_1, self.axis_flat_2 = axis_flat + P1 * 3, axis_flat + P2 * 3
        self.o_flat_1, self.o_flat_2 = rev[:, None] * 3 + P1, rev[:, None] * 3 + P2
        # free joints: bodies and q indices of their positions
        self.free_body = np.array([i for i, _, _ in self.free], dtype=int)
        self.free_pos = np.array([np.arange(start, start + 3) for _, start, _ in self.free], dtype=int).reshape(-1, 3)
        # the body of each revolute dof; each later chain's first dof; m 1 of the world inertias
        self.rev_dof_body = self.dof_body[self.rev_v]
        self.chain_start_dofs = [model.v_idx[i].start for i in self.chain_starts]
        self.m_eye = self.mass[:, None, None] * np.eye(3)

    def terms(self, q, qd) -> ChainTerms:
        """R, o, S, V, M and h at (q, qd): the same numbers as forward_kinematics, crba, bias_force.

        q (nq,) and qd (nv,); or a batch, (K, nq) and (K, nv), and every term gets a leading K
        axis: each member's terms are the ones of its own call, bit for bit (``tests/test_batch.py``).
        """
        nb, lead = self.nb, np.shape(q)[:-1]
        if self.revolute_root:
            raise ValueError("fastdyn needs a free joint at each chain root")
        R, o = self._poses(q)
        S, c = self._motion_subspace(R, o, qd)
        # V_i = cumulative sum of S_k qd_k within each chain, read at each body's last dof
        Sqd = np.swapaxes(S * qd[..., None, :], -1, -2)
        V = self._chain_cumsum(Sqd).take(self.last_dof, axis=-2)
        # c_k = V_body(k) x S_k qd_k for revolute dofs (zero for their own body: use V of the body);
        # the free joints' rows of c are already set
        c[..., self._rev_v, :] = _motion_cross(V.take(self.rev_dof_body, axis=-2), Sqd[..., self._rev_v, :])
        A = self.a_0 + self._chain_cumsum(c).take(self.last_dof, axis=-2)
        com = o + np.einsum("...bij,...bj->...bi", R, self.com)
        I_w = self._world_inertias(R, com)
        # f (nb, 6) and I_w (nb, 36) side by side: one subtree sum gives F and Ic
        fI = np.empty(lead + (nb, 42))
        np.add(np.einsum("...bij,...bj->...bi", I_w, A),
               _force_cross(V, np.einsum("...bij,...bj->...bi", I_w, V)), out=fI[..., :6])
        fI[..., 6:] = I_w.reshape(lead + (nb, 36))
        fI = self._subtree_sum(fI)
        F, Ic = fI[..., :6], fI[..., 6:].reshape(lead + (nb, 6, 6))
        h = np.einsum("...ki,...ki->...i", S, np.swapaxes(F.take(self.dof_body, axis=-2), -1, -2))
        IcS = np.einsum("...kij,...jk->...ik", Ic.take(self.dof_body, axis=-3), S)  # (6, nv): Ic_body(l) S_l
        # M[k, l] = S_k^T Ic_body(l) S_l for k <= l in one chain; the lower triangle by symmetry
        M = np.where(self.upper_same_chain, np.swapaxes(S, -1, -2) @ IcS, 0.0)
        M = M + np.swapaxes(M, -1, -2)
        M.reshape(lead + (-1,))[..., ::self.nv + 1] *= 0.5  # the diagonal (M is contiguous: a view)
        return ChainTerms(R, o, S, V, M, h, com)

    def _poses(self, q):
        """Body orientations and origins; joint rotations batched, the chain product in a loop."""
        lead = np.shape(q)[:-1]
        theta = q[..., self._rev_q]
        c, s = np.cos(theta)[..., None], np.sin(theta)[..., None]
        # R_rel = R_tree Rot_axis(theta): rotate columns j, k of R_tree in their plane
        R_rel = _copies(self.tree_rot_rev, lead)
        if lead:
            R_rel.reshape(lead + (-1,))[..., self.rel_flat] = c * self.rel_a + s * self.rel_b
        else:
            R_rel.put(self.rel_flat, c * self.rel_a + s * self.rel_b)
        R = np.empty(lead + (self.nb, 3, 3))
        for i, start, n in self.pose_plan:
            if n < 0:
                R[..., i, :, :] = quat_to_rot(q[start + 3:start + 7]) if not lead else quat_to_rot_rows(
                    q[..., start + 3:start + 7])
            elif not lead:
                # R_parent @ R_rel: np.dot makes the same BLAS call (dgemm) as matmul, with less overhead
                np.dot(R[i - 1], R_rel[n], out=R[i])
            else:
                np.matmul(R[..., i - 1, :, :], R_rel[..., n, :, :], out=R[..., i, :, :])
        # o_i = o_parent + R_parent tree_pos_i: a cumulative sum along each chain from its root
        # (free joint) position; the free joints' rows of tree_pos are replaced by those positions
        d = np.empty(lead + (self.nb, 3))
        d[..., self._rev_body, :] = np.einsum("...bij,...bj->...bi", R[..., self._rev_parent, :, :], self.tree_pos_rev)
        d[..., self.free_body, :] = q.take(self.free_pos, axis=-1)
        o = np.add.accumulate(d, axis=-2)  # np.cumsum
        for i in self.chain_starts:
            o[..., i:, :] -= o[..., i - 1:i, :]
        return R, o

    def _motion_subspace(self, R, o, qd):
        """World motion subspace S (6, nv), and c (nv, 6) with the free joints' velocity-product
        terms in their rows (the revolute rows are left for ``terms``); a batch leads with K."""
        lead = R.shape[:-3]
        S = _copies(self.S_template, lead)
        # revolute columns [z; o x z], read from R and o by flat index
        R_flat, o_flat = R.reshape(lead + (-1,)), o.reshape(lead + (-1,))
        S[..., :3, self._rev_v] = np.swapaxes(R_flat.take(self.axis_flat, axis=-1), -1, -2)
        S[..., 3:, self._rev_v] = np.swapaxes(o_flat.take(self.o_flat_1, axis=-1) * R_flat.take(self.axis_flat_2, axis=-1)
                                              - o_flat.take(self.o_flat_2, axis=-1) * R_flat.take(self.axis_flat_1, axis=-1),
                                              -1, -2)
        c = np.zeros(lead + (self.nv, 6))
        R_free = R.take(self.free_body, axis=-3)
        oxR = skew_rows(o.take(self.free_body, axis=-2)) @ R_free
        for n, (i, _, v) in enumerate(self.free):
            S[..., :3, v + 3:v + 6] = R_free[..., n, :, :]
            S[..., 3:, v + 3:v + 6] = oxR[..., n, :, :]
            # the free joint's velocity-product term in world coordinates: [0; -w_world x v_world]
            if not lead:
                w0, w1, w2 = np.dot(R_free[n], qd[v + 3:v + 6]).tolist()  # R w_body (dgemv, as matmul)
                u0, u1, u2 = qd[v:v + 3].tolist()
            else:
                w0, w1, w2 = np.matmul(R_free[..., n, :, :], qd[..., v + 3:v + 6, None])[..., 0].T
                u0, u1, u2 = qd[..., v:v + 3].T
            c[..., v + 5, 3], c[..., v + 5, 4], c[..., v + 5, 5] = w2 * u1 - w1 * u2, w0 * u2 - w2 * u0, w1 * u0 - w0 * u1
        return S, c

    def _chain_cumsum(self, x):
        """Cumulative sum over dofs (rows of x), restarting at each chain's first dof."""
        out = np.add.accumulate(x, axis=-2)  # np.cumsum
        for start in self.chain_start_dofs:
            out[..., start:, :] -= out[..., start - 1:start, :]
        return out

    def _subtree_sum(self, x):
        """Sum over each body's descendants (rows = bodies), chains in reverse order."""
        out = np.add.accumulate(x[..., ::-1, :], axis=-2)[..., ::-1, :]  # np.cumsum
        for i in self.chain_starts:
            out[..., :i, :] -= out[..., i:i + 1, :]
        return out

    def _world_inertias(self, R, c):
        """Spatial inertias in world coordinates at the origin, [[Ic + m C C^T, m C], [m C^T, m 1]]
        with C = [c]x for the world centres of mass c (nb, 3)."""
        Ic = R @ self.I_com @ np.swapaxes(R, -1, -2)
        C = skew_rows(c)
        mC = self.mass[:, None, None] * C
        I_w = np.empty(R.shape[:-2] + (6, 6))
        np.add(Ic, mC @ np.swapaxes(C, -1, -2), out=I_w[..., :3, :3])
        I_w[..., :3, 3:] = mC
        I_w[..., 3:, :3] = np.swapaxes(mC, -1, -2)
        I_w[..., 3:, 3:] = self.m_eye
        return I_w

    def point_jacobian(self, terms: ChainTerms, body: int, x: np.ndarray) -> np.ndarray:
        """(3, nv) world velocity of the body-fixed point currently at world position x.

        v(x) = v_O + w x x = [-[x]x, 1] V  for every ancestor column of S.
        """
        start = self.model.v_idx[self.root[body]].start
        stop = self.last_dof[body] + 1
        J = np.zeros((3, self.nv))
        J[:, start:stop] = terms.S[3:, start:stop] - skew(x) @ terms.S[:3, start:stop]
        return J


# the three cross products of a spatial cross product as columns of (n, 9) arrays: component r
# of a x b is a[P1] b[P2] - a[P2] b[P1], P1 = (1, 2, 0), P2 = (2, 0, 1); angular part 0:3,
# linear part 3:6. Columns of v (rows a1, a2) and of m or f (rows b1, b2) for the three products:
_MOTION_CROSS = (np.array([[1, 2, 0, 1, 2, 0, 4, 5, 3], [2, 0, 1, 2, 0, 1, 5, 3, 4]]),
                 np.array([[2, 0, 1, 5, 3, 4, 2, 0, 1], [1, 2, 0, 4, 5, 3, 1, 2, 0]]))
_FORCE_CROSS = (np.array([[1, 2, 0, 4, 5, 3, 1, 2, 0], [2, 0, 1, 5, 3, 4, 2, 0, 1]]),
                np.array([[2, 0, 1, 5, 3, 4, 5, 3, 4], [1, 2, 0, 4, 5, 3, 4, 5, 3]]))


def _cross_products(v, m, columns):
    """(..., n, 9): three row-wise 3-D cross products of parts of v and m (..., n, 6), columns as above."""
    a, b = columns  # (2, 9) each: a1 b1 in row 0, a2 b2 in row 1
    p = v.take(a, axis=-1) * m.take(b, axis=-1)
    return p[..., 0, :] - p[..., 1, :]


def _motion_cross(v, m):
    """Row-wise v x m for motion vectors ([RBDA] eq. 2.31), arrays (n, 6):
    [w x m_ang ; w x m_lin + v_O x m_ang] (a view of columns 0:6 of the three products)."""
    x = _cross_products(v, m, _MOTION_CROSS)
    np.add(x[..., 3:6], x[..., 6:], out=x[..., 3:6])
    return x[..., :6]


def _force_cross(v, f):
    """Row-wise v x* f for force vectors ([RBDA] eq. 2.32), arrays (n, 6):
    [w x f_ang + v_O x f_lin ; w x f_lin] (a view of columns 3:9 of the three products)."""
    x = _cross_products(v, f, _FORCE_CROSS)
    np.add(x[..., :3], x[..., 3:6], out=x[..., 3:6])
    return x[..., 3:]


def _copies(a: np.ndarray, lead: tuple) -> np.ndarray:
    """A new array of ``lead`` copies of a (a itself copied when ``lead`` is empty)."""
    return np.broadcast_to(a, lead + a.shape).copy() if lead else a.copy()


def _index(idx):
    """idx as a slice when it is a contiguous increasing range (the same elements, as a view)."""
    idx = np.asarray(idx, dtype=int)
    if len(idx) and np.array_equal(idx, np.arange(idx[0], idx[0] + len(idx))):
        return slice(int(idx[0]), int(idx[0]) + len(idx))
    return idx
