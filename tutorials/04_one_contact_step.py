# %% [markdown]
# # 04 - One contact step by hand
# **Goal:** take one velocity-level time step with contact by hand: the free velocity, the
# Delassus matrix G, the least-action QP for the impulses (solved with OSQP) and its optimality
# conditions; then the compliant contact law and Coulomb's friction circle; first on a ball on
# the plane, where every number is known, then on COBRA lying on the ground, where we rebuild
# one call of `cobra_ref.step.step` block by block.
# **Paper:** [COBRA] eq. (1) (equations of motion), eq. (2) (the contact law, at the velocity
# level), eq. (5) (Delassus matrix G and free term c), eq. (6) (least action).
# **Run:** `python tutorials/04_one_contact_step.py` (a few seconds; writes `04_friction_square.png`
# and `04_cobra_step.png`)

# %%
import os
import pathlib

import matplotlib.pyplot as plt
import numpy as np

import cobra_ref as cr
from cobra_ref import compliance
from cobra_ref.contact import KINDS, contact_jacobian, find_contacts
from cobra_ref.fast.stepper import FastStepper
from cobra_ref.gaits import RollingGait
from cobra_ref.least_action import (LeastAction, coulomb_split, delassus, kkt_residuals, natural_residual,
                                    project_disk, solve_least_action, turn, turn_tangents)
from cobra_ref.qp import solve_box_qp
from cobra_ref.start import initial_state
from cobra_ref.step import StepSettings, joint_coordinates, least_action_problem, servo_start, step

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)
np.set_printoptions(precision=5, suppress=True)

# %% [markdown]
# ## 1. One time step in one page
# Eq. (1), `M u' + h = tau + J^T f`, over one step dt with M and h frozen at the start of the
# step, and with impulses x = f dt (semi-implicit Euler):
#
#     M (u+ - u) = dt (tau - h) + J^T x,         q+ = q (+) dt u+.
#
# Split u+ into the velocity without contact and the kick of the impulses:
#
#     u+ = u_free + M^-1 J^T x,                  u_free = u + dt M^-1 (tau - h).
#
# The rows J (three per contact: normal n, tangents t1, t2) then move with `J u+ = G x + J u_free`,
# where `G = J M^-1 J^T` is the Delassus matrix of eq. (5): the inverse inertia the contacts see.
# Each row also gets a *law*: a compliance R >= 0 and an offset b (section 4), and eq. (6)
# picks the impulses of least action:
#
#     min_x  1/2 x^T (G + R) x + x^T c,   c = J u_free + b,
#     s.t.   p_N >= 0,  ||p_T|| <= mu p_N   (Coulomb's circle, per contact).
#
# Its optimality conditions are the contact law, eq. (2), at the velocity level (section 3).

# %% [markdown]
# ## 2. The toy: a ball resting on the plane
# A ball of mass m, of which we keep the 3 translations (its spin would only add r^2 / I to
# the tangential diagonal of G): `M = m 1`, gravity in `h = (0, 0, m g)`, no actuator. The
# contact frame is n = e_z, t1 = e_x, t2 = e_y, so the rows of J are these three vectors and
#
#     G = J M^-1 J^T = 1 / m (the 3 x 3 identity over m).
#
# The rigid law of eq. (2)-(6) as written has R = 0 and `b_N = g_gap / dt` on the normal row
# (g_gap: the gap now), so that the normal row's `w_N = (G x + c)_N` is the gap after the step
# divided by dt: `w_N >= 0` lets a gap close within the step, never beyond. (cobra_ref's
# `contact="rigid"` adds a small compliance R = 1e-2 G_ii and removes a penetration gradually,
# `compliance.RIGID_COMPLIANCE` and `BAUMGARTE`; we leave both out here.)

# %%
m, grav, dt, mu = 1.0, 9.81, 1e-3, 0.5  # kg, m/s^2, s, -
M_ball, h_ball = m * np.eye(3), np.array([0.0, 0.0, m * grav])
J_ball = np.array([[0.0, 0.0, 1.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])  # rows n, t1, t2
G_ball = J_ball @ np.linalg.solve(M_ball, J_ball.T)
print("G = J M^-1 J^T =\n", G_ball)


def ball_c(u, gap=0.0):
    """c = J u_free + b for the ball with world velocity u and gap `gap` (rigid law: b_N = gap / dt)."""
    u_free = u + dt * np.linalg.solve(M_ball, -h_ball)  # u + dt M^-1 (tau - h), tau = 0
    return J_ball @ u_free + np.array([gap / dt, 0.0, 0.0])


# %% [markdown]
# **By hand.** At rest on the plane, `u_free = (0, 0, -g dt)` and `c = (-g dt, 0, 0)`. Without
# constraints the minimiser is `x = -G^-1 c = (m g dt, 0, 0)`; it pushes (p_N > 0) and has no
# friction, so it is feasible: it is the solution, and `w = G x + c = 0`.
#
# **OSQP.** `solve_box_qp(H, c, lo, hi)` solves `min 1/2 x^T H x + c^T x, lo <= x <= hi`. A box
# holds p_N >= 0, and friction inside the square `|p_t1|, |p_t2| <= mu pbar_N`, where pbar_N is
# a guess of the normal impulse (here m g dt; section 5 shows how cobra_ref finds it).
# (OSQP says "Polishing not needed" when no bound is active: x is then the unconstrained
# minimiser.)

# %%
r_ball = mu * m * grav * dt  # friction bound mu pbar_N [N s]
lo, hi = np.array([0.0, -r_ball, -r_ball]), np.array([np.inf, r_ball, r_ball])
c_rest = ball_c(np.zeros(3))
sol_rest = solve_box_qp(G_ball, c_rest, lo, hi)
print("c =", c_rest, "m/s")
print("x =", sol_rest.x, "N s,  by hand:", [m * grav * dt, 0.0, 0.0])
print("w = G x + c =", G_ball @ sol_rest.x + c_rest, "m/s;  OSQP:", sol_rest.status)

# %% [markdown]
# ## 3. The optimality conditions are eq. (2)
# For a box QP, x is optimal exactly when `w + y = 0` with `w = G x + c` and multipliers y that
# are zero on a free row, <= 0 on a row at its lower bound and >= 0 at its upper bound (OSQP's
# convention, `BoxQPSolution.y`). On the contact rows this reads:
#
# * **Signorini** (normal row): `0 <= p_N  _|_  w_N >= 0`: no pull, no approach, no push on a
#   contact that opens;
# * **stick**: friction strictly inside its bound gives `w_T = 0`;
# * **slip**: friction on its bound opposes the slip w_T.
#
# Three cases: the ball at rest; hovering 5 mm up at rest (`c_N = 5 m/s - g dt > 0`: nothing);
# landing from 0.5 mm at 1 m/s (it gets `p_N = -m c_N` and ends the step with a zero gap).

# %%
def eq2_by_hand(G, c, sol):
    """(w, stationarity |w + y|, min p_N, min w_N, |p_N w_N|, |w_T| if friction is inside its bound)."""
    x, y = sol.x, sol.y
    w = G @ x + c
    inside = np.all(np.abs(x[1:]) < hi[1:] * (1 - 1e-6))
    stick = np.abs(w[1:]).max() if inside else 0.0
    return w, np.abs(w + y).max(), x[0], w[0], abs(x[0] * w[0]), stick


cases = {"rest": c_rest, "hover": ball_c(np.zeros(3), 5e-3), "landing": ball_c(np.array([0, 0, -1.0]), 0.5e-3)}
sols = {name: solve_box_qp(G_ball, c, lo, hi) for name, c in cases.items()}
for name, c in cases.items():
    w, stat, p_N, w_N, comp, stick = eq2_by_hand(G_ball, c, sols[name])
    print(f"{name:8s} p = {sols[name].x}  y = {sols[name].y}  w = {w}")
    print(f"         |w + y| = {stat:.1e}, p_N = {p_N:.5f} >= 0, w_N = {w_N:.5f} >= 0, |p_N w_N| = {comp:.1e},"
          f" stick |w_T| = {stick:.1e}")

# %% [markdown]
# `cobra_ref.least_action.kkt_residuals(problem, x)` measures the same conditions on a
# `LeastAction(H, c, mu, lo, hi, stiction_velocity)` problem (H = G + R; `lo`, `hi` the servo
# rows' bounds, none here; `stiction_velocity` 0 for the rigid law): `complementarity`
# max |p_N w_N|, `cone_residual` (friction outside the circle) and `coulomb_residual` (stick
# without slip, or slip against mu p_N).

# %%
no_servo = np.zeros(0)
for name, c in cases.items():
    ball_problem = LeastAction(G_ball, c, np.array([mu]), no_servo, no_servo, 0.0)
    print(f"{name:8s}", {k: float(f"{v:.1e}") for k, v in kkt_residuals(ball_problem, sols[name].x).items()})

# %% [markdown]
# ## 4. The compliant law: a spring-damper row
# The paper's "high-fidelity" ground is a spring-damper, `f = -k g_gap - d g_gap'` while it
# pushes. Over one step the damper acts on the velocity after the step, w, and the spring on
# the gap at `g_gap + theta dt w`; with x = f dt it becomes a row law `w + R x + b = 0`
# (`cobra_ref/compliance.py`, assumption A12):
#
#     R = 1 / (dt (theta k dt + d)),      b = k g_gap / (theta k dt + d),
#     theta = max(0, 1 - d / (k dt))      (compliance.contact_theta)
#
# theta = 1 would take the spring at the step's end, which adds a numerical damping k dt: as
# much as d itself at dt = 1 ms. theta = 0 takes it at the step's start and adds none; it is
# used up to dt = d / k (1 ms here), and above, theta grows just enough that a light contact's
# gap does not overshoot (tests/test_compliance.py shows the step stable for every mass).
# On the robot (section 6) the damper also leans back on the rate before the step, w_0:
# `theta_d w + (1 - theta_d) w_0` with `theta_d = compliance.contact_theta_d = 1 / (1 - exp(-h)) - 1 / h`,
# h = d dt / m_c: the weight that decays a contact of mass m_c by exactly exp(-h) per step, as the
# damper does, and -> 1/2 as dt -> 0 (second order). Here, for the ball's rows by hand, theta_d = 1.
#
# At rest (w = 0) under its weight (x = m g dt) the row gives `R m g dt = -b`, that is
# `g_gap = -m g / k`: the ball sinks by the **static sag** m g / k. We check it with
# k = 1e6 N/m, d = 1e3 N s/m (COBRA's ground): the QP with H = G + R at that gap returns the
# weight exactly, and w = 0.

# %%
k, d = 1e6, 1e3  # N/m, N s/m
sag = m * grav / k
theta = compliance.contact_theta(k, d, dt)
R_N, b_N = compliance.spring_damper(k, d, dt, -sag, theta=theta)
print(f"theta = {theta:g} at dt = {dt * 1e3:g} ms: R = {R_N:.5e} (by hand {1 / (dt * (theta * k * dt + d)):.5e}),"
      f"  b = {b_N:.5e} (by hand {-k * sag / (theta * k * dt + d):.5e})")
H_sag = G_ball + np.diag([R_N, 0.0, 0.0])
c_sag = ball_c(np.zeros(3)) + np.array([b_N, 0.0, 0.0])  # J u_free + b, compliant b on the normal row
sol_sag = solve_box_qp(H_sag, c_sag, lo, hi)
print(f"at the sag {sag * 1e6:.2f} um: p_N = {sol_sag.x[0]:.6e} N s (m g dt = {m * grav * dt:.6e}),"
      f" w = {H_sag @ sol_sag.x + c_sag}")

# %% [markdown]
# Dropped from 1 mm above the plane, the ball lands on the spring, rings (damping ratio
# `d / (2 sqrt(k m)) = 0.5`) and settles at that sag. One normal row per step, whose QP
# `min 1/2 H p^2 + c p, p >= 0` (H = 1/m + R) is solved by hand: `p = max(0, -c / H)`.

# %%
gap_drop, v_drop = 1e-3, 0.0
for _ in range(300):
    R_drop, b_drop = compliance.spring_damper(k, d, dt, gap_drop, theta=theta)
    c_drop = v_drop - grav * dt + b_drop
    p_drop = max(0.0, -c_drop / (1 / m + R_drop))
    v_drop = v_drop - grav * dt + p_drop / m
    gap_drop += dt * v_drop
print(f"after 0.3 s: gap = {gap_drop * 1e6:.3f} um, -m g / k = {-sag * 1e6:.3f} um,"
      f" p_N = {p_drop:.6e} N s (m g dt = {m * grav * dt:.6e})")

# %% [markdown]
# ## 5. Coulomb's circle by a turned square
# Now the ball slides at speed v along a heading alpha = 30 deg to t1: `c = (-g dt, v cos alpha,
# v sin alpha)`. Coulomb's law wants friction `mu p_N = mu m g dt` **against** the slip, and
# the ball to keep sliding at `v - mu g dt` (we take v = 3 mu g dt, slow enough for a picture).
# The square `|p_t1|, |p_t2| <= r` of section 2 gets it wrong: both components saturate, so
# friction points at 45 deg (plus 180) and is sqrt(2) times too large.

# %%
alpha, v_slide = np.radians(30.0), 3 * mu * grav * dt
e_slip = np.array([np.cos(alpha), np.sin(alpha)])
c_slide = ball_c(np.array([*(v_slide * e_slip), 0.0]))
x_square = solve_box_qp(G_ball, c_slide, lo, hi).x
heading = np.degrees(np.arctan2(x_square[2], x_square[1]))
print(f"plain square: p_T = {x_square[1:]}, |p_T| / (mu p_N) = {np.hypot(*x_square[1:]) / (mu * x_square[0]):.4f},"
      f" heading {heading:.1f} deg (Coulomb: {np.degrees(alpha) - 180:.1f} deg)")

# %% [markdown]
# **Turn the square.** Turn the tangent frame by theta so that t1' points along the friction,
# `theta = alpha + 180 deg`: `turn(c, theta, m)` gives c' = Q^T c, `turn_tangents(H, theta, m)`
# gives Q^T H Q (m = 1 contact here). The square in the turned frame still contains the
# circle and touches it at `+-r t1'`. Its minimiser lands there, on the circle, so it is also
# the minimiser over the (smaller) circle: the exact Coulomb answer. Turn back with -theta.

# %%
theta = np.array([alpha + np.pi])
sol_turned = solve_box_qp(turn_tangents(G_ball, theta, 1), turn(c_slide, theta, 1), lo, hi)
x_turned = turn(sol_turned.x, -theta, 1)
x_exact = np.array([m * grav * dt, *(-mu * m * grav * dt * e_slip)])
print("turned square: p =", x_turned, "\n by hand:      p =", x_exact)
print("slip after the step:", (G_ball @ x_turned + c_slide)[1:], " by hand", (v_slide - mu * grav * dt) * e_slip)

# %% [markdown]
# **The natural residual.** How do we know a friction impulse is Coulomb's? Let
# `z = p_T - w_T / a` (a = the tangential diagonal of H, here 1/m): where friction would go
# without a bound. Coulomb's friction is z projected onto the disk of radius mu p_N, so
#
#     residual = |p_T - P_{mu p_N}(z)| / p_N
#
# is 0 exactly for Coulomb's answer (stick: z inside, p_T = z; slide: p_T = mu p_N z / |z|).
# The plain square leaves a large residual; the turned square, none.

# %%
for name, x in (("plain square", x_square), ("turned square", x_turned)):
    w_T = (G_ball @ x + c_slide)[1:]
    z_T = x[1:] - w_T / G_ball[1, 1]
    by_hand = np.linalg.norm(x[1:] - project_disk(z_T[None], np.array([mu * x[0]]))[0]) / x[0]
    p_N, p_T, z = coulomb_split(x, G_ball @ x + c_slide, G_ball, 1)
    print(f"{name:13s}: z = {z_T}, residual by hand {by_hand:.2e}, natural_residual"
          f" {natural_residual(p_N, p_T, z, p_N, np.array([mu])):.2e}")

# %% [markdown]
# **The friction fixed point.** We knew theta and pbar_N = m g dt here. `solve_least_action`
# finds them: from an iterate x it guesses (pbar_N, theta) (by Newton's method on Coulomb's
# exact conditions: which contacts slide, which stick), solves the turned box QP with OSQP,
# and stops when the natural residual is below 1e-6 max p_N. From zero (a cold start) its
# first QP has no friction (pbar_N = 0: a guess may at most triple the iterate's normal
# impulses, and zero cannot grow), the second is exact. Started near the answer, as `step`
# starts from the previous step's impulses, one QP is enough.

# %%
slide_problem = LeastAction(G_ball, c_slide, np.array([mu]), no_servo, no_servo, 0.0)
x_fp, info_fp = solve_least_action(slide_problem)
print("cold start: p =", x_fp, info_fp)
x_warm, info_warm = solve_least_action(slide_problem, 0.9 * x_exact)
print("warm start: p =", x_warm, info_warm)
print("kkt_residuals:", kkt_residuals(slide_problem, x_fp))

# %% [markdown]
# The picture: the friction plane (p_t1, p_t2) with the circle of radius mu p_N, the plain and
# the turned squares, where friction would go without a bound (z), and the two answers.

# %%
fig, ax = plt.subplots(figsize=(6, 6))
s = np.linspace(0, 2 * np.pi, 200)
ax.plot(1e3 * r_ball * np.cos(s), 1e3 * r_ball * np.sin(s), "k", label="circle ||p_T|| = mu p_N")
corners = 1e3 * r_ball * np.array([[1, 1], [-1, 1], [-1, -1], [1, -1], [1, 1]])
Q = np.array([[np.cos(theta[0]), -np.sin(theta[0])], [np.sin(theta[0]), np.cos(theta[0])]])
ax.plot(*corners.T, "C0--", label="plain square")
ax.plot(*(Q @ corners.T), "C1--", label="square turned by theta")
ax.plot(*(-1e3 * m * v_slide * e_slip), "kx", label="z: friction without a bound")
ax.plot(*(1e3 * x_square[1:]), "C0o", label="plain square's answer")
ax.plot(*(1e3 * x_turned[1:]), "C1o", label="turned square = Coulomb")
ax.set(xlabel="p_t1 [mN s]", ylabel="p_t2 [mN s]", aspect="equal", title="one sliding contact, slip at 30 deg")
ax.legend(fontsize=7, loc="upper left")
fig.tight_layout()
fig.savefig(OUT / "04_friction_square.png", dpi=120)

# %% [markdown]
# ## 6. Now the robot: COBRA lying on the ground
# `cobra_model()` has the head (floating base), 11 joints and the box as a second free body:
# nv = 23. `initial_state(model, RollingGait())` lays the robot in the gait's t = 0 shape (a
# flat C) beside the box and lets the scene settle (0.3 s for this shape) with the joints
# holding it, so every sphere that carries weight already rests on the ground. The default
# `StepSettings()`: dt = 1 ms, the compliant contact, the position servo, a 1 cm search margin.

# %%
model, ref, settings = cr.cobra_model(), RollingGait(), StepSettings()
q, qd = initial_state(model, ref, settings)
print(settings)
print(f"nq = {model.nq}, nv = {model.nv}, largest speed after settling {np.abs(qd).max():.1e}")
res = step(model, q, qd, 0.0, ref, settings)
print("step():", res.info)

# %% [markdown]
# That one call did blocks 1-7 of `cobra_ref/step.py`. We redo them. **Blocks 1-3**: M and h
# (tutorial 02); with the position servo every coordinate is free, and `u_free = u - dt M^-1 h`.
# (h's velocity-product terms are evaluated at the step's midpoint velocity w, extrapolated
# from the last step's change, `step.midpoint_velocity`; on a first step w is u itself.)

# %%
M, h = cr.crba(model, q), cr.bias_force(model, q, qd)
u_free = qd + np.linalg.solve(M, -dt * h)
print("u_free, head linear [m/s]:", u_free[:3], "  box linear:", u_free[-6:-3])

# %% [markdown]
# **Block 4**: the candidate contacts (gap below the margin) and J_c (tutorial 03). Some carry
# weight (gap < 0: the ground is compressed by a few um), some hover within the margin.

# %%
contacts = find_contacts(model, q, settings.margin)
J_c = contact_jacobian(model, q, contacts)
labels = [model.body_names[b] if kind != 2 else f"box c{f}"
          for kind, b, f in zip(contacts.kind, contacts.body_A, contacts.feature)]
for i in range(contacts.m):
    print(f"  {i:2d} {KINDS[contacts.kind[i]]:12s} {labels[i]:6s} gap = {1e6 * contacts.g[i]:9.2f} um")

# %% [markdown]
# **Block 5**: the rows `J = [J_c; J_servo]`, one servo row per joint (a unit row on its rate),
# and the Delassus matrix over all 23 coordinates. G has 3 m + 11 rows but only 23 columns
# behind it, so it is singular: the compliance R of the rows makes the problem well posed.

# %%
joints = joint_coordinates(model)
J = np.vstack([J_c, np.eye(model.nv)[joints.v]])
G, Minv_JT = delassus(J, M)
print(f"J: {J.shape}, G: {G.shape}, rank G = {np.linalg.matrix_rank(G)}")
q_ref, qd_ref, _ = ref(0.0)  # the joints' reference at the step's start, which the servo follows
w_start = J_c[0::3] @ qd  # the contacts' normal rates before the step (the compliant damper reads them below 1 ms)
problem = least_action_problem(model, G, J @ u_free, contacts, settings, servo_start(joints, q, qd, (q_ref, qd_ref)),
                               w_start)
R_rows, b_rows = np.diag(problem.H - G), problem.c - J @ u_free

# %% [markdown]
# Each row's R and b, by hand: the normal rows are the spring-damper of section 4 on the gap;
# the servo rows are the same spring-damper on the joint error at the step's start,
# `e = q - q_ref(t)`, with `kp, kd`: the spring at the start (theta = 0 at 1 ms) and the damper on
# the mean rate `theta_d u+ + (1 - theta_d) u` against `qd_ref(t)`, with
# `theta_d = max(1/2, 1 - I / (kd dt))` and `I = 1 / G_ii` the inertia the joint's row sees:
# `R = 1 / (dt theta_d kd)`, `b = (kp e + (1 - theta_d) kd u - kd qd_ref) / (theta_d kd)`
# (assumption A7), and the servo's impulse is bounded by `tau_max dt`. The friction rows get
# their compliance from the stick-slip law inside the fixed point.

# %%
theta = compliance.contact_theta(k, d, dt)
# the damper's weight by exponential fitting, h = d dt / m_c with m_c = 1 / G_ii (section 4)
h = d * dt * np.diag(G)[0:3 * contacts.m:3]
theta_dN = 1 / (1 - np.exp(-h)) - 1 / h
g_lo = contacts.g - (1 - theta_dN) * dt * w_start  # the gap at the start of the step's window
penetrating = theta * k * dt + theta_dN * d  # a contact that penetrates at the step's start
R_N_hand = np.where(contacts.g > 0, 1 / (theta_dN * d * dt), 1 / (dt * penetrating))
b_N_hand = np.where(contacts.g > 0, contacts.g / (theta_dN * dt),
                    (k * contacts.g + d * (contacts.g - np.minimum(g_lo, 0)) / dt) / penetrating)
kp, kd = model.servo_kp, model.servo_kd
theta_d = np.maximum(0.5, 1 - 1 / (np.diag(G)[3 * contacts.m:] * kd * dt))
R_s_hand = 1 / (dt * theta_d * kd)
b_s_hand = (kp * (q[joints.q] - q_ref) + (1 - theta_d) * kd * qd[joints.v] - kd * qd_ref) / (theta_d * kd)
n_c = 3 * contacts.m
print("normal rows: R", R_rows[0:n_c:3][:2], "... by hand", R_N_hand, "| b [m/s]", b_rows[0:n_c:3][:3], "...")
print("servo rows : R", R_rows[n_c:][:2], "... by hand", R_s_hand[:2], "| bounds +-", problem.hi[:2], "N m s ...")

# %% [markdown]
# **Block 6**: the impulses, with Coulomb's circle by the friction fixed point (section 5).
# `step` started it from the previous step's impulses; without a previous step, from zero.
# **Block 7**: `u+ = u_free + M^-1 J^T x`, the servo torques `tau = x_servo / dt`, and
# `q+ = q (+) dt u+`. All equal to what `step` returned.

# %%
x, info = solve_least_action(problem)
u_next = u_free + Minv_JT @ x
tau = x[n_c:] / dt
q_next = cr.integrate(model, q, u_next, dt)
mine_theirs = {"p": (x[:n_c], res.p), "u+": (u_next, res.qd), "tau": (tau, res.tau), "q+": (q_next, res.q)}
for name, (mine, theirs) in mine_theirs.items():
    print(f"max |{name:3s} by hand - step()| = {np.abs(mine - theirs).max():.1e}")
print("joint torques [N m]:", tau)

# %% [markdown]
# **Reading the impulses.** Each compressed contact (gap < 0) pushes with `f_N = p_N / dt`,
# which for a spring-damper at rest is `-k g_gap` (its rate is tiny after settling); the
# contacts that hover carry nothing (to OSQP's rounding); the ground carries the whole weight
# to within 1 % (settling stops once nothing moves faster than 1 cm/s, `start.SETTLE_SPEED`; the
# spring-damper still rings a little); eq. (2) holds to the solver's tolerance.

# %%
f_N = x[0:n_c:3] / dt
weight = sum(model.mass) * grav
loaded = contacts.g < 0
print("f_N [N]      :", f_N[loaded])
print("-k g_gap [N] :", -k * contacts.g[loaded])
print(f"hovering contacts: largest f_N = {f_N[~loaded].max():.1e} N")
print(f"sum f_N = {f_N.sum():.4f} N, weight = {weight:.4f} N")
print("kkt_residuals:", res.residuals)

# %% [markdown]
# **The fast stepper.** `FastStepper(model, settings).step` (what `simulate` uses) takes the same
# step with batched dynamics and contacts and its own certified QP solves. From the same state:

# %%
fast = FastStepper(model, settings).step(q, qd, 0.0, ref)
for name in ("p", "qd", "q", "tau"):
    print(f"max |FastStepper - step()| in {name:3s} = {np.abs(getattr(fast, name) - getattr(res, name)).max():.1e}")
print("FastStepper:", fast.info)

# %% [markdown]
# The picture: the normal force of every candidate contact, and the spring's `-k g_gap`.

# %%
fig, ax = plt.subplots(figsize=(8, 3.5))
ax.bar(range(contacts.m), f_N, color=["C1" if kd_ == 2 else "C0" for kd_ in contacts.kind], label="p_N / dt")
ax.plot(range(contacts.m), np.maximum(-k * contacts.g, 0.0), "k_", ms=14, label="-k g_gap")
ax.set_xticks(range(contacts.m), labels, fontsize=7, rotation=90)
ax.set(ylabel="normal force [N]", title=f"COBRA at rest: {contacts.m} candidates, total {f_N.sum():.2f} N")
ax.legend()
fig.tight_layout()
fig.savefig(OUT / "04_cobra_step.png", dpi=120)

# %% [markdown]
# ## 7. What we checked
# * The ball: G = 1/m; OSQP's impulses equal the hand solutions (rest, hover, landing); the
#   conditions of eq. (2) hold by hand and in `kkt_residuals`; the compliant row's R and b are
#   the spring-damper's and the ball rests at the sag m g / k.
# * Coulomb's circle: the plain square gives sqrt(2) mu p_N at 45 deg; the square turned along
#   the friction gives the exact answer, whose natural residual is 0; `solve_least_action`
#   finds it by itself.

# %%
np.testing.assert_allclose(G_ball, np.eye(3) / m, atol=1e-15)
np.testing.assert_allclose(sols["rest"].x, [m * grav * dt, 0, 0], atol=1e-9)
np.testing.assert_allclose(sols["hover"].x, 0.0, atol=1e-9)
np.testing.assert_allclose(sols["landing"].x[0], -m * cases["landing"][0], rtol=1e-7)
for name, c in cases.items():
    w, stat, p_N, w_N, comp, stick = eq2_by_hand(G_ball, c, sols[name])
    assert stat < 1e-7 and p_N >= -1e-12 and w_N >= -1e-7 and comp < 1e-9 and stick < 1e-7, name
    ball_problem = LeastAction(G_ball, c, np.array([mu]), no_servo, no_servo, 0.0)
    assert max(kkt_residuals(ball_problem, sols[name].x).values()) < 1e-6, name
np.testing.assert_allclose([R_N, b_N], [1 / (dt * (theta * k * dt + d)), -k * sag / (theta * k * dt + d)], rtol=1e-12)
np.testing.assert_allclose(sol_sag.x[0], m * grav * dt, rtol=1e-7)
np.testing.assert_allclose(gap_drop, -sag, rtol=1e-2)
np.testing.assert_allclose(np.hypot(*x_square[1:]), np.sqrt(2) * r_ball, rtol=1e-7)
np.testing.assert_allclose(x_turned, x_exact, atol=1e-9)
np.testing.assert_allclose(x_fp, x_exact, atol=1e-9)
np.testing.assert_allclose(x_warm, x_exact, atol=1e-9)
assert info_fp.converged and info_fp.iterations <= 2 and info_warm.converged and info_warm.iterations == 1

# %% [markdown]
# * COBRA: the rows' compliances and offsets are the spring-damper's (ground) and the servo's
#   (joints); the hand-built blocks reproduce `step` (impulses, u+, q+, torques); the ground
#   carries the weight with the spring-damper's `f_N = -k (g + theta dt w_N) - d (theta_d w_N +
#   (1 - theta_d) w_0)`, nearly the static `-k g` since the robot has settled; eq. (2) holds; the
#   fast stepper takes the same step.

# %%
np.testing.assert_allclose(R_rows[0:n_c:3], R_N_hand, rtol=1e-12)
np.testing.assert_allclose(b_rows[0:n_c:3], b_N_hand, rtol=1e-12, atol=1e-15)
np.testing.assert_allclose(R_rows[n_c:], R_s_hand, rtol=1e-12)
np.testing.assert_allclose(b_rows[n_c:], b_s_hand, rtol=1e-12, atol=1e-15)
np.testing.assert_allclose(problem.hi, joints.tau_max * dt, rtol=1e-15)
assert res.contacts.keys() == contacts.keys() and info.converged
for name, tol in (("p", 1e-12), ("u+", 1e-10), ("tau", 1e-9), ("q+", 1e-12)):
    np.testing.assert_allclose(*mine_theirs[name], atol=tol, err_msg=name)
np.testing.assert_allclose(f_N.sum(), weight, rtol=1e-2)
# the spring-damper law of the step where loaded (penetrating through the step's window):
# f_N = -k (g + theta dt w_N) - d (theta_d w_N + (1 - theta_d) w_0)
w_N = res.w[0::3]
law = -k * (contacts.g + theta * dt * w_N) - d * (theta_dN * w_N + (1 - theta_dN) * w_start)
np.testing.assert_allclose(f_N[loaded], law[loaded], rtol=1e-6)
assert f_N[~loaded].max() < 1e-12 * f_N.max()
assert max(res.residuals.values()) < 1e-6, res.residuals
for name in ("p", "qd", "q", "tau"):
    np.testing.assert_allclose(getattr(fast, name), getattr(res, name), atol=1e-9)
print("All one-step contact checks passed.")
# a window on an interactive backend; headless (Agg) the PNGs in OUT are the pictures
if plt.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template"):
    plt.show()
