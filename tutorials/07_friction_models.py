# %% [markdown]
# # 07 - Three friction models on one sliding box
# **Goal:** see why cobra_ref represents Coulomb's friction circle exactly, by building two
# common approximations yourself and watching them fail on a sliding box: (a) the 4-facet
# pyramid, which lets a diagonal slide feel sqrt(2) mu m g and keeps a box under a sideways
# force from turning; (b) Anitescu's convex relaxation, which turns a fast slide into a jump;
# (c) the exact circle with the friction fixed point of `cobra_ref.least_action`.
# **Paper:** [COBRA] eq. (2) (the friction set F_i: Coulomb's cone ||f_T|| <= mu f_N) and
# eq. (6) (least action, whose constraint holds F_i); the time step of tutorial 04.
# **Run:** `python tutorials/07_friction_models.py` (a few seconds; writes `07_friction_models.png`)

# %%
import os
import pathlib

import matplotlib.pyplot as plt
import numpy as np
import osqp
from scipy import sparse
from scipy.integrate import solve_ivp

from cobra_ref.least_action import LeastAction, kkt_residuals, solve_least_action
from cobra_ref.qp import solve_box_qp

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)
np.set_printoptions(precision=5, suppress=True)

# %% [markdown]
# ## 1. The toy: a box sliding on the ground, as one point contact
# A 0.5 kg box that slides without turning has the same velocity at its four corners, and
# Coulomb's law gives each corner friction mu f_N,i against that common slip: together
# mu m g against the slip, as one contact at the centre would. So we take one contact on a
# point mass m, rows [n, t1, t2] = [e_z, e_x, e_y], and (tutorial 04) the Delassus matrix
# `G = J M^-1 J^T = 1 / m`. With the rigid law of eq. (2)-(6) as written (R = 0,
# `b_N = gap / dt`; tutorial 04, section 2) one step is
#
#     min_p  1/2 p^T G p + p^T c,    c = J u_free + b,    u_free = u + dt (F / m - g e_z),
#
# with the friction set F_i of eq. (2) as its constraint: the three models differ only there.

# %%
m, grav, dt = 0.5, 9.81, 1e-3  # kg, m/s^2, s
G = np.eye(3) / m


def free_c(u, gap=0.0, force=(0.0, 0.0, 0.0)):
    """c = J u_free + b for world velocity u, height `gap` and a horizontal force: rows (n, t1, t2)."""
    u_free = np.asarray(u, dtype=float) + dt * (np.asarray(force) / m - np.array([0.0, 0.0, grav]))
    return np.array([u_free[2] + gap / dt, u_free[0], u_free[1]])


# %% [markdown]
# ## 2. (a) The 4-facet pyramid
# Replace the circle ||p_T|| <= mu p_N by the square `|p_t1| <= mu p_N, |p_t2| <= mu p_N`: each
# axis on its own. With a guess pbar_N of the normal impulse in place of p_N the constraints
# are a box, solved by `solve_box_qp` (OSQP); the guess is updated to the answer's p_N until it
# stops changing (for one point contact p_N does not depend on friction: two QPs).

# %%
def pyramid(c, mu, max_iter=20):
    """Impulses with friction in the square |p_t1|, |p_t2| <= mu pbar_N, pbar_N <- p_N to a fixed point."""
    pbar_N = 0.0
    for _ in range(max_iter):
        r = mu * pbar_N
        p = solve_box_qp(G, c, np.array([0.0, -r, -r]), np.array([np.inf, r, r])).x
        if abs(p[0] - pbar_N) <= 1e-12 * max(p[0], 1e-300):
            break
        pbar_N = p[0]
    return p


# %% [markdown]
# One step of a box sliding at 1 m/s, heading 45 deg, on mu = 1 (the paper's ground): both
# axes saturate, so friction is `mu p_N (1, 1)`, sqrt(2) times Coulomb's.

# %%
mu, v = 1.0, 1.0
heading = np.radians(45.0)
c_45 = free_c([v * np.cos(heading), v * np.sin(heading), 0.0])
p_pyr = pyramid(c_45, mu)
print("pyramid: p =", p_pyr, "N s")
print(f"|f_T| / (mu m g) = {np.hypot(*p_pyr[1:]) / (mu * m * grav * dt):.5f} (sqrt 2 = {np.sqrt(2):.5f})")

# %% [markdown]
# ## 3. (b) Anitescu's convex relaxation
# Keep p_N as an unknown inside the cone, as one convex QP: a polygon of K facets around the
# circle, `mu p_N - d_k . p_T >= 0` with unit directions d_k (K = 64: within 0.12 % of round),
# and p_N >= 0. These rows couple p_N and p_T, so they are general constraints `l <= A p <= u`:
# we call OSQP directly with that A.

# %%
def anitescu(c, mu, n_facets=64):
    """Impulses of one convex QP: p_N >= 0 and mu p_N - d_k . p_T >= 0 for n_facets directions d_k."""
    phi = 2 * np.pi * np.arange(n_facets) / n_facets
    A = np.vstack([[1.0, 0.0, 0.0], np.column_stack([np.full(n_facets, mu), -np.cos(phi), -np.sin(phi)])])
    solver = osqp.OSQP()
    solver.setup(P=sparse.triu(G, format="csc"), q=c, A=sparse.csc_matrix(A), l=np.zeros(n_facets + 1),
                 u=np.full(n_facets + 1, np.inf), eps_abs=1e-10, eps_rel=1e-10, polishing=True, verbose=False)
    result = solver.solve(raise_error=False)
    assert result.info.status == "solved", result.info.status
    return result.x


# %% [markdown]
# A ball sliding at 1 m/s along t1 on mu = 1. The QP's optimality conditions put the velocity
# after the step, w = G p + c, on the relaxed cone's *normal*: `w_N = mu |w_T|`. The contact
# pushes until the ball leaves the ground at mu times its slip speed. By hand (projecting
# -m c onto the cone): `p_N = m (g dt + mu v) / (1 + mu^2)`, about fifty times its weight's
# m g dt; friction `mu p_N`. (G = 1/m is a multiple of the identity, so the QP's minimiser is
# the point of the cone nearest to -m c.)

# %%
c_slide = free_c([v, 0.0, 0.0])
p_ani = anitescu(c_slide, mu)
w_ani = G @ p_ani + c_slide
p_N_hand = m * (grav * dt + mu * v) / (1 + mu**2)
print("Anitescu: p =", p_ani, f"N s; p_N by hand {p_N_hand:.6f}, weight's m g dt = {m * grav * dt:.6f}")
print(f"after the step: w_N = {w_ani[0]:.5f} m/s (up), slip |w_T| = {np.hypot(*w_ani[1:]):.5f} m/s,"
      f" w_N / |w_T| = {w_ani[0] / np.hypot(*w_ani[1:]):.5f} = mu")

# %% [markdown]
# ## 4. (c) The exact circle: cobra_ref's friction fixed point
# `solve_least_action` bounds friction by a square turned along the friction's direction with
# the guess pbar_N, solves that box QP with OSQP and updates (pbar_N, direction) until
# Coulomb's natural residual vanishes (tutorial 04, section 5). On the same G and c:

# %%
def circle(c, mu):
    """Impulses with Coulomb's circle ||p_T|| <= mu p_N: cobra_ref's least-action solve (R = 0)."""
    problem = LeastAction(G, c, np.array([mu]), np.zeros(0), np.zeros(0), 0.0)
    p, info = solve_least_action(problem)
    assert info.converged and max(kkt_residuals(problem, p).values()) < 1e-6, info
    return p


for name, c in (("slide at 45 deg", c_45), ("slide along t1", c_slide)):
    p = circle(c, mu)
    w = G @ p + c
    ratio = np.hypot(*p[1:]) / (mu * m * grav * dt)
    print(f"circle, {name}: p = {p}, |f_T| / (mu m g) = {ratio:.5f}, w_N = {w[0]:.1e}")

# %% [markdown]
# ## 5. Every heading
# Slide at 1 m/s in headings from 0 to 90 deg and record, for each model, the friction per
# normal force |f_T| / (mu f_N), the normal force per weight f_N / (m g), the angle between the
# friction and the direction opposite to the slip, and the lift-off speed w_N.

# %%
headings = np.radians(np.arange(0.0, 90.1, 2.0))
models = {"pyramid": pyramid, "Anitescu": anitescu, "circle": circle}
sweep = {name: np.zeros((len(headings), 4)) for name in models}
for i, a in enumerate(headings):
    c = free_c([v * np.cos(a), v * np.sin(a), 0.0])
    for name, solve in models.items():
        p = solve(c, mu)
        error = np.degrees(abs(np.angle(-(p[1] + 1j * p[2]) * np.exp(-1j * a))))
        sweep[name][i] = [np.hypot(*p[1:]) / (mu * p[0]), p[0] / (m * grav * dt), error, (G @ p + c)[0]]
for name, rows in sweep.items():
    print(f"{name:8s}: |f_T|/(mu f_N) in [{rows[:, 0].min():.4f}, {rows[:, 0].max():.4f}],"
          f" f_N/(m g) up to {rows[:, 1].max():6.2f}, direction error up to {rows[:, 2].max():5.2f} deg,"
          f" lift-off up to {rows[:, 3].max():.3f} m/s")

# %% [markdown]
# ## 6. A sideways force
# The box slides along x at 1 m/s while a steady force `F = 0.6 mu m g` pushes it along y, for
# 0.08 s (on mu = 1 it would stop after v / (mu g) = 0.1 s). Coulomb's law,
# `m v' = F e_y - mu m g v / |v|` while it slides, spends the whole friction budget against the
# slip, so F turns the velocity: the path curves. The pyramid bounds the y friction by
# mu m g on its own, which holds F entirely: the box goes straight. We step each model and
# integrate Coulomb's law with scipy for comparison.

# %%
F = np.array([0.0, 0.6 * mu * m * grav, 0.0])
n_steps = 80
runs = {}
for name, solve in models.items():
    x, u, path = np.zeros(3), np.array([v, 0.0, 0.0]), []
    for _ in range(n_steps):
        p = solve(free_c(u, gap=x[2], force=F), mu)
        u = u + dt * (F / m - np.array([0.0, 0.0, grav])) + np.array([p[1], p[2], p[0]]) / m
        x = x + dt * u
        path.append(np.concatenate([x, u]))
    runs[name] = np.array(path)

# %%
def coulomb(t, y):
    """Coulomb's law of the sliding box in the plane: y = (x, y, v_x, v_y)."""
    vel = y[2:]
    return [*vel, *(F[:2] / m - mu * grav * vel / np.linalg.norm(vel))]


exact = solve_ivp(coulomb, (0.0, n_steps * dt), [0.0, 0.0, v, 0.0], rtol=1e-10, atol=1e-12,
                  dense_output=True)
t_steps = dt * np.arange(1, n_steps + 1)
y_exact = exact.sol(t_steps)
for name, path in runs.items():
    print(f"{name:8s}: end at x = {100 * path[-1, 0]:.2f} cm, y = {100 * path[-1, 1]:.2f} cm,"
          f" highest z = {1000 * path[:, 2].max():.2f} mm")
print(f"Coulomb : end at x = {100 * y_exact[0, -1]:.2f} cm, y = {100 * y_exact[1, -1]:.2f} cm")

# %% [markdown]
# ## 7. The picture
# Top: per heading of the slide, friction per normal force |f_T| / (mu f_N), normal force per
# weight (log scale), and the friction's direction error. Bottom: the sideways-force run's
# path, its sideways speed, and its height.

# %%
fig, ax = plt.subplots(2, 3, figsize=(13, 7))
styles = {"pyramid": "C0-", "Anitescu": "C3--", "circle": "C2-"}
for name, rows in sweep.items():
    for j, label in enumerate(("|f_T| / (mu f_N)", "f_N / (m g)", "friction direction error [deg]")):
        ax[0, j].plot(np.degrees(headings), rows[:, j], styles[name], label=name)
        ax[0, j].set(xlabel="heading of the slide [deg]", ylabel=label)
ax[0, 1].set_yscale("log")
ax[0, 1].set_title(f"one step of a slide at {v:.0f} m/s on mu = {mu:.0f}")
ax[0, 0].legend()
for name, path in runs.items():
    ax[1, 0].plot(100 * path[:, 0], 100 * path[:, 1], styles[name], label=name)
    ax[1, 1].plot(1000 * t_steps, path[:, 4], styles[name], label=name)
    ax[1, 2].plot(1000 * t_steps, 1000 * path[:, 2], styles[name], label=name)

# %%
ax[1, 0].plot(100 * y_exact[0], 100 * y_exact[1], "k:", label="Coulomb (scipy)")
ax[1, 1].plot(1000 * t_steps, y_exact[3], "k:", label="Coulomb (scipy)")
ax[1, 0].set(xlabel="x [cm]", ylabel="y [cm]", title="path under a sideways force")
ax[1, 1].set(xlabel="t [ms]", ylabel="sideways speed v_y [m/s]")
ax[1, 2].set(xlabel="t [ms]", ylabel="height z [mm]")
ax[1, 0].legend(fontsize=8)
fig.tight_layout()
fig.savefig(OUT / "07_friction_models.png", dpi=120)

# %% [markdown]
# ## 8. What we checked
# * (a) The pyramid gives sqrt(2) mu m g to a diagonal slide (friction at 45 deg whatever the
#   slide's heading, except along an axis), and holds a sideways force that is below mu m g on
#   its axis: the box does not turn.
# * (b) Anitescu's relaxation has friction on its cone but a normal impulse ~50 times the
#   weight's: the ball leaves the ground at `w_N = mu |w_T|`, mu times its slip speed.
# * (c) The circle: friction mu m g exactly against the slip at every heading, no lift-off,
#   and the sideways-force run follows Coulomb's law (scipy) to within 2 %.

# %%
pyr, ani, cir = sweep["pyramid"], sweep["Anitescu"], sweep["circle"]
np.testing.assert_allclose(np.hypot(*p_pyr[1:]), np.sqrt(2) * mu * m * grav * dt, rtol=1e-7)
assert np.all(pyr[1:-1, 0] > 1.41) and pyr[:, 2].max() > 40.0
assert np.abs(runs["pyramid"][:, 1]).max() < 1e-9, "the pyramid's box goes straight"
np.testing.assert_allclose(p_ani[0], p_N_hand, rtol=1e-6)
np.testing.assert_allclose(w_ani[0], mu * np.hypot(*w_ani[1:]), rtol=1e-6)
assert ani[:, 1].min() > 40.0 and ani[:, 3].min() > 0.4 and runs["Anitescu"][:, 2].max() > 5e-3
np.testing.assert_allclose(cir[:, 0], 1.0, atol=1e-9)
np.testing.assert_allclose(cir[:, 1], 1.0, rtol=1e-7)
assert cir[:, 2].max() < 1e-6 and np.abs(cir[:, 3]).max() < 1e-9
np.testing.assert_allclose(runs["circle"][:, :2], y_exact[:2].T, atol=0.02 * np.hypot(*y_exact[:2, -1]))
np.testing.assert_allclose(runs["circle"][:, 3:5], y_exact[2:].T, atol=0.02 * v)
assert y_exact[1, -1] > 5e-3, "Coulomb's box turns towards the force"
print("All friction-model checks passed.")
# a window on an interactive backend; headless (Agg) the PNGs in OUT are the pictures
if plt.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template"):
    plt.show()
