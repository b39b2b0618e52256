# %% [markdown]
# # 03 - Gap functions, contact normals and the contact Jacobian
# **Goal:** compute the signed gap g between a sphere and the ground, a sphere and a box, and
# the box corners and the ground, with the contact normal and frame; then, on COBRA pushing
# the box, check that the contact Jacobian J_c is the derivative of the gaps, dg/dt = J_c qd,
# including the robot-box contacts whose body B (the box) moves.
# **Paper:** [COBRA] eq. (2) (the normal-cone inclusion is written in the gaps g_i), eq. (3)
# (`g'_i = W_i^T u + zeta_i` with `W_i = (dg_i/dq)^T`, and `dg_i/dt != 0` for a moved object)
# and eq. (4) (`g' = J_c u`, the paper's u is our `qd`). The paper never writes its gap
# functions out; the geometry is `cobra_ref/gaps.py`, the Jacobian `cobra_ref/contact.py`.
# **Run:** `python tutorials/03_gap_functions.py`

# %%
import itertools
import os
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import cobra_ref as cr
from cobra_ref.contact import KINDS, ROBOT_BOX, contact_jacobian, find_contacts
from cobra_ref.gaits import RollingGait
from cobra_ref.gaps import box_corner_plane_gaps, box_corners, sphere_box_gap, sphere_plane_gap
from cobra_ref.kinematics import forward_kinematics
from cobra_ref.quaternion import rot_to_quat
from cobra_ref.start import placed_state

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)
np.set_printoptions(precision=4, suppress=True)
rng = np.random.default_rng(0)
e_x, e_y, e_z = np.eye(3)


def R_x(theta):
    """Rotation by theta about the x axis (body -> world)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def R_y(theta):
    """Rotation by theta about the y axis (body -> world)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def R_z(theta):
    """Rotation by theta about the z axis (body -> world)."""
    c, s = np.cos(theta), np.sin(theta)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


# %% [markdown]
# ## 1. The toy: a sphere above the ground
# A contact is between a body A and a body B. The gap g is the signed distance between them:
# `g > 0` separated, `g = 0` touching, `g < 0` penetrating (all in metres, world coordinates).
# The unit normal n points **from B to A**, and the two witness points (the closest points of
# A and of B) satisfy `point_A - point_B = g n`.
#
# For a sphere (A) of radius r with centre c above the plane z = 0 (B), by hand:
#
#     n = e_z,   g = c_z - r,   point_A = c - r e_z (the sphere's lowest point),
#     point_B = (c_x, c_y, 0) (its foot on the plane).
#
# With c = (0.1, -0.2, 0.3) and r = 0.05: g = 0.25, point_A = (0.1, -0.2, 0.25).
#
# The contact frame `[n, t1, t2]` (columns) splits a contact force into its normal part f_N
# and its tangential part f_T (the paper's `f_ext,i = [f_N,i, f_T,i]`, after eq. (3)). It must
# be orthonormal (`C^T C = 1`) and right-handed (`det C = +1`, i.e. `t2 = n x t1`).

# %%
r = 0.05                                          # m
c = np.array([0.1, -0.2, 0.3])                    # m
gap_plane = sphere_plane_gap(c, r)
C = gap_plane.frame
print(f"g = {gap_plane.g:.4f} m   by hand: c_z - r = {c[2] - r:.4f} m")
print("n =", gap_plane.n, " point_A =", gap_plane.point_A, " point_B =", gap_plane.point_B)
print("contact frame [n, t1, t2] =\n", C)
print("C^T C =\n", C.T @ C, "\ndet C =", np.linalg.det(C))

# %% [markdown]
# A sphere that has sunk into the plane has a negative gap: centre at z = 0.02 < r gives
# g = 0.02 - 0.05 = -0.03, the depth of penetration with a minus sign.

# %%
gap_sunk = sphere_plane_gap([0.0, 0.0, 0.02], r)
print(f"sunk sphere: g = {gap_sunk.g:.4f} m (by hand -0.03)")

# %% [markdown]
# ## 2. A sphere and a box
# The box (B) has centre p, rotation R (box -> world) and half extents h. First we work in box
# coordinates (p = 0, R = 1) with a box that is not a cube, h = (0.3, 0.2, 0.1) m, so the three
# axes are told apart. For a centre c **outside** the box, the closest box point is found by
# clipping each coordinate to the box, `q_B = clip(c, -h, h)`; then
#
#     d = |c - q_B|,   n = (c - q_B) / d,   g = d - r,   point_B = q_B,   point_A = c - r n.
#
# This single formula covers the three cases, depending on how many coordinates are clipped:
#
# * **face** (one clipped): c = (0.42, 0.05, 0.02). Only x is clipped, to 0.3:
#   q_B = (0.3, 0.05, 0.02), d = 0.12, g = 0.07, n = +e_x (the face's outward normal);
# * **edge** (two clipped): c = (0.36, 0.28, 0.04). x and y are clipped:
#   q_B = (0.3, 0.2, 0.04) on the vertical edge, c - q_B = (0.06, 0.08, 0), d = 0.1,
#   g = 0.05, n = (0.6, 0.8, 0);
# * **corner** (three clipped): c = (-0.33, 0.24, 0.22). q_B = (-0.3, 0.2, 0.1), the corner,
#   c - q_B = (-0.03, 0.04, 0.12), d = 0.13 (a 3-4-12-13 triple), g = 0.08,
#   n = (-3, 4, 12) / 13.
#
# For a centre **inside** the box (no coordinate clipped), the sphere is pushed out through the
# face it is least deep under: the depths below the six faces are `h_k - |c_k|`, the smallest
# one picks the face, and `g = -(least depth) - r`:
#
# * **inside**: c = (0.1, -0.16, 0.03). Depths (0.2, 0.04, 0.07), least is y on the -y side:
#   g = -0.04 - 0.05 = -0.09, n = -e_y, point_B = (0.1, -0.2, 0.03) on that face.
#
# In every case n points from the box (B) towards the sphere (A): pushing along +n separates
# them.

# %%
h = np.array([0.3, 0.2, 0.1])                     # half extents [m]
centres = {
    "face": np.array([0.42, 0.05, 0.02]),
    "edge": np.array([0.36, 0.28, 0.04]),
    "corner": np.array([-0.33, 0.24, 0.22]),
    "inside": np.array([0.1, -0.16, 0.03]),
}
hand = {                                          # (g, n, point_B), derived above
    "face": (0.07, e_x, np.array([0.3, 0.05, 0.02])),
    "edge": (0.05, np.array([0.6, 0.8, 0.0]), np.array([0.3, 0.2, 0.04])),
    "corner": (0.08, np.array([-3.0, 4.0, 12.0]) / 13, np.array([-0.3, 0.2, 0.1])),
    "inside": (-0.09, np.array([0.0, -1.0, 0.0]), np.array([0.1, -0.2, 0.03])),
}
gaps_box = {}
for case, c_case in centres.items():
    gaps_box[case] = sphere_box_gap(c_case, r, np.eye(3), np.zeros(3), h)
    gap, (g_hand, n_hand, _) = gaps_box[case], hand[case]
    print(f"{case:6s}: g = {gap.g:+.4f} (hand {g_hand:+.4f})  n = {gap.n} (hand {n_hand})  "
          f"point_B = {gap.point_B}  |point_A - point_B - g n| = "
          f"{np.linalg.norm(gap.point_A - gap.point_B - gap.g * gap.n):.1e}")

# %% [markdown]
# ## 3. The normal is the gradient of the gap
# Moving the sphere by dc changes the gap by `n . dc`, and moving the box by dp changes it by
# `-n . dp`: `dg/dc = n`, `dg/dp = -n`. This is why the normal row of the contact Jacobian
# (section 7) is `n^T (J_A - J_B)`. We check both by central differences, for the edge case.
#
# The box's pose only enters through box coordinates `R^T (c - p)`, so a rigid motion of the
# box and the sphere together leaves g unchanged and rotates n with R. We check that too, with
# the box turned 30 degrees about z and moved to p = (1, 2, 0.5).

# %%
eps = 1e-6
gap_edge = gaps_box["edge"]
dg_dc = np.zeros(3)
dg_dp = np.zeros(3)
for k in range(3):
    dc = eps * np.eye(3)[k]
    dg_dc[k] = (sphere_box_gap(centres["edge"] + dc, r, np.eye(3), np.zeros(3), h).g
                - sphere_box_gap(centres["edge"] - dc, r, np.eye(3), np.zeros(3), h).g) / (2 * eps)
    dg_dp[k] = (sphere_box_gap(centres["edge"], r, np.eye(3), dc, h).g
                - sphere_box_gap(centres["edge"], r, np.eye(3), -dc, h).g) / (2 * eps)
print("dg/dc by finite differences:", dg_dc, "  n =", gap_edge.n)
print("dg/dp by finite differences:", dg_dp, "  -n =", -gap_edge.n)

R_moved, p_moved = R_z(np.pi / 6), np.array([1.0, 2.0, 0.5])
gap_moved = sphere_box_gap(p_moved + R_moved @ centres["edge"], r, R_moved, p_moved, h)
print(f"moved box: g = {gap_moved.g:.4f} (same as {gap_edge.g:.4f}),  n = {gap_moved.n} = R n")

# %% [markdown]
# ## 4. Box corners on the ground
# The box touches the ground with its corners. Each of the 8 corners is a point (A) against
# the plane (B), so its gap is just its height, `g_k = (p + R s_k h)_z`, with signs
# `s_k in {-1, +1}^3` in the order of `itertools.product`: corner 0 is (-,-,-), corner 4 is
# (+,-,-), corner 7 is (+,+,+).
#
# Tilt the box by theta = 30 deg about x, then by phi = 10 deg about y: `R = R_y(phi) R_x(theta)`.
# The third row of R is `(-sin phi, cos phi sin theta, cos phi cos theta)`, so
#
#     g_k = p_z - s_x h_x sin phi + cos phi (s_y h_y sin theta + s_z h_z cos theta).
#
# With all three angles' sines and cosines positive, the lowest corner takes s = (+, -, -),
# corner 4, at `p_z - h_x sin phi - cos phi (h_y sin theta + h_z cos theta)`.

# %%
theta, phi = np.radians(30.0), np.radians(10.0)
R_tilt, p_tilt = R_y(phi) @ R_x(theta), np.array([0.2, -0.1, 0.3])
corner_gaps = box_corner_plane_gaps(R_tilt, p_tilt, h)
g_corners = np.array([gap.g for gap in corner_gaps])
g_lowest_hand = p_tilt[2] - h[0] * np.sin(phi) - np.cos(phi) * (h[1] * np.sin(theta) + h[2] * np.cos(theta))
print("corner gaps [m]:", g_corners)
print(f"lowest corner: {np.argmin(g_corners)} (hand: 4),  g = {g_corners.min():.5f} m, "
      f"by hand {g_lowest_hand:.5f} m")

# %% [markdown]
# ## 5. A picture: the slice z = 0 through the box
# The box of section 2 cut by the plane z = 0 is the rectangle |x| <= 0.3, |y| <= 0.2. We put
# sphere centres in that plane in front of a face, next to a vertical edge (a corner of the
# rectangle) and inside, and draw the sphere (its slice), the witness points joined by a dotted
# line (`point_A - point_B = g n`), and the normal n as an arrow from point_B. Outside, the
# arrow points at the sphere; inside, it points out through the least-deep face, and point_A
# lies behind point_B (g < 0).

# %%
slice_centres = [np.array(c_slice) for c_slice in ([0.45, 0.05, 0.0], [-0.1, -0.33, 0.0], [0.37, 0.3, 0.0],
                                                   [-0.42, 0.32, 0.0], [0.12, -0.13, 0.0])]
fig, ax = plt.subplots(figsize=(6, 4.5))
ax.add_patch(plt.Rectangle((-h[0], -h[1]), 2 * h[0], 2 * h[1], fill=False, lw=2, label="box B (slice z = 0)"))
for i, c_slice in enumerate(slice_centres):
    gap = sphere_box_gap(c_slice, r, np.eye(3), np.zeros(3), h)
    ax.add_patch(plt.Circle(c_slice[:2], r, fill=False, color="C0", ls="--"))
    ax.plot(*gap.point_A[:2], "o", color="C0", label="point_A (sphere)" if i == 0 else None)
    ax.plot(*gap.point_B[:2], "s", color="C3", label="point_B (box)" if i == 0 else None)
    ax.plot(*np.stack([gap.point_A[:2], gap.point_B[:2]]).T, ":", color="k")
    ax.annotate("", xy=gap.point_B[:2] + 0.08 * gap.n[:2], xytext=gap.point_B[:2],
                arrowprops=dict(arrowstyle="->", color="C2", lw=1.5))
    ax.text(c_slice[0] + 0.06, c_slice[1], f"g = {gap.g:+.3f}", fontsize=8)
ax.plot([], [], color="C2", label="n (from B to A)")
ax.plot([], [], ":", color="k", label="point_A - point_B = g n")
ax.set_aspect("equal")
ax.set_xlim(-0.6, 0.7)
ax.set_ylim(-0.45, 0.45)
ax.set_xlabel("x [m]")
ax.set_ylabel("y [m]")
ax.set_title("sphere-box gaps: witness points and normals")
ax.legend(loc="lower left", fontsize=7)
fig.tight_layout()
fig.savefig(OUT / "03_sphere_box_gaps.png", dpi=120)

# %% [markdown]
# ## 6. Now the robot: COBRA next to the box
# `cobra_model()` has 13 bodies, 13 contact spheres (two on the head, one on each link L1..L10
# and one on the tail) and the box, a 0.1 m cube that is a second free body. Coordinates, as in
# tutorial 02:
#
#     q  (25) = [head x y z qw qx qy qz | theta_0 .. theta_10 | box x y z qw qx qy qz]
#     qd (23) = [head v_world, w_body   | thetad_0 .. thetad_10 | box v_world, w_body]
#
# We take the t = 0 shape of the rolling gait from `placed_state` (a flat C-shaped snake whose
# lowest sphere, the tail's, is 1 mm above the ground; `initial_state` would then let it settle
# onto the ground, which we do not need here), turn the yaw joints by a few random
# hundredths of a radian so that nothing is symmetric, and place the box ourselves (so that we
# know the gap to expect): resting on the ground just outside the curve, 4 mm from the sphere
# of link L6 and turned 0.2 rad from facing it squarely.
#
# `find_contacts` lists the candidate contacts with gap below a margin: spheres on the ground
# (kind 0), spheres on the box (kind 1) and box corners on the ground (kind 2), one gap
# function call per pair. `find_contacts(model, q, margin)` and `contact_jacobian(model, q,
# contacts)` (module `cobra_ref.contact`, the readable reference) compute the body poses with
# `forward_kinematics(model, q)` (lists `kin.o[i]`, `kin.R[i]` per body), which we use too.

# %%
cobra = cr.cobra_model()
box = cobra.boxes[0]
i_L6 = cobra.body_names.index("L6")
s_L6 = int(np.flatnonzero(cobra.spheres.body == i_L6)[0])
q = placed_state(cobra, RollingGait())
yaw_q = [cobra.q_idx[i].start for i, jt in enumerate(cobra.joint_type) if jt == "Rz"]
q[yaw_q] += 0.03 * rng.normal(size=len(yaw_q))

# Place the box. u_out = L6's left axis (it points out of the C here). The box's x axis is
# u_out turned by alpha = 0.2 rad, so its -x face faces the sphere at an angle. The centre
# goes along u_out at distance d; the sphere centre is then d cos(alpha) - h_x from the face
# plane, and 4 mm of gap needs d cos(alpha) - h_x - r = 0.004.
kin = forward_kinematics(cobra, q)
c_L6 = kin.o[i_L6] + kin.R[i_L6] @ cobra.spheres.center[s_L6]
r_L6 = cobra.spheres.radius[s_L6]
u_out = kin.R[i_L6] @ e_y
alpha = 0.2
R_box = R_z(np.arctan2(u_out[1], u_out[0]) + alpha)
d = (r_L6 + box.half[0] + 0.004) / np.cos(alpha)
p_box = c_L6 + d * u_out
p_box[2] = box.half[2]                            # resting on the ground
iq_box = cobra.q_idx[box.body]
q[iq_box] = np.concatenate([p_box, rot_to_quat(R_box)])

kin = forward_kinematics(cobra, q)
contacts = find_contacts(cobra, q, margin=0.01)
print(f"{contacts.m} contacts with g < 1 cm:")
for k, (kind, body_A, feature) in enumerate(contacts.keys()):
    print(f"  {k:2d}  {KINDS[kind]:12s}  A = {cobra.body_names[body_A]:4s}  feature {feature:2d}  "
          f"g = {contacts.g[k] * 1000:6.2f} mm  n = {contacts.frame[k][:, 0]}")

# %% [markdown]
# ## 7. The normal rows of J_c are dg/dq
# `contact_jacobian` stacks, for each contact, the three rows `[n, t1, t2]^T (J_A - J_B)`,
# where J_A is the point Jacobian of body A at point_A (world velocity of that body point =
# J_A qd) and J_B the same for body B at point_B (zero for the ground). The first row of each
# triple is the paper's `W_i^T`:
#
#     g'_i = n^T (v_A(point_A) - v_B(point_B)) = n^T (J_A - J_B) qd = W_i^T qd.
#
# Why this is dg/dt: by section 3, moving A's material point by dx_A changes g by `n . dx_A`
# and moving B's by dx_B changes it by `-n . dx_B`. (The witness points slide over the
# surfaces as the bodies move, but that sliding is tangential, so it does not change g to
# first order. A sphere spinning about its own centre does not change g either: point_A =
# c - r n moves with w x (-r n), which is perpendicular to n.)
#
# Check by central differences. Because nq != nv (the quaternions), we cannot perturb q[k];
# instead we move along each velocity direction e_k for a time +-eps with `integrate`
# (`q (+) eps e_k`, the quaternion is updated by the exponential map), so that
#
#     W^T e_k = d/d eps g(q (+) eps e_k) ~ [g(q (+) eps e_k) - g(q (+) -eps e_k)] / (2 eps).
#
# The perturbed states must measure the **same** contact: we recompute every candidate gap
# with an infinite margin and look each one up by its key (kind, body A, feature).
#
# Two columns by hand: lifting the head (column 2, head v_z) lifts the whole robot, so every
# robot-ground row has W^T e_2 = 1, the box-ground rows 0, and the robot-box row `n_z = 0`
# (its normal is horizontal); lifting the box (column 19, box v_z) gives 1 for each box corner,
# 0 for the robot-ground rows and `-n_z = 0` for the robot-box row.

# %%
def gaps_by_key(q_new):
    """Every candidate gap at q_new (margin = inf), as a dict {contact key: g}."""
    all_contacts = find_contacts(cobra, q_new, margin=np.inf)
    return dict(zip(all_contacts.keys(), all_contacts.g))


J_c = contact_jacobian(cobra, q, contacts)
W_T = J_c[0::3]                                   # normal rows: one W_i^T per contact, (m, nv)
keys = contacts.keys()
eps = 1e-6
W_T_fd = np.zeros_like(W_T)
I_nv = np.eye(cobra.nv)
for k in range(cobra.nv):
    g_plus = gaps_by_key(cr.integrate(cobra, q, I_nv[k], eps))
    g_minus = gaps_by_key(cr.integrate(cobra, q, I_nv[k], -eps))
    W_T_fd[:, k] = [(g_plus[key] - g_minus[key]) / (2 * eps) for key in keys]
err_normal = np.abs(W_T_fd - W_T).max()
rel_err_normal = err_normal / np.abs(W_T).max()
print("J_c shape:", J_c.shape, " (3 rows per contact x nv)")
print(f"max |W^T - finite differences| = {err_normal:.2e}  (relative to max |W^T|: {rel_err_normal:.2e})")
print("column 2 (head v_z):", W_T[:, 2])
print("column 19 (box v_z):", W_T[:, 19])

# %% [markdown]
# ## 8. The relative Jacobian: a moving box changes the gap
# The paper stresses `dg_i/dt != 0` (eq. (3)): when the robot pushes a box that moves, the gap
# changes even if the robot is still. If the box's motion is seen as given, g depends on time
# explicitly (the paper's `zeta_i`); in our stacked coordinates the box is part of q, and the
# same effect appears in the **box columns** of the robot-box row, `-n^T J_B`.
#
# By hand: the box point at point_B moves with `v_box + w_world x r`, `r = point_B - p_box`,
# `w_world = R_box w_body`. Then
#
#     g' = -n . (v_box + w_world x r) = -n . v_box - w_body . R_box^T (r x n),
#
# so the six box columns of W^T are `[-n^T, -(R_box^T (r x n))^T]`. We give **only** the box a
# velocity, `v_box = 0.1 (-n)` m/s (straight at the sphere) and `w_body = (0, 0, 0.5)` rad/s, and
# compare the hand value, `W^T qd` and a finite difference of the gap along that velocity.

# %%
k_rb = keys.index((ROBOT_BOX, i_L6, s_L6))
n_rb = contacts.frame[k_rb][:, 0]
r_rb = contacts.point_B[k_rb] - p_box
iv_box = cobra.v_idx[box.body]
W_box_hand = np.concatenate([-n_rb, -R_box.T @ np.cross(r_rb, n_rb)])
qd_box = np.zeros(cobra.nv)
qd_box[iv_box] = np.concatenate([-0.1 * n_rb, [0.0, 0.0, 0.5]])
gd_hand = W_box_hand @ qd_box[iv_box]
gd_J = W_T[k_rb] @ qd_box
gd_fd = (gaps_by_key(cr.integrate(cobra, q, qd_box, eps))[keys[k_rb]]
         - gaps_by_key(cr.integrate(cobra, q, qd_box, -eps))[keys[k_rb]]) / (2 * eps)
print("box columns of the robot-box row:", W_T[k_rb, iv_box], "\n  by hand:", W_box_hand)
print(f"robot still, box moving: g' by hand = {gd_hand:.6f} m/s, W^T qd = {gd_J:.6f} m/s, "
      f"finite difference = {gd_fd:.6f} m/s")
print("  of which the translation gives -n . v_box = 0.1 m/s, the spin",
      f"{gd_hand - 0.1:.6f} m/s")

# %% [markdown]
# The box columns are zero for the robot-ground rows, and the robot columns (0-16) are zero
# for the box-ground rows: a contact couples only the two bodies it touches.

# %%
kinds = contacts.kind
print("max |box columns| of robot-ground rows :", np.abs(W_T[kinds == 0][:, iv_box]).max())
print("max |robot columns| of box-ground rows :", np.abs(W_T[kinds == 2][:, :iv_box.start]).max())

# %% [markdown]
# ## 9. The tangential rows: the sliding velocity
# The rows t1 and t2 of each triple are not derivatives of any gap: they give the velocity at
# which A slides over B, `t^T (v_A(point_A) - v_B(point_B))`, which the friction cone acts on.
# They are checked the same way if we follow the two **material** points: the point of body A
# that sits at point_A now (body coordinates `x_A = R_A^T (point_A - p_A)`), and likewise for
# B; after a move their world positions are `p_A + R_A x_A`, and
#
#     J_c e_k ~ [C^T (x_A - x_B)(q (+) eps e_k) - C^T (x_A - x_B)(q (+) -eps e_k)] / (2 eps)
#
# with the contact frame C held fixed. (The ground's point_B never moves.)

# %%
def frozen_separations(q_new):
    """C^T (x_A - x_B) at q_new for the material points that were at point_A, point_B at q, (m, 3)."""
    kin_new = forward_kinematics(cobra, q_new)

    def moved(body, x):
        """World position at q_new of the point of ``body`` that was at x at q (the ground: x)."""
        if body < 0:
            return x
        return kin_new.o[body] + kin_new.R[body] @ (kin.R[body].T @ (x - kin.o[body]))

    out = np.zeros((contacts.m, 3))
    for i in range(contacts.m):
        x_A = moved(contacts.body_A[i], contacts.point_A[i])
        x_B = moved(contacts.body_B[i], contacts.point_B[i])
        out[i] = contacts.frame[i].T @ (x_A - x_B)
    return out


J_c_fd = np.zeros_like(J_c)
for k in range(cobra.nv):
    J_c_fd[:, k] = (frozen_separations(cr.integrate(cobra, q, I_nv[k], eps))
                    - frozen_separations(cr.integrate(cobra, q, I_nv[k], -eps))).ravel() / (2 * eps)
err_full = np.abs(J_c_fd - J_c).max()
print(f"all 3 rows per contact: max |J_c - finite differences| = {err_full:.2e} "
      f"(relative {err_full / np.abs(J_c).max():.2e})")

# %% [markdown]
# ## 10. What we checked
# * Sections 1-4, against the hand derivations: the sphere-plane gap `c_z - r`; the sphere-box
#   gap by clipping for a face, an edge and a corner, and by the least-deep face inside; the
#   normal from B to A with `point_A - point_B = g n` and `dg/dc = n = -dg/dp`; the rigid-motion
#   invariance; the lowest corner of a tilted box; orthonormal right-handed contact frames.

# %%
np.testing.assert_allclose(gap_plane.g, 0.25, atol=1e-15, err_msg="sphere-plane g")
np.testing.assert_allclose(gap_plane.n, e_z, atol=0, err_msg="ground normal")
np.testing.assert_allclose(gap_plane.point_A, [0.1, -0.2, 0.25], atol=1e-15, err_msg="sphere-plane point_A")
np.testing.assert_allclose(gap_sunk.g, -0.03, atol=1e-15, err_msg="sunk sphere")
for case, (g_hand, n_hand, point_B_hand) in hand.items():
    gap = gaps_box[case]
    np.testing.assert_allclose(gap.g, g_hand, atol=1e-14, err_msg=f"{case}: g")
    np.testing.assert_allclose(gap.n, n_hand, atol=1e-14, err_msg=f"{case}: n")
    np.testing.assert_allclose(gap.point_B, point_B_hand, atol=1e-15, err_msg=f"{case}: point_B")
    np.testing.assert_allclose(gap.point_A - gap.point_B, gap.g * gap.n, atol=1e-14, err_msg=f"{case}: g n")
for C_k in [gap_plane.frame] + [gap.frame for gap in gaps_box.values()] + list(contacts.frame):
    np.testing.assert_allclose(C_k.T @ C_k, np.eye(3), atol=1e-14, err_msg="frame orthonormal")
    np.testing.assert_allclose(np.linalg.det(C_k), 1.0, atol=1e-14, err_msg="frame right-handed")
np.testing.assert_allclose(dg_dc, gap_edge.n, atol=1e-9, err_msg="dg/dc = n")
np.testing.assert_allclose(dg_dp, -gap_edge.n, atol=1e-9, err_msg="dg/dp = -n")
np.testing.assert_allclose(gap_moved.g, gap_edge.g, atol=1e-14, err_msg="rigid motion keeps g")
np.testing.assert_allclose(gap_moved.n, R_moved @ gap_edge.n, atol=1e-14, err_msg="rigid motion rotates n")
assert int(np.argmin(g_corners)) == 4, "lowest corner is s = (+, -, -)"
np.testing.assert_allclose(g_corners.min(), g_lowest_hand, atol=1e-14, err_msg="lowest corner by hand")
g_corners_hand = [p_tilt[2] - s_x * h[0] * np.sin(phi)
                  + np.cos(phi) * (s_y * h[1] * np.sin(theta) + s_z * h[2] * np.cos(theta))
                  for s_x, s_y, s_z in itertools.product((-1, 1), repeat=3)]
np.testing.assert_allclose(g_corners, g_corners_hand, atol=1e-14, err_msg="all 8 corner heights by hand")
np.testing.assert_allclose(g_corners, box_corners(R_tilt, p_tilt, h)[:, 2], atol=0, err_msg="g_k = corner height")

# %% [markdown]
# * Sections 6-9, on COBRA and the box: the robot-box contact is where we built it (4 mm, normal
#   = the outward normal of the box's -x face); every normal row of J_c equals the
#   finite-difference gradient of its gap along all 23 velocity directions, and all three rows
#   equal the finite-difference velocity of the contact's material points, to ~1e-10 with
#   eps = 1e-6 (round-off eps_machine / eps); the box alone moving changes the robot-box gap
#   at the rate `W^T qd` derived by hand (eq. (3): dg/dt != 0 for a moving object); and each
#   contact couples only its two bodies.

# %%
assert ROBOT_BOX in contacts.kind and 0 in contacts.kind and 2 in contacts.kind, "all three contact kinds"
np.testing.assert_allclose(contacts.g[k_rb], 0.004, atol=1e-12, err_msg="robot-box gap as placed")
np.testing.assert_allclose(n_rb, -R_box[:, 0], atol=1e-12, err_msg="normal of the box's -x face")
assert rel_err_normal < 1e-6, f"normal rows vs dg/dq: relative error {rel_err_normal:.1e}"
assert err_full / np.abs(J_c).max() < 1e-6, f"J_c vs material-point velocities: {err_full:.1e}"
np.testing.assert_allclose(W_T[kinds == 0, 2], 1.0, atol=1e-12, err_msg="lifting the head lifts every sphere")
np.testing.assert_allclose(W_T[kinds == 2, iv_box.start + 2], 1.0, atol=1e-12, err_msg="lifting the box")
np.testing.assert_allclose(W_T[k_rb, iv_box], W_box_hand, atol=1e-12, err_msg="box columns by hand")
np.testing.assert_allclose(gd_J, gd_hand, atol=1e-12, err_msg="g' of the moving box by hand")
np.testing.assert_allclose(gd_fd, gd_J, atol=1e-8, err_msg="g' of the moving box by finite differences")
assert abs(gd_J) > 0.05, "the box alone moving changes the gap (dg/dt != 0)"
np.testing.assert_allclose(W_T[kinds == 0][:, iv_box], 0.0, atol=0, err_msg="robot-ground rows ignore the box")
np.testing.assert_allclose(W_T[kinds == 2][:, :iv_box.start], 0.0, atol=0, err_msg="box-ground rows ignore the robot")
print("All gap and contact-Jacobian checks passed.")
# a window on an interactive backend; headless (Agg) the PNGs in OUT are the pictures
if plt.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template"):
    plt.show()
