# %% [markdown]
# # 01 - Spatial algebra on a toy
# **Goal:** learn the 6-D vectors that every dynamics algorithm in `cobra_ref` is written
# in: motion and force vectors, their cross products, coordinate transforms and the
# spatial inertia. We use a turntable and a small rod, no robot yet.
# **Paper:** [COBRA] eq. (1) is assembled from these pieces in tutorial 02; the algebra is
# [RBDA] ch. 2 (Featherstone 2008): sec. 2.8 coordinate transforms, sec. 2.9 spatial cross
# products, sec. 2.13 spatial inertia.
# **Run:** `python tutorials/01_spatial_algebra.py`

# %%
import numpy as np

from cobra_ref.spatial import crf, crm, force_X, inv_X, mcI, plux, rotz, skew, xlt

np.set_printoptions(precision=4, suppress=True)
rng = np.random.default_rng(0)

# %% [markdown]
# ## 1. Motion and force vectors are angular-first
# A **motion vector** (spatial velocity) in a frame with origin O is `m = [w; v_O]`:
# the angular velocity `w`, then the velocity `v_O` of the body point that is at O right
# now (not the velocity of the centre of mass). Any body point p then moves with
# `v_p = v_O + w x p`.
#
# Toy: a turntable spins at 2 rad/s about a vertical axis through P = (1, 0, 0).
# Seen from O, the body point at O circles P, so `v_O = w x (O - P) = (0, -2, 0)`.

# %%
w = np.array([0.0, 0.0, 2.0])                   # rad/s
P = np.array([1.0, 0.0, 0.0])                   # m, a point on the spin axis
v_O = np.cross(w, -P)                           # velocity of the body point at O
m_A = np.concatenate([w, v_O])                  # motion vector [w; v_O] in frame A
v_P = v_O + np.cross(w, P)                      # points on the axis do not move
print("motion vector m_A = [w; v_O]:", m_A)
print("velocity of the axis point P:", v_P, "m/s")

# %% [markdown]
# A **force vector** is `f = [n; F]`: the moment `n` about the origin O, then the force `F`.
# A force F applied at a point Q has moment `n = Q x F` about O.
# The power delivered is the scalar product of a motion and a force vector,
# `m . f = w . n + v_O . F`. We check it against the 3-D rule "power = force . velocity of
# the point where the force acts".

# %%
Q = np.array([2.0, 0.0, 0.0])                   # m, where we push
F = np.array([0.0, 3.0, 0.0])                   # N
f_A = np.concatenate([np.cross(Q, F), F])       # force vector [n; F] in frame A
v_Q = v_O + np.cross(w, Q)                      # velocity of the pushed point
power_spatial = m_A @ f_A
power_3d = F @ v_Q
print("force vector f_A = [n; F]:", f_A)
print(f"power m.f = {power_spatial:.4f} W,  F.v_Q = {power_3d:.4f} W")

# %% [markdown]
# ## 2. `skew`: the 3-D cross product as a matrix
# `skew(w) @ u = w x u` ([RBDA] eq. 2.23). The matrix is antisymmetric: `skew(w).T = -skew(w)`.

# %%
u = rng.normal(size=3)
print("skew(w) =\n", skew(w))
print("skew(w) @ u :", skew(w) @ u)
print("np.cross(w,u):", np.cross(w, u))
print("skew(w) + skew(w).T is zero:", np.allclose(skew(w) + skew(w).T, 0.0))

# %% [markdown]
# ## 3. Spatial cross products `crm` and `crf` ([RBDA] sec. 2.9)
# `crm(v) @ m = v x m` is the rate of change of a motion vector m that is carried along
# with a body moving at velocity v. `crf(v) @ f = v x* f` is the same for a force vector.
# They are tied by **crf(v) = -crm(v).T**, so that carrying both m and f along leaves their
# power unchanged: `(v x m) . f + m . (v x* f) = 0`.

# %%
v, m, f = rng.normal(size=(3, 6))
print("crm(v) =\n", crm(v))
print("crf(v) + crm(v).T is zero:", np.allclose(crf(v) + crm(v).T, 0.0))
print("v x v (a motion does not change itself):", crm(v) @ v)
power_rate = (crm(v) @ m) @ f + m @ (crf(v) @ f)
print(f"(v x m).f + m.(v x* f) = {power_rate:.2e}")

# %% [markdown]
# ## 4. Coordinate transforms `rotz`, `xlt`, `plux`
# `X_BA` maps motion vectors from A coordinates to B coordinates. Frame B has its origin at
# `r` (in A) and its axes rotated by theta about A's z axis. In [RBDA] sec. 2.8 (Table 2.2)
#
#     plux(E, r) = [ E            0 ]  = rotz(theta) @ xlt(r),    E = rotz(theta)[:3, :3]
#                  [ -E skew(r)   E ]
#
# where `E` rotates A coordinates into B coordinates. Put B on the turntable axis: there
# the body point at B's origin is at rest, so the linear part of `m_B` must be zero.

# %%
theta = np.pi / 2
E = np.array([[np.cos(theta), np.sin(theta), 0.0],
              [-np.sin(theta), np.cos(theta), 0.0],
              [0.0, 0.0, 1.0]])                 # A -> B coordinates (B turned +theta about z)
X_BA = plux(E, P)
print("rotz(theta)[:3,:3] equals E:", np.allclose(rotz(theta)[:3, :3], E))
print("plux(E, P) equals rotz(theta) @ xlt(P):", np.allclose(X_BA, rotz(theta) @ xlt(P)))
m_B = X_BA @ m_A
print("m_B = X_BA m_A:", m_B, " (zero linear part: B sits on the spin axis)")

# %% [markdown]
# ## 5. Inverse transform `inv_X`
# Going back from B to A needs `X_AB = X_BA^-1 = plux(E^T, -E r)` ([RBDA] sec. 2.8).
# `inv_X` builds it from the blocks, without a numerical matrix inverse.

# %%
X_AB = inv_X(X_BA)
print("inv_X(X_BA) equals np.linalg.inv(X_BA):", np.allclose(X_AB, np.linalg.inv(X_BA)))
print("X_AB @ m_B gives back m_A:", X_AB @ m_B)

# %% [markdown]
# ## 6. Force transforms: X* = X^-T keeps the power pairing
# Force vectors change coordinates with `X* = X^-T` (`force_X`, [RBDA] sec. 2.8). This is the
# only choice for which the power does not depend on the frame it is computed in:
#
#     (X m) . (X* f) = m^T X^T X^-T f = m . f
#
# By hand for the push at Q: about B's origin P the moment is (Q - P) x F = (0, 0, 3) N m,
# and in B's axes the force (0, 3, 0) N reads E F = (3, 0, 0) N.

# %%
X_BA_star = force_X(X_BA)
f_B = X_BA_star @ f_A
f_B_hand = np.concatenate([E @ np.cross(Q - P, F), E @ F])
print("X* equals inv(X).T:", np.allclose(X_BA_star, np.linalg.inv(X_BA).T))
print("f_B = X* f_A:", f_B, "  by hand:", f_B_hand)
print(f"power in A: {m_A @ f_A:.4f} W,  power in B: {m_B @ f_B:.4f} W")

# %% [markdown]
# ## 7. Spatial inertia of a small rod: `mcI(m, c, Ic)`
# A rod of mass 0.5 kg, length 0.2 m and radius 0.01 m lies along +x with frame A at one
# end, so its centre of mass is c = (L/2, 0, 0). About the centre of mass, a solid cylinder
# has Ic = diag(m r^2 / 2, m (3 r^2 + L^2) / 12, m (3 r^2 + L^2) / 12). [RBDA] sec. 2.13:
#
#     I = [ Ic + m skew(c) skew(c)^T   m skew(c) ]
#         [ m skew(c)^T                m 1       ]
#
# The top-left block is the parallel-axis theorem: I_yy about the end = Ic_yy + m (L/2)^2.

# %%
mass, L, r_rod = 0.5, 0.2, 0.01                  # kg, m, m
c = np.array([L / 2, 0.0, 0.0])                  # centre of mass in frame A, m
Ic = np.diag([mass * r_rod**2 / 2] + [mass * (3 * r_rod**2 + L**2) / 12] * 2)   # kg m^2
I_A = mcI(mass, c, Ic)
print("I_A (frame at the rod's end) =\n", I_A)
print(f"I_xx (spin about the rod's own axis): {I_A[0, 0]:.2e} kg m^2, tiny for a thin rod")
print(f"I_yy about the end: {I_A[1, 1]:.6f},  parallel axis: {Ic[1, 1] + mass * (L / 2)**2:.6f} kg m^2")
print("symmetric:", np.allclose(I_A, I_A.T), " eigenvalues > 0:", np.all(np.linalg.eigvalsh(I_A) > 0))

# %% [markdown]
# ## 8. Kinetic energy from the spatial inertia
# For a spatial velocity `v_A = [w; v_O]` the kinetic energy is `T = 1/2 v^T I v`
# ([RBDA] sec. 2.13). By hand (Koenig's theorem) it is the translational energy of the centre
# of mass plus the rotational energy about it: `T = 1/2 m |v_com|^2 + 1/2 w^T Ic w`, with
# `v_com = v_O + w x c`.

# %%
v_A = rng.normal(size=6)                         # [w; v_O] of the rod, rad/s and m/s
w_rod, v_O_rod = v_A[:3], v_A[3:]
v_com = v_O_rod + np.cross(w_rod, c)
T_spatial = 0.5 * v_A @ I_A @ v_A
T_hand = 0.5 * mass * v_com @ v_com + 0.5 * w_rod @ Ic @ w_rod
print(f"1/2 v^T I v                 = {T_spatial:.6f} J")
print(f"1/2 m|v_com|^2 + 1/2 w.Ic w = {T_hand:.6f} J")

# %% [markdown]
# ## 9. One rigid body seen from two frames
# Frame C sits at the rod's centre of mass, its axes turned by 30 degrees about z. The same
# rigid-body motion in C coordinates is `v_C = X_CA v_A`. By hand: the angular part is `E w`,
# and the linear part is the velocity of the body point at C's origin (the centre of mass),
# in C's axes: `E v_com`. Inertias transform as `I_C = X* I_A X^-1` ([RBDA] sec. 2.13); at
# the centre of mass this must be block diagonal, `mcI(m, 0, E Ic E^T)`.

# %%
E_30 = rotz(np.pi / 6)[:3, :3]
X_CA = plux(E_30, c)                             # A -> centre-of-mass frame C
v_C = X_CA @ v_A
v_C_hand = np.concatenate([E_30 @ w_rod, E_30 @ v_com])
I_C = force_X(X_CA) @ I_A @ inv_X(X_CA)
print("v_C = X_CA v_A:", v_C)
print("by hand      :", v_C_hand)
print("I_C is mcI(m, 0, E Ic E^T):", np.allclose(I_C, mcI(mass, np.zeros(3), E_30 @ Ic @ E_30.T)))
print(f"kinetic energy in A: {T_spatial:.6f} J,  in C: {0.5 * v_C @ I_C @ v_C:.6f} J")

# %% [markdown]
# ## 10. What we just verified
# Motion and force vectors, cross products and transforms (sections 1-6):

# %%
np.testing.assert_allclose(v_P, 0.0, atol=1e-12, err_msg="points on the spin axis are at rest")
np.testing.assert_allclose(power_spatial, power_3d, atol=1e-12, err_msg="m.f = F.v_Q")
np.testing.assert_allclose(skew(w) @ u, np.cross(w, u), atol=1e-12)
np.testing.assert_allclose(crf(v), -crm(v).T, atol=0.0, err_msg="crf(v) = -crm(v)^T")
np.testing.assert_allclose(power_rate, 0.0, atol=1e-12)
np.testing.assert_allclose(plux(E, P), rotz(theta) @ xlt(P), atol=1e-12)
np.testing.assert_allclose(m_B, [0, 0, 2, 0, 0, 0], atol=1e-12, err_msg="B on the spin axis")
np.testing.assert_allclose(inv_X(X_BA) @ X_BA, np.eye(6), atol=1e-12)
np.testing.assert_allclose(f_B, f_B_hand, atol=1e-12)
np.testing.assert_allclose(m_B @ f_B, m_A @ f_A, atol=1e-12, err_msg="(X m).(X* f) = m.f")
np.testing.assert_allclose((X_BA @ m) @ (force_X(X_BA) @ f), m @ f, atol=1e-12)

# %% [markdown]
# The rod's spatial inertia, kinetic energy and change of frame (sections 7-9):

# %%
np.testing.assert_allclose(I_A[1, 1], Ic[1, 1] + mass * (L / 2) ** 2, rtol=1e-12)
np.testing.assert_allclose(T_spatial, T_hand, rtol=1e-12, err_msg="1/2 v^T I v = Koenig")
np.testing.assert_allclose(v_C, v_C_hand, atol=1e-12)
np.testing.assert_allclose(I_C, mcI(mass, np.zeros(3), E_30 @ Ic @ E_30.T), atol=1e-12)
np.testing.assert_allclose(0.5 * v_C @ I_C @ v_C, T_spatial, rtol=1e-12)
print("All spatial-algebra checks passed.")
