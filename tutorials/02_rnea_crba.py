# %% [markdown]
# # 02 - Inverse dynamics (RNEA) and the mass matrix (CRBA)
# **Goal:** compute the two halves of the equation of motion, the bias force h and the mass
# matrix M, first on a 3-link chain and then on COBRA with the box, and check the identities
# that tie them together.
# **Paper:** [COBRA] eq. (1), written with the signs of [RBDA]:
# `M(q) qdd + h(q, qd) = tau + sum_i J_i^T f_i`. Algorithms: [RBDA] Table 5.1 (recursive
# Newton-Euler, RNEA) and Table 6.2 (composite rigid body algorithm, CRBA).
# **Run:** `python tutorials/02_rnea_crba.py`

# %%
import os
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import cobra_ref as cr

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)
np.set_printoptions(precision=4, suppress=True)
rng = np.random.default_rng(0)

# %% [markdown]
# ## 1. The toy: a 3-link chain with a fixed base
# Three uniform rods (mass 1 kg, length 0.3 m) joined by revolute joints Rz, Ry, Rz, the
# first joint fixed to the world at the origin. At q = 0 every link lies along the world's
# -x axis, and each body frame sits at the link's own joint, with its centre of mass
# half a link further along -x (the same layout as COBRA's links). Gravity is -9.81 m/s^2 in z.

# %%
m_link, L = 1.0, 0.3                              # kg, m
chain = cr.chain(3, link_length=L, link_mass=m_link)
print("joint types:", chain.joint_type, " nq =", chain.nq, " nv =", chain.nv)
print("joint positions in the parent frame [m]:", [p.tolist() for p in chain.tree_pos])
print("centres of mass in the body frames [m]:", [c.tolist() for c in chain.com])

# %% [markdown]
# ## 2. A gravity torque by hand
# `rnea(model, q, qd, qdd)` returns the joint torques `tau` that produce the acceleration
# `qdd` ([RBDA] Table 5.1; gravity enters as a fictitious upward base acceleration).
# With `qd = qdd = 0` it returns the torques that **hold the chain still** against gravity.
#
# Take q = (0, theta, 0): link 0 stays horizontal, joint 1 (about y, at x = -L) tilts links
# 1 and 2 together, and rotating -x by theta about y gives the link direction
# (-cos theta, 0, sin theta). Their centres of mass are L/2 and 3L/2 from joint 1 along it,
# so the horizontal lever arms are (L/2) cos theta and (3L/2) cos theta. Joint 1 must supply
#
#     tau_1 = m g (L/2 + 3L/2) cos theta = 2 m g L cos theta.
#
# For theta = -60 degrees (hanging 60 degrees below the horizontal), cos theta = 1/2 and
# tau_1 = m g L = 2.943 N m. Joints 0 and 2 need no torque: the weights produce moments
# about the horizontal world y axis, which is perpendicular to both of their axes.

# %%
theta = -np.pi / 3
q_hang = np.array([0.0, theta, 0.0])
zeros = np.zeros(chain.nv)
tau_hang = cr.rnea(chain, q_hang, zeros, zeros)
tau_1_hand = 2 * m_link * 9.81 * L * np.cos(theta)
print("rnea at rest:", tau_hang, "N m")
print(f"tau_1 by hand: 2 m g L cos(theta) = {tau_1_hand:.4f} N m")

# %% [markdown]
# ## 3. Inverse dynamics at a random state
# `random_state` draws joint angles within the limits and normally distributed velocities.
# The result is the full left-hand side of eq. (1), `tau = M qdd + h`.

# %%
q, qd = cr.random_state(chain, rng)
qdd = rng.normal(size=chain.nv)
tau = cr.rnea(chain, q, qd, qdd)
print("q   =", q, "rad")
print("qd  =", qd, "rad/s")
print("qdd =", qdd, "rad/s^2")
print("tau = rnea(q, qd, qdd) =", tau, "N m")

# %% [markdown]
# ## 4. The bias force h = rnea(q, qd, 0)
# Setting the acceleration to zero leaves `h(q, qd) = C(q, qd) qd + g(q)`: Coriolis and
# centrifugal terms plus gravity (`bias_force`, MuJoCo's `qfrc_bias`). With qd = 0 as well,
# only gravity `g(q)` remains.

# %%
h = cr.bias_force(chain, q, qd)
g_q = cr.rnea(chain, q, zeros, zeros)
print("h = bias_force(q, qd)  :", h)
print("rnea(q, qd, 0)         :", cr.rnea(chain, q, qd, zeros))
print("gravity part g(q)      :", g_q)
print("velocity part C(q,qd)qd:", h - g_q)

# %% [markdown]
# ## 5. The mass matrix M(q) from CRBA
# `crba(model, q)` ([RBDA] Table 6.2) sums each subtree's inertia into a composite inertia
# and projects it onto the joint axes. M depends on q only.

# %%
M = cr.crba(chain, q)
print("M(q) [kg m^2] =\n", M)

# %% [markdown]
# ## 6. Column k of M is inverse dynamics with a unit acceleration
# RNEA is affine in qdd, so `rnea(q, qd, e_k) - rnea(q, qd, 0) = M e_k = M[:, k]`
# (the simple method of [RBDA] ch. 6, also ModernRobotics' MassMatrix). This ties the two
# algorithms together: they are independent codes for the same equation of motion.

# %%
M_from_rnea = np.zeros_like(M)
for k in range(chain.nv):
    e_k = np.eye(chain.nv)[k]
    M_from_rnea[:, k] = cr.rnea(chain, q, qd, e_k) - h
print("M from n+1 RNEA calls =\n", M_from_rnea)
print("max |difference| to crba:", np.abs(M_from_rnea - M).max())

# %% [markdown]
# ## 7. The equation of motion and the properties of M
# Eq. (1) without contact: `M qdd + h = rnea(q, qd, qdd)`. M is symmetric and positive
# definite, because `1/2 qd^T M qd` is a kinetic energy, which is positive for any motion.

# %%
print("M qdd + h         :", M @ qdd + h)
print("rnea(q, qd, qdd)  :", tau)
print("symmetric:", np.allclose(M, M.T), " eigenvalues:", np.linalg.eigvalsh(M))
np.linalg.cholesky(M)                             # raises LinAlgError unless M is positive definite
print("Cholesky factorisation exists: M is positive definite")

# %% [markdown]
# ## 8. Kinetic energy two ways
# `1/2 qd^T M qd` must equal the sum over bodies of `1/2 v_i^T I_i v_i`, the spatial kinetic
# energy of tutorial 01 with each body's velocity v_i from forward kinematics.

# %%
T_M = 0.5 * qd @ M @ qd
T_bodies = cr.body_kinetic_energies(chain, q, qd)
print("per-body kinetic energies [J]:", T_bodies)
print(f"1/2 qd^T M qd = {T_M:.6f} J,  sum over bodies = {T_bodies.sum():.6f} J")

# %% [markdown]
# ## 9. Now the robot: COBRA and the box
# `cobra_model()` has 13 bodies: the head (free joint, the floating base), links L1..L10, the
# tail, and the box (a second free body). Coordinates follow MuJoCo:
#
#     q  (25) = [head x y z qw qx qy qz | theta_0 .. theta_10 | box x y z qw qx qy qz]
#     qd (23) = [head v_world, w_body | thetad_0 .. thetad_10 | box v_world, w_body]
#
# A free joint's velocity is the linear velocity of the body origin in **world** coordinates,
# then the angular velocity in **body** coordinates. So nq != nv and qd is not dq/dt.

# %%
cobra = cr.cobra_model()
q_c, qd_c = cr.random_state(cobra, rng)
qdd_c = rng.normal(size=cobra.nv)
print("bodies:", cobra.body_names)
print("nq =", cobra.nq, " nv =", cobra.nv)
print("head q :", q_c[:7], "\njoints :", q_c[7:18], "\nbox q  :", q_c[18:])

# %% [markdown]
# ## 10. The same identities on COBRA
# Nothing in RNEA or CRBA is specific to chains: the same code handles the floating base
# (the free joint's motion subspace S and its velocity-product term c_J, see `joints.py`).

# %%
M_c = cr.crba(cobra, q_c)
h_c = cr.bias_force(cobra, q_c, qd_c)
tau_c = cr.rnea(cobra, q_c, qd_c, qdd_c)
I_nv = np.eye(cobra.nv)
M_c_from_rnea = np.column_stack([cr.rnea(cobra, q_c, qd_c, I_nv[k]) - h_c for k in range(cobra.nv)])
print("M shape:", M_c.shape)
print("max |M qdd + h - rnea|           :", np.abs(M_c @ qdd_c + h_c - tau_c).max())
print("max |M[:, k] - (rnea(e_k) - h)|  :", np.abs(M_c_from_rnea - M_c).max())
print("smallest eigenvalue of M, symmetric:", np.linalg.eigvalsh(M_c).min(), np.allclose(M_c, M_c.T))

# %% [markdown]
# ## 11. Block structure: robot 17 + box 6
# The paper's M is 17 x 17 (6 head DoF + 11 joints). The box is not connected to the robot by
# any joint, so the full 23 x 23 matrix is block diagonal with zero coupling (contact will
# couple them later, through J^T f, not through M). Two blocks can be checked by hand:
#
# * box block: its frame is at its centre of mass and its linear velocity is in world
#   coordinates, so `M_box = diag(m_box, m_box, m_box, I_box, I_box, I_box)`;
# * head linear block: moving the head's origin with all joints locked translates the whole
#   snake, so `M[:3, :3] = (total robot mass) * 1`.

# %%
nv_robot = 17
M_robot = M_c[:nv_robot, :nv_robot]               # the paper's 17 x 17 M
M_box = M_c[nv_robot:, nv_robot:]
M_coupling = M_c[:nv_robot, nv_robot:]
params = cr.CobraParameters()
m_robot = sum(cobra.mass[:12])
M_box_hand = np.diag([params.box_mass] * 3 + [params.box_inertia] * 3)
print("robot block:", M_robot.shape, " box block:", M_box.shape, " coupling:", M_coupling.shape)
print("max |coupling|:", np.abs(M_coupling).max())
print("box block diagonal:", np.diag(M_box), " by hand:", np.diag(M_box_hand))
print(f"M[:3, :3] diagonal: {np.diag(M_c[:3, :3])},  total robot mass = {m_robot} kg")

# %% [markdown]
# ## 12. Gravity on COBRA at rest, by hand
# At rest only gravity is left in h. The rows of a free joint's linear velocity hold the
# total weight hanging below it: `h[0:3] = (0, 0, m_robot g)` for the head (whatever the
# joint angles) and `h[17:20] = (0, 0, m_box g)` for the box. The box's centre of mass is
# its origin, so gravity exerts no moment on it: `h[20:23] = 0`.

# %%
h_rest = cr.bias_force(cobra, q_c, np.zeros(cobra.nv))
print("head linear rows [N]:", h_rest[:3], " m_robot g =", m_robot * 9.81)
print("box rows [N, N m]   :", h_rest[17:], " m_box g =", params.box_mass * 9.81)

# %% [markdown]
# ## 13. Kinetic energy on COBRA

# %%
T_M_c = 0.5 * qd_c @ M_c @ qd_c
T_bodies_c = cr.body_kinetic_energies(cobra, q_c, qd_c)
print(f"1/2 qd^T M qd = {T_M_c:.6f} J,  sum over the 13 bodies = {T_bodies_c.sum():.6f} J")

# %% [markdown]
# ## 14. A picture of M
# `log10 |M_ij|` at the random configuration. The dashed lines separate the head's 6 free
# DoF, the 11 joints and the box's 6 DoF. Exact zeros are drawn at the floor value -12.

# %%
fig, ax = plt.subplots(figsize=(6, 5))
image = ax.imshow(np.log10(np.maximum(np.abs(M_c), 1e-12)), cmap="viridis", vmin=-12)
for edge in (5.5, 16.5):
    ax.axhline(edge, color="w", ls="--", lw=0.8)
    ax.axvline(edge, color="w", ls="--", lw=0.8)
ax.set_xlabel("column j: index into qd (0-5 head, 6-16 joints, 17-22 box)")
ax.set_ylabel("row i: index into qd")
ax.set_title("COBRA + box: log10 |M_ij(q)| at a random q")
fig.colorbar(image, ax=ax, label="log10 |M_ij|  (M_ij in kg, kg m or kg m^2)")
fig.tight_layout()
fig.savefig(OUT / "02_mass_matrix.png", dpi=120)

# %% [markdown]
# ## 15. What we just verified
# The hand-derived gravity torque and the RNEA/CRBA identities, on both models:

# %%
np.testing.assert_allclose(tau_hang, [0.0, tau_1_hand, 0.0], atol=1e-12, err_msg="torque by hand")
np.testing.assert_allclose(tau_1_hand, m_link * 9.81 * L, rtol=1e-12, err_msg="cos(-60 deg) = 1/2")
np.testing.assert_allclose(h, cr.rnea(chain, q, qd, zeros), atol=1e-12, err_msg="h = rnea(q, qd, 0)")
for model, M_, M_rnea, h_, tau_, qdd_ in ((chain, M, M_from_rnea, h, tau, qdd),
                                          (cobra, M_c, M_c_from_rnea, h_c, tau_c, qdd_c)):
    np.testing.assert_allclose(M_rnea, M_, atol=1e-10, err_msg=f"{model.name}: M[:, k] = rnea(e_k) - h")
    np.testing.assert_allclose(M_ @ qdd_ + h_, tau_, atol=1e-10, err_msg=f"{model.name}: eq. (1)")
    np.testing.assert_allclose(M_, M_.T, atol=1e-12, err_msg=f"{model.name}: M symmetric")
    assert np.linalg.eigvalsh(M_).min() > 0.0, f"{model.name}: M positive definite"
np.testing.assert_allclose(T_M, T_bodies.sum(), rtol=1e-10, err_msg="chain kinetic energy")
np.testing.assert_allclose(T_M_c, T_bodies_c.sum(), rtol=1e-10, err_msg="COBRA kinetic energy")

# %% [markdown]
# COBRA's block structure and the blocks and weights derived by hand (sections 11-12):

# %%
assert M_c.shape == (23, 23) and M_robot.shape == (17, 17)
np.testing.assert_allclose(M_coupling, 0.0, atol=0.0, err_msg="robot and box are not coupled in M")
np.testing.assert_allclose(M_box, M_box_hand, atol=1e-12, err_msg="box block by hand")
np.testing.assert_allclose(M_c[:3, :3], m_robot * np.eye(3), atol=1e-12, err_msg="head linear block")
np.testing.assert_allclose(h_rest[:3], [0.0, 0.0, m_robot * 9.81], atol=1e-10, err_msg="robot weight")
np.testing.assert_allclose(h_rest[17:], [0, 0, params.box_mass * 9.81, 0, 0, 0], atol=1e-12,
                           err_msg="box weight")
print("All RNEA/CRBA checks passed.")
# a window on an interactive backend; headless (Agg) the PNGs in OUT are the pictures
if plt.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template"):
    plt.show()
