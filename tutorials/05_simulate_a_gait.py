# %% [markdown]
# # 05 - Simulate one gait and read its contacts
# **Goal:** run COBRA's J-shaped lateral rolling against the box for 1.2 s (the hook reaches
# the box at 0.87 s), then read the trajectory the way the paper's figures do: which link touches the ground when (fig. 4), the
# forces between the robot and the box (fig. 5), the locomotion power (fig. 7) and the work on
# the box (fig. 6), each recomputed by hand from the stored arrays and compared with
# `cobra_ref.analysis`.
# **Paper:** [COBRA] sec. "Results"; the work and power definitions are notes C18 (the paper
# plots them without defining them).
# **Run:** `python tutorials/05_simulate_a_gait.py` (about 10 s; it writes `05_contacts.png`).

# %%
import os
import pathlib

import matplotlib.pyplot as plt
import numpy as np

from cobra_ref import analysis
from cobra_ref.gaits import gait
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import initial_state, simulate

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)

np.set_printoptions(precision=4, suppress=True)

# %% [markdown]
# ## 1. The gait and the start
# `gait("J")` is the J-shaped rolling of notes B9 with its defaults (A = 0.5 rad on the head
# half, f = 0.5 Hz). It is a function of time that returns the 11 joint angles, rates and
# accelerations. Its phase rate ramps in over one period, so the robot starts at rest.
# `initial_state` lays the robot flat in the gait's t = 0 shape and puts the box 5 cm beside
# the middle link, on the concave side (assumption C9).

# %%
model = cobra_model(with_box=True)
J = gait("J")
q0, qd0 = initial_state(model, J)
q_ref, qd_ref, qdd_ref = J(0.0)
print("joint angles at t = 0 [rad]:", q_ref)
print("joint rates at t = 0:", qd_ref, "(the ramp starts from rest)")
assert np.allclose(qd_ref, 0.0)
box = model.boxes[0].body
print("box centre [m]:", q0[model.q_idx[box]][:3])

# %% [markdown]
# ## 2. Simulate
# The joints follow the reference exactly (prescribed motion, Simscape's "motion provided");
# each step solves the least-action contact problem (eq. 6) and recovers the joint torques from
# eq. (1). The trajectory keeps every state, the torques, solver records, and a flat contact
# log with one row per active contact and step.

# %%
T = 1.2
traj = simulate(model, J, T)
print(f"{len(traj.tau)} steps in {traj.wall_time:.1f} s (real-time factor {T / traj.wall_time:.2f})")
print("contact log rows:", len(traj.contacts["contact_step"]))
print("summary:", traj.summary())

# %% [markdown]
# ## 3. Which link touches the ground, and how hard (fig. 4)
# The log's `contact_kind` is 0 for robot-ground, 1 for robot-box, 2 for box-ground;
# `contact_force` is the force on body A (the link; the box for box-ground) in world
# coordinates. For a ground contact the normal is +z, so the normal force is the force's z
# component and the tangential force its horizontal part. Summing per link and step by hand:

# %%
c = traj.contacts
n_steps, nb = len(traj.tau), model.nb
normal_by_hand = np.zeros((n_steps, nb))
for k, kind, body, f in zip(c["contact_step"], c["contact_kind"], c["contact_body"], c["contact_force"]):
    if kind == analysis.ROBOT_GROUND:
        normal_by_hand[k, body] += f[2]
forces = analysis.contact_forces(traj, analysis.ROBOT_GROUND, nb)
assert np.allclose(forces.normal, normal_by_hand, atol=1e-9)
links = [model.body_names.index(f"L{i}") for i in range(1, 11)]
share = forces.in_contact[:, links].mean(axis=0)
for i, s in zip(range(1, 11), share):
    print(f"L{i}: on the ground {100 * s:5.1f} % of the time")

# %% [markdown]
# ## 4. Power and work (figs. 6 and 7)
# Locomotion power is P = sum_j tau_j qdot_j; the motors cannot store the energy they brake,
# so the energy they must supply is the integral of sum_j |tau_j qdot_j|. The joint rates are
# taken at each step's midpoint, (u_k + u_k+1) / 2, the velocity at which the stepper's energy
# ledger closes exactly. The work on the box sums f . v_box(p) over the robot-box contacts,
# with f = minus the logged force (the log holds the force on the robot).

# %%
qdot = 0.5 * (traj.qd[:-1, 6:17] + traj.qd[1:, 6:17])
P_hand = np.sum(traj.tau * qdot, axis=1)
P, P_abs = analysis.locomotion_power(traj)
assert np.allclose(P, P_hand)
W_loc = analysis.locomotion_work(traj)
W_box = analysis.box_work(traj)
print(f"locomotion work {W_loc[-1]:.2f} J, work on the box {W_box[-1]:.3f} J, "
      f"box moved {analysis.box_distance(traj)[-1] * 100:.1f} cm")
assert W_loc[-1] > 0

# %% [markdown]
# ## 5. The picture
# Top: the contact timeline of L1..L10 (a dot when the link presses on the ground). Middle:
# normal force on the box from the robot and from the ground. Bottom: power.

# %%
t_mid = traj.t[:-1] + traj.dt / 2
fig, ax = plt.subplots(3, 1, figsize=(7, 7), sharex=True)
for row, b in enumerate(links):
    on = forces.in_contact[:, b]
    ax[0].plot(t_mid[on], np.full(on.sum(), row + 1), "|", ms=6, color="tab:blue")
ax[0].set_ylabel("link (L1 = head end)")
ax[0].set_yticks(range(1, 11))
robot_box = analysis.contact_forces(traj, analysis.ROBOT_BOX, nb).normal.sum(axis=1)
box_ground = analysis.contact_forces(traj, analysis.BOX_GROUND, nb).normal.sum(axis=1)
ax[1].plot(t_mid, robot_box, label="robot on box")
ax[1].plot(t_mid, box_ground, label="ground on box")
ax[1].set_ylabel("normal force [N]")
ax[1].legend()
ax[2].plot(t_mid, P, label="P = sum tau qdot")
ax[2].plot(t_mid, P_abs, "--", label="sum |tau qdot|")
ax[2].set_ylabel("power [W]")
ax[2].set_xlabel("time [s]")
ax[2].legend()
fig.tight_layout()
fig.savefig(OUT / "05_contacts.png", dpi=120)
plt.show()

# %% [markdown]
# ## What to try
# * `gait("J-mirror")`: the box's sideways displacement changes sign (the paper's claim).
# * `gait("C", amplitude=0.4)`: a flatter arc; does it still reach the box?
# * `cobra-ref figures` runs all five gaits for 10 s and writes figs. 3-9 and the claims report.
