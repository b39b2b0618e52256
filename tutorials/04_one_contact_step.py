# %% [markdown]
# # 04 - One contact time step by hand
# **Goal:** take one velocity-level time step with contact, by hand: the free velocity,
# the Delassus matrix G, the least-action QP for the impulses, and its optimality conditions.
# First on a ball on the plane (every number by hand), then on COBRA lying on the ground
# next to the box, where we rebuild `Stepper.step` piece by piece and compare.
# **Paper:** [COBRA] eq. (1) (equations of motion), eq. (2) (normal-cone inclusion, at the
# velocity level), eq. (5) (Delassus matrix G and free term c), eq. (6) (least action).
# Impulses p = f dt replace the paper's forces f_ext (`cobra_ref/contact_qp.py`).
# **Run:** `python tutorials/04_one_contact_step.py`

# %%
import matplotlib.pyplot as plt
import numpy as np

import cobra_ref as cr
from cobra_ref.fast.contacts import KINDS, ROBOT_BOX, contact_jacobian, find_contacts
from cobra_ref.fast.contact_qp import ContactQP, facet_directions, kkt_residuals
from cobra_ref.fast.chain import ChainModel
from cobra_ref.gaits import RollingGait
from cobra_ref.simulate import initial_state
from cobra_ref.fast.stepper import Stepper

np.set_printoptions(precision=5, suppress=True)

# %% [markdown]
# ## 1. One time step in one page
# Eq. (1) with the signs of the README, `M u' + h = tau + J_c^T f`, integrated over one step
# dt with M and h frozen at the start of the step, and with the impulse p = f dt:
#
#     M (u+ - u) = dt (tau - h) + J_c^T p.
#
# Split u+ into the velocity the system would have **without contact** and the kick the
# impulses give it:
#
#     u+ = u_free + M^-1 J_c^T p,          u_free = u + dt M^-1 (tau - h).
#
# The contact velocities after the step (normal, then the two tangential ones, per contact)
# are `w = J_c u+`. Substituting u+:
#
#     w = G p + c,    G = J_c M^-1 J_c^T  (eq. (5), the Delassus matrix),   c = J_c u_free.
#
# G is the "inverse inertia seen at the contacts". To keep an open gap g_i > 0 (the paper's
# gap function; plain g is gravity here) from closing by more than g_i in one step, we ask
# for `g_i + dt w_N >= 0` rather than `w_N >= 0`. We do this by adding `g_i / dt` to the
# normal rows of c, so that w_N means (gap after the step) / dt.
#
# Least action, eq. (6) (with impulses), finds p:
#
#     min_p  1/2 p^T G p + p^T c    s.t.  p_N >= 0,  |p_t1| <= mu p_N,  |p_t2| <= mu p_N.
#
# The constraint set is the 4-facet **friction pyramid**, our linearisation of the paper's
# friction cone F_i. Its optimality (KKT) conditions are eq. (2) at the velocity level (section 4).

# %% [markdown]
# ## 2. The toy: a ball resting on the plane
# A point mass m with velocity `u = (u_x, u_y, u_z)` (world), so `M = m 1`. Gravity is the
# bias force: `M u' + h = 0` in free fall gives `h = (0, 0, m g)`. There is no actuator, so
# tau = 0. The contact frame is n = e_z, t1 = e_x, t2 = e_y, and the contact Jacobian holds
# these three vectors as rows:
#
#     J_c = [n; t1; t2] = [[0, 0, 1], [1, 0, 0], [0, 1, 0]],    G = J_c M^-1 J_c^T = 1 / m.
#
# The ball starts at rest on the plane (g_i = 0), so
# `u_free = (0, 0, -g dt)` and `c = J_c u_free = (-g dt, 0, 0)`.
#
# **By hand.** Without constraints the minimiser is `p = -G^-1 c = (m g dt, 0, 0)`. It has
# p_N > 0 and p_T = 0, so it lies inside the pyramid: it is the solution. Then
# `w = G p + c = 0`: the ball neither sinks nor lifts off.

# %%
m, grav, dt, mu = 2.0, 9.81, 1e-3, 0.5            # kg, m/s^2, s, -
M_ball = m * np.eye(3)
h_ball = np.array([0.0, 0.0, m * grav])
J_ball = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])   # rows n, t1, t2
G_ball = J_ball @ np.linalg.solve(M_ball, J_ball.T)
print("G = J_c M^-1 J_c^T =\n", G_ball)


def ball_c(u, gap=0.0):
    """c = J_c u_free + [gap / dt, 0, 0] for the ball with velocity u (world)."""
    u_free = u + dt * np.linalg.solve(M_ball, -h_ball)          # u + dt M^-1 (tau - h), tau = 0
    return J_ball @ u_free + np.array([gap / dt, 0.0, 0.0])


# %% [markdown]
# `ContactQP(mu).solve(G, c)` returns the impulses p = [p_N, p_t1, p_t2] per contact and a
# `QPInfo` record. OSQP solves `G + eps 1` with eps = 1e-6 mean(diag G), a tiny uniform
# regularization (section 8 explains why the robot needs it). For the ball this gives
# `p_N = m g dt / (1 + 1e-6)`, so we compare with the hand result at rtol 1e-5.

# %%
c_rest = ball_c(np.zeros(3))
p_rest, info_rest = ContactQP(mu).solve(G_ball, c_rest)
p_rest_hand = np.array([m * grav * dt, 0.0, 0.0])
print("c      =", c_rest, "m/s")
print("p OSQP =", p_rest, "N s,  by hand:", p_rest_hand)
print("w = G p + c =", G_ball @ p_rest + c_rest, "m/s   status:", info_rest.status)

# %% [markdown]
# ## 3. Sliding and sticking, by hand
# Now give the ball a tangential velocity v along t1 = e_x, so `c = (-g dt, v, 0)`.
# The normal row of G does not couple to the tangential ones, so p_N = m g dt again.
#
# * **Fast slip**, v = 0.5 m/s > mu g dt = 4.9 mm/s. Stopping the slip would take
#   |p_t1| = m v > mu p_N, which lies outside the pyramid. So friction sits on the facet that
#   opposes the slip, `p_t1 = -mu p_N = -mu m g dt`, and the ball keeps sliding at
#   `w_t1 = v - mu g dt`. This is Coulomb's kinetic friction.
# * **Slow slip**, v = 0.4 mu g dt. The unconstrained minimiser `p = (m g dt, -m v, 0)` has
#   `|p_t1| = 0.4 mu p_N < mu p_N`. It is feasible, so the ball sticks within the step:
#   `w_T = 0`.

# %%
v_fast, v_slow = 0.5, 0.4 * mu * grav * dt        # m/s
c_fast, c_slow = ball_c(np.array([v_fast, 0, 0])), ball_c(np.array([v_slow, 0, 0]))
p_fast, _ = ContactQP(mu).solve(G_ball, c_fast)
p_slow, _ = ContactQP(mu).solve(G_ball, c_slow)
p_fast_hand = np.array([m * grav * dt, -mu * m * grav * dt, 0.0])
p_slow_hand = np.array([m * grav * dt, -m * v_slow, 0.0])
print("fast slip: p =", p_fast, " by hand", p_fast_hand, "  w =", G_ball @ p_fast + c_fast)
print("slow slip: p =", p_slow, " by hand", p_slow_hand, "  w =", G_ball @ p_slow + c_slow)

# %% [markdown]
# **The gap term.** A ball hovering g_i = 0.5 mm above the plane and falling at 1 m/s has
# `c_N = -1 - g dt + g_i / dt = -0.50981 m/s < 0`. It would pass through the plane within this
# step, so it receives `p_N = -m c_N`. Its velocity after the step is then exactly
# `-g_i / dt = -0.5 m/s`: the gap closes at the end of the step, without penetration and without
# a bounce. A ball at rest 5 mm up has `c_N = g_i / dt - g dt = 5 m/s - g dt > 0` and gets nothing: the
# candidate contact (within the 10 mm margin) stays inactive. COBRA's first steps below
# work the same way.

# %%
gap_near, gap_far = 0.5e-3, 5e-3                  # m
c_land = ball_c(np.array([0.0, 0.0, -1.0]), gap=gap_near)
c_hover = ball_c(np.zeros(3), gap=gap_far)
p_land, _ = ContactQP(mu).solve(G_ball, c_land)
p_hover, _ = ContactQP(mu).solve(G_ball, c_hover)
print(f"landing: c_N = {c_land[0]:.5f} m/s, p_N = {p_land[0]:.6f} N s (by hand {-m * c_land[0]:.6f}),"
      f" u_z+ = {(G_ball @ p_land + c_land)[0] - gap_near / dt:.5f} m/s")
print(f"hovering: c_N = {c_hover[0]:.5f} m/s, p = {p_hover} N s")

# %% [markdown]
# ## 4. Optimality conditions = eq. (2) at the velocity level
# Eq. (2) reads `-g' in N_F(f)`: the contact velocity lies in the normal cone of the force
# set F at the force. Written out for one contact, with w = G p + c:
#
# * **Signorini** (normal): `0 <= p_N  _|_  w_N >= 0`. There is no pull, no approach, and no
#   force on a contact that opens.
# * **Stick**: if p_T lies strictly inside the pyramid, then `w_T = 0`.
# * **Slip**: if w_T != 0, then p_T is on the boundary and opposes it. For the 4-facet pyramid
#   (the box |p_ti| <= mu p_N) this holds per component: a component strictly inside its
#   bound has `w_ti = 0`, and a component on its bound has w_ti of the opposite sign
#   (`p_ti = -mu p_N sign(w_ti)` whenever w_ti != 0).
#
# These are exactly the KKT conditions of the QP in section 1. The multiplier of `p_N >= 0` is
# w_N, and the multipliers of the facets give w_T. `kkt_residuals(G, c, p, mu, D)` measures
# three numbers: `max |p_N w_N|`, the cone violation relative to max p_N, and the largest
# |w_T| over the contacts that are strictly inside (relative margin 1e-6, and p_N > 1e-9 max p_N).
# We compute the same three numbers with plain numpy. We add a slip residual that
# `kkt_residuals` does not report: the largest violation of the per-component rule, in m/s.

# %%
def velocity_level_eq2(G, c, p, mu):
    """w = G p + c and the residuals of eq. (2): (comp, cone, stick, slip), plus 'inside' per contact."""
    w = G @ p + c
    p_N, p_T = p[0::3], np.stack([p[1::3], p[2::3]], axis=1)
    w_N, w_T = w[0::3], np.stack([w[1::3], w[2::3]], axis=1)
    bound = np.broadcast_to(mu, p_N.shape)[:, None] * p_N[:, None]   # mu p_N, per component
    scale = max(p_N.max(), 1e-12)
    comp = np.abs(p_N * w_N).max()                                  # Signorini: p_N w_N = 0
    cone = max(0.0, (np.abs(p_T) - bound).max()) / scale             # |p_ti| <= mu p_N
    loaded = p_N > 1e-9 * scale
    inside = np.all(np.abs(p_T) < bound * (1 - 1e-6), axis=1) & loaded
    stick = np.linalg.norm(w_T[inside], axis=1).max(initial=0.0)    # w_T = 0 inside
    # per component: inside its bound w_ti = 0; on it, w_ti opposes p_ti (sign(p_ti) w_ti <= 0)
    on = np.abs(p_T) >= bound * (1 - 1e-6)
    slip = np.where(on, np.maximum(np.sign(p_T) * w_T, 0.0), np.abs(w_T))[loaded].max(initial=0.0)
    return w, comp, cone, stick, slip, inside


# %%
D4 = facet_directions(4)                          # facet normals d_0 = t1, d_1 = t2
for name, c, p in (("rest", c_rest, p_rest), ("fast slip", c_fast, p_fast), ("slow slip", c_slow, p_slow)):
    w, comp, cone, stick, slip, inside = velocity_level_eq2(G_ball, c, p, mu)
    print(f"{name:9s}: p_N = {p[0]:.6f} N s >= 0, w_N = {w[0]: .1e} m/s >= 0,"
          f" {'stick' if inside[0] else 'slip '}: w_T = {w[1:]} m/s")
    print(f"           numpy (comp, cone, stick) = ({comp:.1e}, {cone:.1e}, {stick:.1e}), slip = {slip:.1e} m/s;"
          f" kkt_residuals = {tuple(float(f'{r:.1e}') for r in kkt_residuals(G_ball, c, p, mu, D4))}")

# %% [markdown]
# ## 5. An independent solver: projected Gauss-Seidel
# Projected Gauss-Seidel (PGS) solves the same conditions one row r at a time. It first
# sets `w_r = (G p + c)_r` to zero by changing p_r alone, `p_r <- p_r - w_r / G_rr`, then
# projects the result: a normal row onto p_N >= 0, a tangential row onto
# `[-mu p_N, mu p_N]` of its own contact. We simply run a fixed number of sweeps. PGS has no
# regularization, no ADMM and no friction fixed point, so it shares no code with OSQP.

# %%
def projected_gauss_seidel(G, c, mu, n_sweeps=200):
    """Row-by-row relaxation of w = G p + c, projected on p_N >= 0 and |p_ti| <= mu_i p_N."""
    p, mu = np.zeros(len(c)), np.broadcast_to(mu, (len(c) // 3,))
    for _ in range(n_sweeps):
        for r in range(len(c)):
            k = r - r % 3                                           # normal row of this contact
            p[r] -= (G[r] @ p + c[r]) / G[r, r]                     # w_r = 0
            p[r] = max(p[r], 0.0) if r == k else np.clip(p[r], -mu[k // 3] * p[k], mu[k // 3] * p[k])
    return p


# %%
for name, c, p_osqp, p_hand in (("rest", c_rest, p_rest, p_rest_hand), ("fast slip", c_fast, p_fast, p_fast_hand),
                                ("slow slip", c_slow, p_slow, p_slow_hand)):
    p_pgs = projected_gauss_seidel(G_ball, c, mu)
    print(f"{name:9s}: PGS {p_pgs}  |PGS - hand| = {np.abs(p_pgs - p_hand).max():.1e}"
          f"  |OSQP - PGS| = {np.abs(p_osqp - p_pgs).max():.1e} N s")

# %% [markdown]
# **A caveat of the 4-facet pyramid.** The pyramid circumscribes the circle
# `|p_T| <= mu p_N`. Along t1 or t2 it is exact, but along a diagonal it lets friction reach
# `sqrt(2) mu p_N` (41 % too much). A ball sliding fast along (1, 1)/sqrt(2) gets
# `p_T = -mu p_N (1, 1)` from both solvers. This is why the stepper turns each contact's t1
# along the previous slip direction (the `t_hint` of `find_contacts`): then the pyramid is
# exact where it matters.

# %%
c_diag = ball_c(np.array([0.5, 0.5, 0.0]) / np.sqrt(2))
p_diag, _ = ContactQP(mu).solve(G_ball, c_diag)
p_diag_pgs = projected_gauss_seidel(G_ball, c_diag, mu)
print("diagonal slip: p OSQP =", p_diag, " PGS =", p_diag_pgs)
print(f"|p_T| / (mu p_N) = {np.linalg.norm(p_diag[1:]) / (mu * p_diag[0]):.4f}  (sqrt 2 = {np.sqrt(2):.4f})")

# %% [markdown]
# ## 6. Now the robot: COBRA lying on the ground next to the box
# `cobra_model()` has the head (floating base), 11 joints and the box as a second free body:
# nv = 23. The built-in `RollingGait()` starts at rest in a flat C shape (only the yaw
# joints are bent) and ramps up the rolling over 2 s. `initial_state` puts the robot in that
# shape with its lowest sphere 1 mm above the ground. It puts the box on the ground with its
# centre 0.12 m from the centre of the middle link L5 along +x, which is the concave side of
# the C. This leaves 16.5 mm between the box and L5.

# %%
model = cr.cobra_model()
ref = RollingGait()
q0, u0 = initial_state(model, ref, box_offset=(0.12, 0.0))
m_robot, m_box = sum(model.mass[:12]), model.mass[12]
weight = (m_robot + m_box) * grav                 # N
print(f"nq = {model.nq}, nv = {model.nv}; robot {m_robot} kg + box {m_box} kg, weight {weight:.3f} N")
print(f"mu ground = {model.mu}, mu robot-box = {model.mu_robot_box}")

# %% [markdown]
# ## 7. The first steps, and letting it settle
# We run `Stepper(model).step` for 300 steps (0.3 s) and log the total vertical contact force
# against the weight. Only contacts with the ground count: robot-box impulses are internal.
# The impulses p are in each contact's frame `[n, t1, t2]`, so the world force is
# `frame @ p / dt`.
#
# What to expect: at t = 0 the robot's spheres hover 1 to 4.5 mm up. Each has
# `c_N ~ g_i / dt >= 1 m/s > 0`, so only the box carries load at first. The ratio is then
# `m_box / (m_robot + m_box) = 0.077`. The robot falls freely until its lowest sphere (the
# tail's, the largest) can close its gap within one step. After that it rocks on its spheres
# and comes to rest on three of them.

# %%
stepper = Stepper(model)
q, u = q0.copy(), u0.copy()
force_ratio, n_robot_active = [], []
for k in range(300):
    res = stepper.step(q, u, k * dt, ref)
    on_ground = res.contacts.kind != ROBOT_BOX
    f_world = np.einsum("kij,kj->ki", res.contacts.frame, res.p.reshape(-1, 3)) / dt   # N
    force_ratio.append(f_world[on_ground, 2].sum() / weight)
    n_robot_active.append(int(np.sum((res.contacts.kind == 0) & (res.p[0::3] > 1e-9))))
    if k == 0:
        r0 = res                                  # the very first step, for the printout below
    q, u = res.q, res.qd
t_settled, res_last = 300 * dt, res             # state (q, u) at t = 0.3 s, last step's result
force_ratio = np.array(force_ratio)

# %%
print("step 0: gaps of the candidates [mm]:", np.round(1e3 * r0.contacts.g, 2))
print("        normal forces p_N / dt [N] :", np.round(r0.p[0::3] / dt, 3) + 0.0)
landing = int(np.argmax(np.array(n_robot_active) > 0))
print(f"force / weight, steps 0-5: {np.round(force_ratio[:6], 4)}  (m_box / m_total = {m_box / (m_robot + m_box):.4f})")
print(f"first robot contact at step {landing} (free fall of 1 mm takes sqrt(2 mm / g) = "
      f"{1e3 * np.sqrt(2e-3 / grav):.1f} ms)")
print(f"force / weight at steps 50, 100, 200, 299: {np.round(force_ratio[[50, 100, 200, 299]], 5)}")
print(f"active robot contacts at steps 50, 100, 200, 299: {[n_robot_active[k] for k in (50, 100, 200, 299)]}")

# %% [markdown]
# Each touchdown shows as a short spike (the log-scale plot in section 10). The contact
# removes the approach velocity within one step, with no bounce, so the force over that one
# step is large. While the robot rocks on two spheres, the ratio stays a few % below 1: the
# centre of mass accelerates downwards as the robot tips. Once it rests on three spheres
# (from about step 225), the ratio is 1 to within 1e-4. The small remainder is the rolling
# gait starting up.
#
# ## 8. One step by hand at the settled state
# From here on, (q, u) is the state after 0.3 s. We rebuild what `Stepper.step` does, using
# only public functions.
#
# **8a. M and h.** `ChainModel(model).terms(q, u)` returns M (23 x 23) and h (23), the same
# numbers as `crba` and `bias_force` of tutorial 02.
#
# **Free and prescribed coordinates.** With the default "prescribed" servo, the 11 joints
# follow the reference exactly. Their velocity over the step is the secant
# `u+_P = (q_ref(t + dt) - q_P) / dt`. Only the head's 6 and the box's 6 coordinates (the set
# F, 12 DoF) are left to the dynamics.

# %%
chain = ChainModel(model)
terms = chain.terms(q, u)
M, h = terms.M, terms.h
P = np.array([model.v_idx[i].start for i, jt in enumerate(model.joint_type) if jt != "free"])   # joints
P_q = np.array([model.q_idx[i].start for i, jt in enumerate(model.joint_type) if jt != "free"])
F = np.setdiff1d(np.arange(model.nv), P)          # head 0-5, box 17-22
print("free coordinates F:", F, "\nprescribed P:", P)

# %% [markdown]
# **8b. Free velocity.** Take the F rows of eq. (1). Base and box have no actuator, so
# tau_F = 0, and their velocity change also feels the prescribed joints through M_FP:
#
#     M_FF (u_free,F - u_F) = dt (tau_F - h_F) - M_FP (u+_P - u_P).

# %%
u_next = u.copy()
u_next[P] = (ref(t_settled + dt)[0] - q[P_q]) / dt          # prescribed joints: secant velocity
tau = np.zeros(model.nv)
M_FF = M[np.ix_(F, F)]
rhs = dt * (tau[F] - h[F]) - M[np.ix_(F, P)] @ (u_next[P] - u[P])
u_free = u_next.copy()
u_free[F] = u[F] + np.linalg.solve(M_FF, rhs)
print("u_free (head linear, box linear) [m/s]:", u_free[:3], u_free[17:20])

# %% [markdown]
# **8c. Contacts and J_c.** `find_contacts` collects every candidate whose gap is below the
# margin (10 mm), in a fixed order: robot-ground, robot-box, box corner-ground.
# `contact_jacobian` stacks the rows `[n, t1, t2]^T (J_A - J_B)` per contact, so that
# `J_c u` are the contact velocities (eq. (4)).

# %%
margin = stepper.s.margin
contacts = find_contacts(model, terms, margin)
J = contact_jacobian(chain, terms, contacts)
n_c = contacts.m
labels = [f"{model.body_names[b]}" if kind != 2 else f"box c{f}"
          for kind, b, f in zip(contacts.kind, contacts.body_A, contacts.feature)]
print(f"{n_c} candidate contacts, J_c is {J.shape[0]} x {J.shape[1]}")
for k in range(n_c):
    print(f"  {k:2d} {KINDS[contacts.kind[k]]:12s} {labels[k]:6s} gap = {1e3 * contacts.g[k]:6.3f} mm")

# %% [markdown]
# **8d. The Delassus matrix over the free coordinates** (eq. (5)). Only the free columns move
# under contact, `G = J_F M_FF^-1 J_F^T`, with J_F = J_c[:, F].
#
# **G is singular.** G is (3 n_c) x (3 n_c), 45 x 45 here, but it is a product through only 12
# free DoF, so `rank G <= 12`. Put another way, the 13 spheres rest on one plane, and the
# robot's shape is rigid over the step (its joints are prescribed). Whatever the sphere
# impulses are, they act on the robot only through their resultant force and moment, which
# is 6 numbers. The box's 4 corners act on its 6 DoF in the same way. Many impulse patterns
# therefore have no effect on the free coordinates: two box corners pushing tangentially
# towards each other, for example, or impulses whose generalized force lands only on the
# prescribed joint rows, where the servos absorb it. Without regularization the minimiser is
# not unique. `ContactQP` adds `eps 1` with eps = 1e-6 mean(diag G). This acts like a tiny
# uniform compliance: it picks the least-norm impulses among the equally good ones, and
# `QPInfo.cond_G` reports the condition number of `G + eps 1`.

# %%
M_FF_inv_JT = np.linalg.solve(M_FF, J[:, F].T)
G = J[:, F] @ M_FF_inv_JT
sv = np.linalg.svd(G, compute_uv=False)
eps_reg = 1e-6 * np.mean(np.diag(G))
rank_G = np.linalg.matrix_rank(G)
print(f"G: {G.shape}, rank {rank_G}, singular values 1-13: {sv[:13]}")
print(f"cond(G) = {sv[0] / sv[-1]:.1e} (numerically infinite: G is singular)")
print(f"cond(G + eps 1) = {(sv[0] + eps_reg) / eps_reg:.3e}, eps = {eps_reg:.2e}")

# %% [markdown]
# **8e. The free contact velocity**, `c = J_c u_free`, plus the gap term g_i / dt on the normal
# rows. A penetration (g_i < 0) is removed gently, at the rate beta g_i / dt with beta = 0.2.

# %%
c = J @ u_free
beta = stepper.s.beta
g_stab = np.where(contacts.g >= 0, contacts.g, beta * contacts.g)
c[0::3] += g_stab / dt
print("c_N [m/s]:", c[0::3])

# %% [markdown]
# **8f. Least action, eq. (6)**, with one friction coefficient per contact: model.mu = 1 on
# the ground and model.mu_robot_box = 0.5 between the robot and the box (none of the latter
# are active right now). We build the solver exactly as the stepper does, from its
# `StepSettings`.
#
# With `friction="fixed-point"`, the friction bound is mu times the p_N of the previous
# iterate, and the QP is solved again until p_N stops changing. At convergence this is exact
# Coulomb friction on the pyramid. The stepper allows at most `fp_max` iterates per step,
# because it starts each step from the previous step's impulses. If the iterates have not
# converged by then, the solver clips each p_T into the pyramid of its own p_N, and says so
# in `status`. Here we start **cold** (p = 0), as a fresh `Stepper` does.
#
# The `QPInfo` fields are: the status, the OSQP (ADMM) iterations summed over the iterates,
# the number of fixed-point iterates, the three KKT residuals of section 4, and cond(G + eps 1).

# %%
settings = stepper.s
mu_c = np.where(contacts.kind == ROBOT_BOX, model.mu_robot_box, model.mu)
qp = ContactQP(model.mu, settings.n_facets, settings.reg, friction=settings.friction, fp_max=settings.fp_max)
p, info = qp.solve(G, c, mu=mu_c)
print("mu per contact:", mu_c, f"  fp_max = {settings.fp_max}")
for field, value in info._asdict().items():
    print(f"  QPInfo.{field:20s} = {value}")

# %% [markdown]
# **The converged fixed point.** We let the same fixed point run up to 500 iterates and call
# its answer p*. This is the exact Coulomb solution on the pyramid, in these contact frames.
# For comparison, we also print what the stepper that ran the 300 steps reported on its last
# step. It was warm-started, and its t1 axes followed the slip.

# %%
p_star, info_star = ContactQP(model.mu, fp_max=500).solve(G, c, mu=mu_c)
print(f"p*: {info_star.status} after {info_star.fp_iterations} iterates")
print(f"max |p - p*| = {np.abs(p - p_star).max():.1e} N s  (max p* = {p_star.max():.4f} N s);"
      f" sum p_N / dt: {p[0::3].sum() / dt:.4f} N vs {p_star[0::3].sum() / dt:.4f} N")
print(f"running stepper, last settling step: '{res_last.qp.status}' after {res_last.qp.fp_iterations} iterate(s)")

# %% [markdown]
# When the status above says "not converged", the cold step stopped early. Its normal
# impulses are then close to p*, but a sliding contact may be left with friction a little
# inside the pyramid. Section 9 measures what that costs in eq. (2). A warm-started stepper
# that has been running does not have this problem.
#
# **8g. Velocity, position and joint torques after the step.**
# `u+_F = u_free,F + M_FF^-1 J_F^T p`. Positions advance by `integrate` (semi-implicit
# Euler: q+ = q (+) dt u+). The joint torques that the servos must supply follow from the
# joint rows of eq. (1): `tau = M (u+ - u) / dt + h - J_c^T p / dt`.
#
# We now compare with `Stepper(model).step` from the same state. We use a **fresh** stepper:
# the one that ran the 300 steps starts its QP from the previous impulses, and it turns each
# t1 along the previous slip (section 5). With the pyramid, that changes the friction of the
# sliding contacts. A fresh stepper has neither, exactly like our hand-built step.

# %%
u_next = u_free.copy()
u_next[F] += M_FF_inv_JT @ p
q_next = cr.integrate(model, q, u_next, dt)
tau_joints = (M @ (u_next - u) / dt + h - J.T @ p / dt)[P]
ref_step = Stepper(model).step(q, u, t_settled, ref)
print("same contacts:", ref_step.contacts.keys() == contacts.keys(), "  stepper status:", ref_step.qp.status)
print(f"max |p - p_stepper|   = {np.abs(p - ref_step.p).max():.1e} N s")
print(f"max |u+ - u+_stepper| = {np.abs(u_next - ref_step.qd).max():.1e},"
      f"  max |q+ - q+_stepper| = {np.abs(q_next - ref_step.q).max():.1e}")
print("joint torques [N m]:", tau_joints, "\n  stepper          :", ref_step.tau)

# %% [markdown]
# ## 9. Reading the impulses
# We read the converged p*. Per contact: the normal force p_N / dt, the friction use
# |p_T| / (mu p_N), and the slip speed |w_T| after the step. Then come the checks of
# section 4, on the real problem. Which sphere carries what is decided by the geometry: the
# tail sphere is the largest (57 mm radius, against 53.5 mm for the links), so the rigid
# C-shape rests on it and on two link spheres.
#
# Look at the friction use. The gait is ramping up, so the robot's shape changes during the
# step, and the distances between its three contact points change with it. They cannot all
# stay put: at least one contact must slide. Here all three slide slowly (a few mm/s), with
# friction on the pyramid's boundary, opposing the slip. The resting box sticks, with no
# friction at all.

# %%
w, comp, cone, stick, slip, inside = velocity_level_eq2(G, c, p_star, mu_c)
p_N, p_T, w_T = p_star[0::3], np.stack([p_star[1::3], p_star[2::3]], 1), np.stack([w[1::3], w[2::3]], 1)
active = p_N > 1e-9 * p_N.max()
state = np.where(~active, "open", np.where(inside, "stick", "slip"))
for k in np.flatnonzero(active):
    use = np.abs(p_T[k]).max() / (mu_c[k] * p_N[k])                # 1 = on the pyramid
    print(f"  {labels[k]:6s} f_N = {p_N[k] / dt:7.3f} N, |p_T|/(mu p_N) = {use:.3f},"
          f" |w_T| = {1e3 * np.linalg.norm(w_T[k]):.3f} mm/s  -> {state[k]}")
print(f"p*, eq. (2) numpy: comp {comp:.1e}, cone {cone:.1e}, stick {stick:.1e}, slip {slip:.1e} m/s")
print("p*, kkt_residuals: ", tuple(float(f"{r:.1e}") for r in kkt_residuals(G, c, p_star, mu_c, D4)))
print(f"p*: min p_N = {p_N.min():.1e} N s, min w_N = {w[0::3].min():.1e} m/s")
print("cold step p, eq. (2) numpy (comp, cone, stick, slip):",
      tuple(float(f"{r:.1e}") for r in velocity_level_eq2(G, c, p, mu_c)[1:5]))

# %% [markdown]
# **Total normal force against the weight.** Every contact here is with the ground. The
# normal is e_z, so the vertical force is the sum of the p_N / dt. The robot's three spheres
# carry its weight and the four box corners carry m_box g / 4 each.

# %%
f_N = p_N / dt
robot_part = f_N[contacts.kind == 0].sum()
box_part = f_N[contacts.kind == 2].sum()
print(f"robot: {robot_part:.3f} N vs m_robot g = {m_robot * grav:.3f} N")
print(f"box  : {box_part:.3f} N vs m_box g = {m_box * grav:.3f} N (per corner {f_N[contacts.kind == 2]})")
print(f"total: {f_N.sum():.3f} N vs weight {weight:.3f} N  (ratio {f_N.sum() / weight:.5f})")

# %% [markdown]
# **PGS on the real problem.** We run PGS on `G + eps 1`, the same matrix that OSQP minimises.
# PGS bounds friction by the current p_N, so it looks for the same Coulomb solution as p*.
# The impulses do **not** agree, because they are not unique (8d): PGS leaves a
# self-balancing pattern of tangential impulses on the box corners, with zero resultant. What
# is unique is what the impulses do: the contact velocities `w = G p + c`, and the generalized
# impulse `J_F^T p` on the 12 free coordinates (J_F has rank 12). These two must agree.

# %%
G_reg = G + eps_reg * np.eye(len(c))
p_pgs = projected_gauss_seidel(G_reg, c, mu_c, n_sweeps=1000)
w_pgs = G @ p_pgs + c
print(f"max |p* - p_PGS|           = {np.abs(p_star - p_pgs).max():.1e} N s  (not unique)")
print(f"max |w* - w_PGS|           = {np.abs(w - w_pgs).max():.1e} m/s")
print(f"max |J_F^T (p* - p_PGS)|   = {np.abs(J[:, F].T @ (p_star - p_pgs)).max():.1e}"
      f"  (max |J_F^T p*| = {np.abs(J[:, F].T @ p_star).max():.3f})")
print("PGS box-corner tangential impulses [N s]:\n", p_pgs.reshape(-1, 3)[contacts.kind == 2, 1:])

# %% [markdown]
# ## 10. Pictures
# Left: total vertical ground force over the first 0.3 s, divided by the weight, on a log
# scale (free fall on the box alone, touchdown spikes, rocking, rest). Middle: top view of
# the snake (its contact spheres), the box, and the active contacts of p*, with marker area
# proportional to the normal force. Right: normal force of p* per candidate contact.

# %%
fig, (ax_t, ax_top, ax_bar) = plt.subplots(1, 3, figsize=(15, 4.5))
ax_t.semilogy(1e3 * dt * np.arange(len(force_ratio)), force_ratio, lw=1)
ax_t.axhline(1.0, color="k", ls="--", lw=0.8, label="weight")
ax_t.axhline(m_box / (m_robot + m_box), color="C3", ls=":", lw=0.8, label="box weight only")
ax_t.set(xlabel="t [ms]", ylabel="sum of vertical ground forces / weight [-]", title="settling")
ax_t.legend()
sph = model.spheres
centers = terms.p[sph.body] + np.einsum("sij,sj->si", terms.R[sph.body], sph.center)
for centre, r in zip(centers, sph.radius):
    ax_top.add_patch(plt.Circle(centre[:2], r, fill=False, color="0.5"))
ax_top.plot(centers[:, 0], centers[:, 1], "-", color="0.5", lw=0.8)

# %%
box_corners = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]]) * model.boxes[0].half[:2]
box_R, box_p = terms.R[model.boxes[0].body], terms.p[model.boxes[0].body]
ax_top.plot(*(box_p[:2, None] + box_R[:2, :2] @ box_corners.T), color="C1", label="box")
for kind, colour in ((0, "C0"), (2, "C1")):
    sel = active & (contacts.kind == kind)
    ax_top.scatter(contacts.point_A[sel, 0], contacts.point_A[sel, 1], s=15 * f_N[sel], color=colour,
                   alpha=0.6, label=f"{KINDS[kind]} (area ~ f_N)")
ax_top.text(*centers[0, :2], " head", fontsize=8)
ax_top.text(*centers[-1, :2], " tail", fontsize=8)
ax_top.set(xlabel="x [m]", ylabel="y [m]", title=f"top view at t = {t_settled:.1f} s", aspect="equal")
ax_top.set_xlim(-0.7, 0.6)                          # room on the right for the legend
ax_top.legend(fontsize=8, loc="center right")
ax_bar.bar(range(n_c), f_N, color=["C1" if kd == 2 else "C0" for kd in contacts.kind])
ax_bar.set_xticks(range(n_c), [f"{lab}\n{s}" for lab, s in zip(labels, state)], fontsize=7, rotation=90)
ax_bar.set(ylabel="normal force p_N / dt [N]", title=f"{n_c} candidates, total {f_N.sum():.2f} N")
fig.tight_layout()

# %% [markdown]
# ## 11. What we checked
# * Ball at rest, sliding fast, sliding slowly, landing, hovering: the OSQP impulses equal the
#   hand solutions (`m g dt`, `-mu m g dt` along the slip, `-m v` when sticking, `-m c_N`
#   when landing, 0 when hovering), up to the 1e-6 regularization.
# * The optimality conditions are eq. (2) at the velocity level (Signorini, stick, slip). They
#   are computed with plain numpy and agree with `kkt_residuals`.
# * An independent projected Gauss-Seidel gives the same ball impulses. On COBRA it gives the
#   same contact velocities and generalized impulses, but different impulses, because G is
#   singular (rank 12 for 45 rows).
# * COBRA: the first steps load only the box (the gap term). After settling, the vertical
#   ground force equals the weight. The hand-built step reproduces a fresh `Stepper.step`
#   (impulses, u+, q+ and the joint torques), including its solver status. G has rank 12
#   for 45 rows, and `QPInfo.cond_G` is the condition number of G + eps 1.
# * The converged fixed point p* satisfies eq. (2) to the solver tolerances. A cold step that
#   stops after `fp_max` iterates is close to p*, but its friction is only approximately Coulomb.

# %%
REG = 1e-6
for p_osqp, p_hand in ((p_rest, p_rest_hand), (p_fast, p_fast_hand), (p_slow, p_slow_hand),
                       (p_land, np.array([-m * c_land[0], 0.0, 0.0])), (p_hover, np.zeros(3))):
    np.testing.assert_allclose(p_osqp, p_hand, rtol=0, atol=10 * REG * m * max(1.0, abs(c_land[0])),
                               err_msg="ball: OSQP vs hand")
np.testing.assert_allclose(G_ball @ p_fast + c_fast, [0, v_fast - mu * grav * dt, 0], atol=1e-6, err_msg="slip speed")
np.testing.assert_allclose((G_ball @ p_slow + c_slow)[1:], 0.0, atol=1e-6, err_msg="slow slip sticks")
np.testing.assert_allclose(np.abs(p_diag[1:]), mu * p_diag[0], rtol=1e-5, err_msg="pyramid corner")
for c_toy, p_toy in ((c_rest, p_rest), (c_fast, p_fast), (c_slow, p_slow)):
    _, comp_toy, cone_toy, stick_toy, slip_toy, _ = velocity_level_eq2(G_ball, c_toy, p_toy, mu)
    np.testing.assert_allclose([comp_toy, cone_toy, stick_toy], kkt_residuals(G_ball, c_toy, p_toy, mu, D4),
                               rtol=1e-9, atol=1e-18, err_msg="ball: numpy eq. (2) = kkt_residuals")
    assert max(comp_toy, cone_toy) < 1e-9 and max(stick_toy, slip_toy) < 1e-6, "ball: eq. (2) holds"
    np.testing.assert_allclose(projected_gauss_seidel(G_ball, c_toy, mu), p_toy, atol=10 * REG * m,
                               err_msg="ball: PGS vs OSQP")

# %% [markdown]
# COBRA: the first steps, the weight, the rank, the match with `Stepper.step`, eq. (2) and
# PGS. The tolerances come from the solver settings: OSQP stops at 1e-7 on its residuals,
# and the regularization moves w by eps |p|.

# %%
np.testing.assert_allclose(force_ratio[0], m_box / (m_robot + m_box), rtol=1e-4, err_msg="step 0: box only")
assert landing > 5, "the robot falls freely for a few steps"
np.testing.assert_allclose(force_ratio[-1], 1.0, atol=0.01, err_msg="settled: ground carries the weight")
np.testing.assert_allclose(f_N.sum(), weight, rtol=0.01, err_msg="p*: total normal force")
np.testing.assert_allclose(p[0::3].sum() / dt, weight, rtol=0.01, err_msg="cold step: total normal force")
np.testing.assert_allclose(box_part, m_box * grav, rtol=1e-3, err_msg="box weight")
assert rank_G == 12 and G.shape == (3 * n_c, 3 * n_c) and 3 * n_c > 12, "G singular: rank = free DoF"
np.testing.assert_allclose(info.cond_G, (sv[0] + eps_reg) / eps_reg, rtol=1e-6, err_msg="QPInfo.cond_G")
assert info.status.startswith("solved"), info.status
assert ref_step.contacts.keys() == contacts.keys()
np.testing.assert_allclose(p, ref_step.p, rtol=0, atol=1e-6 * np.abs(p).max(), err_msg="p vs Stepper.step")
np.testing.assert_allclose(u_next, ref_step.qd, rtol=0, atol=1e-6, err_msg="u+ vs Stepper.step")
np.testing.assert_allclose(q_next, ref_step.q, rtol=0, atol=1e-9, err_msg="q+ vs Stepper.step")
np.testing.assert_allclose(tau_joints, ref_step.tau, rtol=0, atol=1e-3, err_msg="tau vs Stepper.step")

# %%
tol_w = 10 * (eps_reg * np.abs(p_star).max() + 1e-7 * (1 + np.abs(c).max()))
assert info_star.status == "solved", info_star.status
np.testing.assert_allclose([comp, cone, stick], kkt_residuals(G, c, p_star, mu_c, D4), rtol=1e-9, atol=1e-18,
                           err_msg="COBRA: numpy eq. (2) = kkt_residuals")
assert comp <= tol_w * np.abs(p_star).max() and cone <= 1e-6 and max(stick, slip) <= tol_w, "eq. (2) on COBRA"
assert p_N.min() >= -1e-9 * p_N.max() and w[0::3].min() >= -tol_w, "no pull, no approach"
np.testing.assert_allclose(w_pgs, w, atol=tol_w, err_msg="PGS vs OSQP: contact velocities")
np.testing.assert_allclose(J[:, F].T @ p_pgs, J[:, F].T @ p_star, atol=1e-6 * np.abs(J[:, F].T @ p_star).max(),
                           err_msg="PGS vs OSQP: generalized impulse")
print("All one-step contact checks passed.")
plt.show()
