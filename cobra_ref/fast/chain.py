"""Faster path for chains: M, h and Jacobians in world coordinates with batched NumPy.

Helper (performance): the readable recursions in :mod:`cobra_ref.dynamics` stay the
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
from ..quaternion import quat_to_rot
from ..spatial import cross_rows, skew, skew_rows

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

    def terms(self, q, qd) -> ChainTerms:
        """R, o, S, V, M and h at (q, qd): the same numbers as forward_kinematics, crba, bias_force."""
        R, o = self._poses(q)
        S, c_free = self._motion_subspace(R, o, qd)
        # V_i = cumulative sum of S_k qd_k within each chain, read at each body's last dof
        Sqd = (S * qd).T
        V = self._chain_cumsum(Sqd)[self.last_dof]
        # c_k = V_body(k) x S_k qd_k for revolute dofs (zero for their own body: use V of the body)
        c = _motion_cross(V[self.dof_body], Sqd)
        c[self.free_dofs] = c_free
        A = self.a_0 + self._chain_cumsum(c)[self.last_dof]
        com = o + np.einsum("bij,bj->bi", R, self.com)
        I_w = self._world_inertias(R, com)
        f = np.einsum("bij,bj->bi", I_w, A) + _force_cross(V, np.einsum("bij,bj->bi", I_w, V))
        F = self._subtree_sum(f)
        h = np.einsum("ki,ki->i", S, F[self.dof_body].T)
        Ic = self._subtree_sum(I_w.reshape(len(I_w), 36)).reshape(-1, 6, 6)
        IcS = np.einsum("kij,jk->ik", Ic[self.dof_body], S)  # (6, nv): Ic_body(l) S_l
        # M[k, l] = S_k^T Ic_body(l) S_l for k <= l in one chain; the lower triangle by symmetry
        M = np.where(self.upper_same_chain, S.T @ IcS, 0.0)
        M = M + M.T
        M.flat[::len(M) + 1] *= 0.5
        return ChainTerms(R, o, S, V, M, h, com)

    def _poses(self, q):
        """Body orientations and origins; joint rotations batched, the chain product in a loop."""
        model = self.model
        theta = q[self.rev_q]
        c, s = np.cos(theta)[:, None], np.sin(theta)[:, None]
        # R_rel = R_tree Rot_axis(theta): rotate columns j, k of R_tree in their plane
        R_rel = self.tree_rot[self.rev_body].copy()
        cols_j, cols_k = self.tree_rot_cols
        rows = np.arange(len(theta))
        R_rel[rows, :, self.rev_j] = c * cols_j + s * cols_k
        R_rel[rows, :, self.rev_k] = c * cols_k - s * cols_j
        R, n = [None] * model.nb, 0
        for i, jt in enumerate(model.joint_type):
            if jt == "free":
                start = model.q_idx[i].start
                R[i] = quat_to_rot(q[start + 3:start + 7])
            else:
                R[i] = R[i - 1] @ R_rel[n]
                n += 1
        R = np.array(R)
        # o_i = o_parent + R_parent tree_pos_i: a cumulative sum along each chain from its root
        # (free joint) position; the free joints' rows of tree_pos are replaced by those positions
        steps = np.einsum("bij,bj->bi", R[self.rev_body - 1], self.tree_pos[self.rev_body])
        d = np.empty((model.nb, 3))
        d[self.rev_body] = steps
        for i, start, _ in self.free:
            d[i] = q[start:start + 3]
        o = np.cumsum(d, axis=0)
        for i in self.chain_starts:
            o[i:] -= o[i - 1]
        return R, o

    def _motion_subspace(self, R, o, qd):
        """World motion subspace S (6, nv) and the free joints' velocity-product terms (6k, 6)."""
        S = self.S_template.copy()
        axes = R[self.rev_body, :, self.rev_axis]
        S[:3, self.rev_v] = axes.T
        S[3:, self.rev_v] = cross_rows(o[self.rev_body], axes).T
        c = np.zeros((6 * len(self.free), 6))
        for n, (i, _, v) in enumerate(self.free):
            S[:3, v + 3:v + 6] = R[i]
            S[3:, v + 3:v + 6] = skew(o[i]) @ R[i]
            # the free joint's velocity-product term in world coordinates: [0; -w_world x v_world]
            w, u = R[i] @ qd[v + 3:v + 6], qd[v:v + 3]
            c[6 * n + 5, 3:] = (w[2] * u[1] - w[1] * u[2], w[0] * u[2] - w[2] * u[0], w[1] * u[0] - w[0] * u[1])
        return S, c

    def _chain_cumsum(self, x):
        """Cumulative sum over dofs (rows of x), restarting at each chain's first dof."""
        out = np.cumsum(x, axis=0)
        for i in self.chain_starts:
            start = self.model.v_idx[i].start
            out[start:] -= out[start - 1]
        return out

    def _subtree_sum(self, x):
        """Sum over each body's descendants (rows = bodies), chains in reverse order."""
        out = np.cumsum(x[::-1], axis=0)[::-1].copy()
        for i in self.chain_starts:
            out[:i] -= out[i]
        return out

    def _world_inertias(self, R, c):
        """Spatial inertias in world coordinates at the origin, [[Ic + m C C^T, m C], [m C^T, m 1]]
        with C = [c]x for the world centres of mass c (nb, 3)."""
        Ic = R @ self.I_com @ R.transpose(0, 2, 1)
        C = skew_rows(c)
        m = self.mass[:, None, None]
        mC = m * C
        I_w = np.empty((len(R), 6, 6))
        I_w[:, :3, :3] = Ic + mC @ C.transpose(0, 2, 1)
        I_w[:, :3, 3:] = mC
        I_w[:, 3:, :3] = mC.transpose(0, 2, 1)
        I_w[:, 3:, 3:] = m * np.eye(3)
        return I_w

    def point_jacobian(self, terms: ChainTerms, body: int, x: np.ndarray) -> np.ndarray:
        """(3, nv) world velocity of the body-fixed point currently at world position x.

        v(x) = v_O + w x x = [-[x]x, 1] V  for every ancestor column of S.
        """
        start = self.model.v_idx[self.root[body]].start
        stop = self.last_dof[body] + 1
        J = np.zeros((3, self.model.nv))
        J[:, start:stop] = terms.S[3:, start:stop] - skew(x) @ terms.S[:3, start:stop]
        return J


def _motion_cross(v, m):
    """Row-wise v x m for motion vectors ([RBDA] eq. 2.31), arrays (n, 6):
    [w x m_ang ; w x m_lin + v_O x m_ang], the three products in one batched call."""
    n = len(v)
    w, vo = v[:, :3], v[:, 3:]
    x = cross_rows(np.concatenate([w, w, vo]), np.concatenate([m[:, :3], m[:, 3:], m[:, :3]]))
    return np.concatenate([x[:n], x[n:2 * n] + x[2 * n:]], axis=1)


def _force_cross(v, f):
    """Row-wise v x* f for force vectors ([RBDA] eq. 2.32), arrays (n, 6):
    [w x f_ang + v_O x f_lin ; w x f_lin], the three products in one batched call."""
    n = len(v)
    w, vo = v[:, :3], v[:, 3:]
    x = cross_rows(np.concatenate([w, vo, w]), np.concatenate([f[:, :3], f[:, 3:], f[:, 3:]]))
    return np.concatenate([x[:n] + x[n:2 * n], x[2 * n:]], axis=1)
