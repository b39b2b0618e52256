# %% [markdown]
# # 06 - Single shooting: joint commands that push the box to a goal with least torque
# **Goal:** see what the shooting method optimises, and why it is solved derivative-free, first on a
# toy (a piston pushing a box, two parameters, a cost landscape you can plot), then on COBRA.
# **Paper:** [COBRA] sec. "Results": "We take the shooting method to find optimal u_ref for minimized
# joint torques tau such that generalized contact forces f_ext stand orthogonal to gap functions and
# their derivative"; Eq. (6) constraints (2), (3) (torque and joint limits); assumption A17.
# **Run:** `python tutorials/06_shooting.py` (about half a minute; writes `06_shooting_landscape.png`
# and `06_shooting_cobra.png` in the current directory).

# %%
import os
import pathlib

import matplotlib.pyplot as plt
import numpy as np

from cobra_ref import planning as sh
from cobra_ref.kinematics import forward_kinematics
from cobra_ref.robots import cobra_model

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)

np.set_printoptions(precision=4, suppress=True)

# %% [markdown]
# ## 1. The toy: a piston pushes a box along a line
# A piston (mass m_p) follows the prescribed stroke x_p(t) = A (1 - cos(2 pi f t)) / 2, as COBRA's
# joints follow their reference. A box (mass m_b) sits `gap0` ahead of it with Coulomb friction mu.
# One time step is the 1-D version of the least-action step of tutorial 04, solved by hand: the box's
# velocity without contact is v_nc = max(v_b - mu g dt, 0); if that would close the gap,
# g + dt (v_nc - v_p+) < 0, the contact impulse p >= 0 makes the gap after the step exactly zero
# (so p > 0 only where the gap closes: p is "orthogonal to the gap function"). The piston's force is
# F = m_p (v_p+ - v_p) / dt + p / dt, the analogue of COBRA's joint torques recovered from eq. (1).
#
# The shooting cost has the same terms as COBRA's (`cobra_ref/planning/cost.py`):
#
#     J(A, f) = integral F^2 dt / (F_max^2 T) + 10 (d_T / d_0)^2 + integral max(0, |F| - F_max) dt / (F_max T)

# %%
m_b, m_p, mu, grav, F_max = 0.5, 0.5, 0.5, 9.81, 10.0  # [kg], [kg], [-], [m/s^2], [N]
gap0, goal, T, dt = 0.05, 0.15, 2.0, 1e-3  # [m] start gap, [m] goal displacement of the box, [s], [s]


def toy_rollout(A, f):
    """Simulate every (A, f) pair at once (numpy broadcasting); return J, d_T, max |p * gap rate|."""
    A, f = np.broadcast_arrays(np.asarray(A, float), np.asarray(f, float))
    x_b, v_b, x_p, v_p = np.full(A.shape, gap0), np.zeros(A.shape), np.zeros(A.shape), np.zeros(A.shape)
    effort, over, compl = np.zeros(A.shape), np.zeros(A.shape), np.zeros(A.shape)
    for k in range(round(T / dt)):
        x_p1 = A * (1 - np.cos(2 * np.pi * f * (k + 1) * dt)) / 2
        v_p1 = (x_p1 - x_p) / dt  # prescribed: the secant velocity, as the prescribed servo
        gap = x_b - x_p
        v_nc = np.maximum(v_b - mu * grav * dt, 0.0)  # friction alone (the box only slides forward)
        contact = gap + dt * (v_nc - v_p1) < 0  # would the gap close?
        v_b1 = np.where(contact, v_p1 - gap / dt, v_nc)  # then: gap after the step = 0
        p = np.where(contact, m_b * (v_b1 - v_b) + mu * m_b * grav * dt, 0.0)  # impulse on the box, >= 0
        F = m_p * (v_p1 - v_p) / dt + p / dt
        effort, over = effort + F**2 * dt, over + np.maximum(np.abs(F) - F_max, 0.0) * dt
        compl = np.maximum(compl, np.abs(p * (gap / dt + v_b1 - v_p1)))  # p (gap after step)/dt = 0
        x_b, v_b, x_p, v_p = x_b + dt * v_b1, v_b1, x_p1, v_p1
    d_T = np.abs(x_b - (gap0 + goal))
    J = effort / (F_max**2 * T) + 10.0 * (d_T / goal) ** 2 + over / (F_max * T)
    return J, d_T, compl


J0, d0, c0 = toy_rollout(0.1, 1.0)
print(f"A = 0.1 m, f = 1 Hz: J = {float(J0):.4f}, box {float(d0) * 100:.1f} cm from the goal")

# %% [markdown]
# ## 2. The cost landscape
# 61 x 36 rollouts in one vectorised call. Three features decide the method:
# * a **plateau** for A < gap0: the piston never reaches the box, the goal term is exactly 10 and
#   its gradient is zero: a gradient method started there never moves;
# * a **valley** near A = gap0 + goal = 0.2 m, where the box ends at the goal;
# * **ragged** level sets at high f: each impact is an impulse in one step (the F spike, like
#   COBRA's torque spikes at impacts), and J is not differentiable across the contact switches.
#
# So we use a derivative-free search, and start it from a guess that already touches the box.

# %%
A_grid, f_grid = np.linspace(0.0, 0.3, 61), np.linspace(0.25, 2.0, 36)
AA, FF = np.meshgrid(A_grid, f_grid, indexing="ij")
J_grid, d_grid, c_grid = toy_rollout(AA, FF)
k_min = np.unravel_index(np.argmin(J_grid), J_grid.shape)
print(f"grid minimum J = {J_grid[k_min]:.4f} at A = {AA[k_min]:.3f} m, f = {FF[k_min]:.2f} Hz")
print(f"plateau A < gap0: J in [{J_grid[A_grid < gap0].min():.4f}, {J_grid[A_grid < gap0].max():.4f}]")

# %% [markdown]
# ## 3. The compass search of `cobra_ref.planning`, on the toy
# `sh.compass_search` is the optimizer of `cobra-ref optimize`: each iteration polls the 2n points
# x +- step e_i (in the bounds scaled to [0, 1]), as one batch, so that the 2n rollouts run in
# parallel; it moves to the best one if it lowers J and halves the step otherwise. Here a batch is
# one vectorised `toy_rollout` call.

# %%
def recording_batch(path):
    """A batch of toy rollouts that records every point it evaluates in ``path``."""

    def batch(xs):
        xs = np.asarray(xs)
        path.extend(xs)
        return list(toy_rollout(xs[:, 0], xs[:, 1])[0])

    return batch


path = []
toy_batch = recording_batch(path)


x_best, J_best, why = sh.compass_search(toy_batch, x0=[0.1, 1.5], lower=[0.0, 0.25], upper=[0.3, 2.0],
                                        maxiter=40)
print(f"{why}; {len(path)} rollouts; optimum A = {x_best[0]:.4f} m, f = {x_best[1]:.3f} Hz, J = {J_best:.4f}")

# %% [markdown]
# The compass search is local: started in the ragged region it stops in one of its small dips
# (every poll at the final, finest step is worse), short of the valley's floor. That is why
# `cobra-ref optimize` starts from the paper's default gait, and why `method="de"` exists: scipy's
# differential evolution (seeded, so deterministic) samples the whole box; its population is one
# batch per generation, so it parallelises the same way, at many more rollouts (here 20 x 31).

# %%
de_path = []
toy_batch_de = recording_batch(de_path)


x_de, J_de, why_de = sh.differential_evolution_search(toy_batch_de, x0=[0.1, 1.5], lower=[0.0, 0.25],
                                                      upper=[0.3, 2.0], maxiter=30, seed=1, popsize=10)
print(f"{why_de}; {len(de_path)} rollouts; optimum A = {x_de[0]:.4f} m, f = {x_de[1]:.3f} Hz, J = {J_de:.4f}")

# %%
fig, ax = plt.subplots(figsize=(6, 4.5))
cs = ax.contourf(AA, FF, np.log10(J_grid), 30, cmap="viridis")
fig.colorbar(cs, label="log10 J")
ax.plot(*np.array(path).T, "w.", ms=3, label="rollouts of the compass search")
ax.plot(0.1, 1.5, "ws", label="initial guess")
ax.plot(*x_best, "r*", ms=12, label="compass search optimum")
ax.plot(*x_de, "m*", ms=12, label="differential evolution optimum")
ax.axvline(gap0, color="w", ls=":", lw=1)
ax.set(xlabel="stroke amplitude A [m]", ylabel="frequency f [Hz]", title="toy shooting cost J(A, f)")
ax.legend(loc="upper right", fontsize=8)
fig.tight_layout()
fig.savefig(OUT / "06_shooting_landscape.png", dpi=120)

# %% [markdown]
# ## 4. The real problem: COBRA pushes the box
# `sh.make_problem(gait, goal, ...)` builds the same problem for COBRA: the decision vector is a few
# parameters of one gait family (C: amplitude and frequency), one rollout is one `simulate` of the
# full model over the horizon, and the cost is
#
#     J = E + 10 (d_T / d_0)^2 + P_tau + P_q,   E = integral ||tau||^2 dt / (11 tau_max^2 T).
#
# Each candidate starts at rest in its own t = 0 shape (the prescribed joints start on their
# reference), moved in the plane so that its middle link is where the initial guess's is; the box
# starts at the same pose for every rollout. Below: the start of the initial guess (A = 0.5 rad) and
# of a tighter C (A = 0.7 rad) -- the box faces the same link across the same gap.
# For a rollout that runs in seconds we take a 0.3 s horizon with the box 5 mm from the middle link.

# %%
problem = sh.make_problem("C", goal=(0.05, -0.01), duration=0.3, space=sh.DecisionSpace(ramp_time=0.1), box_gap=0.005)
print("decision:", problem.names, "lower", problem.lower, "upper", problem.upper, "x0", problem.x0)
print("box starts at", np.round(problem.box_pose0[:2], 4), "goal", np.round(problem.goal_world, 4))
model = cobra_model(problem.cobra)
starts = {A: sh.start_state(problem, (A, 0.5), model)[0] for A in (0.5, 0.7)}
for A, q0 in starts.items():
    print(f"A = {A}: middle pose (x, y, heading) = {sh.middle_pose(model, q0)}")

# %% [markdown]
# ## 5. Two rollouts and their cost terms
# The initial guess (0.5 Hz) and a faster roll (1 Hz). With the prescribed servo the joint torques
# spike above tau_max at impacts for a step or two: the L1 penalty P_tau counts them. Every step's
# contact impulses satisfy the least-action QP's conditions (complementarity p_N w_N ~ 0 and the
# friction cone), which is the paper's "f_ext orthogonal to the gap functions".

# %%
entries = {f: sh.evaluate(problem, (0.5, f)) for f in (0.5, 1.0)}
for f, e in entries.items():
    terms = ", ".join(f"{k} {v:.4f}" for k, v in e["terms"].items())
    c = e["contact"]
    print(f"f = {f} Hz: J = {e['cost']:.4f} ({terms}); box {e['box_distance_to_goal'] * 100:.2f} cm from the goal; "
          f"max p_N w_N {c['max_complementarity']:.1e} N s m/s, cone residual {c['max_cone_residual']:.1e}, "
          f"{c['steps_over_tau_max']} steps over tau_max")

# %%
fig, axes = plt.subplots(1, 2, figsize=(10, 4))
for (A, q0), style in zip(starts.items(), ("C0", "C1")):
    pts = np.array([forward_kinematics(model, q0).o[i][:2] for i in range(model.nb - 1)])
    axes[0].plot(*pts.T, "o-", color=style, label=f"start shape, A = {A} rad")
half = 0.05
bx, by = problem.box_pose0[:2]
for ax in axes:
    ax.add_patch(plt.Rectangle((bx - half, by - half), 2 * half, 2 * half, fill=False, lw=1.5, label="box (t = 0)"))
    ax.plot(*problem.goal_world, "r*", ms=12, label="goal")
    ax.set(xlabel="x [m]", ylabel="y [m]", aspect="equal")
axes[0].set_title("common initial state: the middle link is anchored")
for f, e in entries.items():
    axes[1].plot(*np.array([problem.box_pose0[:2], e["box_final"]]).T, "o-", label=f"box start -> end, f = {f} Hz")
axes[1].set(xlim=(bx - 0.1, bx + 0.1), ylim=(by - 0.1, by + 0.1), title="box after 0.3 s")
for ax in axes:
    ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(OUT / "06_shooting_cobra.png", dpi=120)

# %% [markdown]
# ## 6. Running the real optimization
# The default problems (`sh.DEFAULTS`: horizon 1.5 s for the rolling gaits, 3 s for sidewinding,
# goals about 1.5 times as far as the default gait pushes the box) take a few minutes per gait on two
# cores, so they are not run here:
#
#     cobra-ref optimize --gait C --goal 0.2,-0.1 --out C.json      # progress on stderr
#     cobra-ref simulate --params C.json --out C.npz               # replays the optimum exactly
#
# Each iteration's 2n rollouts go through a `concurrent.futures.Executor`: by default a process pool
# on the local cores; `sh.optimize(problem, executor=client.get_executor())` hands them to a Dask
# cluster instead (or `method="de"` for scipy's differential evolution with a larger population).

# %% [markdown]
# ## 7. What we verified

# %%
assert np.all(J_grid[A_grid < gap0] >= 10.0 - 1e-12)  # the plateau: the box never moves
assert np.all(c_grid < 1e-9)  # toy: the impulse acts only where the gap closes
assert J_best < float(toy_rollout(0.1, 1.5)[0])  # the search lowered the cost from the guess
assert J_best < 1.0 and abs(x_best[0] - (gap0 + goal)) < 0.03  # a stroke that pushes the box near the goal
assert J_de <= J_grid[k_min] + 0.02 and J_de < J_best  # DE found the valley's floor, the compass a local dip
assert np.allclose(sh.middle_pose(model, starts[0.5]), sh.middle_pose(model, starts[0.7]), atol=1e-9)
assert entries[1.0]["cost"] < entries[0.5]["cost"]  # rolling faster brings the box closer here
assert entries[1.0]["box_distance_to_goal"] < entries[0.5]["box_distance_to_goal"]
for e in entries.values():
    assert e["contact"]["max_cone_residual"] < 1e-6 and e["contact"]["max_q_excess"] <= 0.0
# a window on an interactive backend; headless (Agg) the PNGs in OUT are the pictures
if plt.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template"):
    plt.show()
