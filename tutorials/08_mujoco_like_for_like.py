# %% [markdown]
# # 08 - MuJoCo like for like: the same spring-damper, the same friction circle
# **Goal:** map cobra_ref's compliant contact (a spring-damper normal force, Coulomb's circle)
# onto MuJoCo's soft constraints, understand which effective mass the mapping uses and why the
# impedance must be small, then check it on two cases solvable by hand, in both simulators: a
# body resting on the ground (it sinks by m g / k) and a box sliding on it (it slows at mu g).
# **Paper:** [COBRA] sec. "Simulation Setup" (the high-fidelity contact: assumptions A12, A13 of
# docs/assumptions.md), the mapping A27 and docs/mujoco.md; [MJ] "Computation" / "Parameters".
# **Run:** `python tutorials/08_mujoco_like_for_like.py` (about ten seconds; needs `mujoco`;
# writes `08_mujoco_like_for_like.png`)

# %%
import os
import pathlib
import xml.etree.ElementTree as ET

import matplotlib.pyplot as plt
import mujoco
import numpy as np

from cobra_ref.mjcf import IMPEDANCE, inverse_weights, pair_parameters, to_mjcf
from cobra_ref.model import BoxGeom, Model, SphereSet
from cobra_ref.simulate import simulate

# pictures go to an ignored folder beside the tutorials (or to $COBRA_REF_OUT)
OUT = pathlib.Path(os.environ.get("COBRA_REF_OUT", pathlib.Path(__file__).resolve().parent / "out"))
OUT.mkdir(parents=True, exist_ok=True)
np.set_printoptions(precision=6, suppress=False)

# %% [markdown]
# ## 1. Two toys: a ball and a box, each one free rigid body
# A 1 kg ball of radius 0.1 m (one contact with the ground) and the paper's box, a 0.1 m cube of
# 0.5 kg (four corner contacts when it lies flat). Both get cobra_ref's contact law:
# k = 1e6 N/m, c = 1e3 N s/m (A12), mu = 0.5 here (below the cube's tipping limit mu = 1),
# stick-slip velocity v_s = 1e-3 m/s (A13).

# %%
g = 9.81  # [m/s^2]


def free_body(name, mass, I_com, spheres=None, boxes=(), mu=0.5):
    """One rigid body on a free joint, centre of mass at its origin, with cobra_ref's default contact law."""
    spheres = spheres or SphereSet(body=np.zeros(0, dtype=int), center=np.zeros((0, 3)), radius=np.zeros(0))
    return Model(name=name, body_names=(name,), joint_names=("free",), parent=(-1,), joint_type=("free",),
                 tree_pos=(np.zeros(3),), tree_rot=(np.eye(3),), mass=(mass,), com=(np.zeros(3),),
                 I_com=(I_com,), gravity=np.array([0.0, 0.0, -g]), q_limit=(np.inf,), tau_limit=(np.inf,),
                 spheres=spheres, boxes=boxes, mu=mu)


ball = free_body("ball", 1.0, 0.4 * 1.0 * 0.1**2 * np.eye(3),
                 spheres=SphereSet(body=np.zeros(1, dtype=int), center=np.zeros((1, 3)), radius=np.array([0.1])))
box = free_body("box", 0.5, 0.5 * 0.1**2 / 6 * np.eye(3), boxes=(BoxGeom(body=0, half=np.full(3, 0.05)),))
k, c = ball.contact_stiffness, ball.contact_damping
print(f"k = {k:g} N/m, c = {c:g} N s/m, mu = {box.mu}, v_s = {box.stiction_velocity} m/s")

# %% [markdown]
# ## 2. What MuJoCo's soft constraint does with solref and solimp
# MuJoCo solves for each constraint row a force f with `R f = a_ref - a_c` ([MJ] "Parameters"):
# a_c is the row's acceleration, `R = (1 - d) / d * A_hat` a regularizer set by the impedance d
# (solimp) and A_hat, MuJoCo's estimate of the row's inverse mass, and `a_ref = -b v - k_mj r` a
# reference acceleration of the row's distance r and its rate v. In the *direct* solref format
# (-stiffness, -damping) with a constant impedance d, b = damping / d and k_mj = stiffness / d:
#
#     f = -(damping v + stiffness r) / ((1 - d) A_hat)  -  d / (1 - d) * a_c / A_hat.
#
# With stiffness = k (1 - d) A_hat and damping = c (1 - d) A_hat the first term is our
# spring-damper -k r - c v, whatever the true effective mass: the mapping uses MuJoCo's own
# A_hat, not the physics' 1 / (J M^-1 J^T). The second term is what is left: it vanishes at rest
# and is 1e-4 of a_c / A_hat for d = 1e-4, the smallest impedance MuJoCo allows.
# For the ball A_hat = 1 / m; `inverse_weights` computes it for any model from our own M and
# Jacobians, as MuJoCo's compiler does (body_invweight0).

# %%
print("A_hat of the ball:", inverse_weights(ball), "1/kg   (1 / m =", 1 / ball.mass[0], ")")
geom1, geom2, attributes = pair_parameters(ball)[0]
print(f"<pair geom1={geom1!r} geom2={geom2!r}", " ".join(f'{key}="{v}"' for key, v in attributes.items()), "/>")

# %% [markdown]
# Check it on MuJoCo's own numbers: push the ball 1 mm into the ground, moving down at 1 cm/s,
# and compare a_ref / R of its normal row with -k r - c v.

# %%
m_ball = mujoco.MjModel.from_xml_string(to_mjcf(ball))
d_ball = mujoco.MjData(m_ball)
d_ball.qpos[:] = [0.0, 0.0, 0.1 - 1e-3, 1.0, 0.0, 0.0, 0.0]
d_ball.qvel[2] = -0.01
mujoco.mj_forward(m_ball, d_ball)
row = d_ball.contact[0].efc_address
r, v = d_ball.efc_pos[row], d_ball.efc_vel[row]
print(f"r = {r:.4g} m, v = {v:.4g} m/s: a_ref / R = {d_ball.efc_aref[row] / d_ball.efc_R[row]:.6f} N, "
      f"-k r - c v = {-k * r - c * v:.6f} N, MuJoCo's force {d_ball.efc_force[row]:.6f} N")

# %% [markdown]
# ## 3. Why not an impedance near 1?
# With d near 1 (MuJoCo's default range is 0.9-0.95) R is small and the row is nearly hard:
# a_c = (1 - d) a_u + d a_ref. Gravity's a_u is then felt only with the weight 1 - d, so the
# spring holds the ball at (1 - d) g / k_mj: with the same stiffness 1e4 times less deep than
# our m g / k (in practice the ball chatters at the scale of one step's fall, g dt^2 = 1e-7 m,
# still 100 times less). Matching the sag instead (k_mj 1e4 times softer) would make the
# contact's dynamics 100 times slower. Only a small impedance gives the spring-damper itself.

# %%
def resting_sag(model, xml, duration=0.5):
    """How far ``model`` (a body lying on the ground at its own height) sinks in ``duration`` of MuJoCo."""
    m = mujoco.MjModel.from_xml_string(xml)
    d = mujoco.MjData(m)
    height = 0.1 if model.name == "ball" else 0.05
    d.qpos[:] = [0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0]
    for _ in range(int(round(duration / m.opt.timestep))):
        mujoco.mj_step(m, d)
    return height - d.qpos[2]


root = ET.fromstring(to_mjcf(ball))
for pair in root.iter("pair"):
    pair.set("solimp", "0.9999 0.9999 0.001 0.5 2")
sag_hard = resting_sag(ball, ET.tostring(root, encoding="unicode"))
print(f"ball's sag: d = 0.9999 {sag_hard:.3e} m, d = {IMPEDANCE:g} {resting_sag(ball, to_mjcf(ball)):.3e} m, "
      f"m g / k = {ball.mass[0] * g / k:.3e} m")

# %% [markdown]
# ## 4. The resting case, in both simulators
# At rest each of n contacts carries m g / n, so each spring sinks by m g / (n k): 9.81 um for
# the ball, 1.23 um for the box on its four corners. cobra_ref's implicit step reaches it
# exactly (`simulate`, at its 1 ms step); MuJoCo's, with the remainder of section 2 gone at rest, too.

# %%
def ours(model, q, qd, duration):
    """(q, qd) at every 1 ms step of ``duration`` of cobra_ref from (q, qd); no joints to drive."""
    no_joints = lambda t: (np.zeros(0), np.zeros(0), np.zeros(0))  # noqa: E731
    traj = simulate(model, no_joints, duration, q0=q, qd0=qd)
    return traj.q, traj.qd


sags = {}
for model, height, n in ((ball, 0.1, 1), (box, 0.05, 4)):
    q0 = np.array([0.0, 0.0, height, 1.0, 0.0, 0.0, 0.0])
    q_end = ours(model, q0, np.zeros(6), 0.3)[0][-1]
    sags[model.name] = (model.mass[0] * g / (n * k), height - q_end[2], resting_sag(model, to_mjcf(model)))
    print(f"{model.name}: m g / (n k) = {sags[model.name][0]:.6e} m, ours {sags[model.name][1]:.6e} m, "
          f"MuJoCo {sags[model.name][2]:.6e} m")

# %% [markdown]
# ## 5. The sliding case, in both simulators
# Thrown at 0.5 m/s along x, each corner opposes the slip with mu f_N: in sum mu m g, so the box
# slows at mu g = 4.905 m/s^2 and stops after v0 / (mu g) = 0.10 s. In MuJoCo the pair is on the
# elliptic cone (condim 3), whose friction rows are made hard (impratio) so that the cone takes
# the excess off the friction and does not lift the box (tutorial 07 shows that lift).

# %%
v0, T = 0.5, 0.12
q0 = np.array([0.0, 0.0, 0.05 - box.mass[0] * g / (4 * k), 1.0, 0.0, 0.0, 0.0])
qd0 = np.array([v0, 0.0, 0.0, 0.0, 0.0, 0.0])
v_ours = ours(box, q0, qd0, T)[1][:, 0]
m_box = mujoco.MjModel.from_xml_string(to_mjcf(box))
d_box = mujoco.MjData(m_box)
d_box.qpos[:], d_box.qvel[:] = q0, qd0
v_mj = [v0]
for _ in range(int(round(T / m_box.opt.timestep))):
    mujoco.mj_step(m_box, d_box)
    v_mj.append(d_box.qvel[0])
t_ours, t_mj = np.arange(len(v_ours)) * 1e-3, np.arange(len(v_mj)) * m_box.opt.timestep
decel = {who: (v0 - np.interp(0.05, t, v)) / 0.05 for who, t, v in (("ours", t_ours, v_ours), ("MuJoCo", t_mj, v_mj))}
print("deceleration over the first 0.05 s:", ", ".join(f"{who} {a:.5f}" for who, a in decel.items()),
      f"m/s^2; mu g = {box.mu * g:.5f} m/s^2")

# %% [markdown]
# ## 6. The time step MuJoCo needs
# With d = 1e-4 nothing of the contact is implicit in MuJoCo: the force is evaluated at the
# start of each step. The box's heave is damped by its four corners at the rate 4 c / m =
# 8000 / s, which semi-implicit Euler keeps stable only for dt < 2 m / (4 c) = 0.25 ms; the
# friction rows stop a slip at the rate b_T = mu g / v_s (9810 / s at mu = 1), stable for
# dt < 2 / b_T = 0.2 ms. Stable is not yet accurate: an explicit damper errs by about c dt / (2 m)
# on a contact of mass m, 5 % for a 1 kg ball at 0.1 ms. The export's default, 0.05 ms, is a
# quarter of both bounds and keeps that error at 2.5 % for 1 kg. cobra_ref's implicit step needs
# neither bound.

# %%
for timestep in (5e-5, 3e-4):
    sag = resting_sag(box, to_mjcf(box, timestep=timestep))
    print(f"timestep {timestep * 1e3:g} ms: the resting box sinks {sag:.3e} m (m g / (4 k) = {sags['box'][0]:.3e} m)")
sag_coarse = resting_sag(box, to_mjcf(box, timestep=3e-4))

# %%
fig, ax = plt.subplots(1, 2, figsize=(9, 3.4))
ax[0].bar(np.arange(2) - 0.2, [1e6 * sags[name][1] for name in ("ball", "box")], 0.4, label="cobra_ref")
ax[0].bar(np.arange(2) + 0.2, [1e6 * sags[name][2] for name in ("ball", "box")], 0.4, label="MuJoCo")
ax[0].plot(np.arange(2), [1e6 * sags[name][0] for name in ("ball", "box")], "k_", ms=30, label="m g / (n k)")
ax[0].set_xticks(np.arange(2), ["ball (1 contact)", "box (4 corners)"])
ax[0].set_ylabel("sag at rest [um]")
ax[0].legend(fontsize=8)
ax[1].plot(t_ours, v_ours, label="cobra_ref (1 ms)")
ax[1].plot(t_mj, v_mj, "--", label=f"MuJoCo ({m_box.opt.timestep * 1e3:g} ms)")
ax[1].plot(t_ours, np.maximum(v0 - box.mu * g * t_ours, 0.0), "k:", label="v0 - mu g t")
ax[1].set_xlabel("t [s]")
ax[1].set_ylabel("box speed [m/s]")
ax[1].legend(fontsize=8)
fig.tight_layout()
fig.savefig(OUT / "08_mujoco_like_for_like.png", dpi=120)

# %% [markdown]
# ## 7. What we checked
# * The mapping: MuJoCo's a_ref / R is our -k r - c v, and its force differs only by the
#   remainder d / (1 - d) a_c / A_hat.
# * An impedance near 1 makes the ball sink 1e4 times less than m g / k: the wrong law.
# * Resting: both sink by m g / (n k), for one contact and for four.
# * Sliding: both slow at mu g (within 1 %), in a straight line.
# * At 0.3 ms MuJoCo's explicit contact damping no longer settles the resting box.
# `cobra_ref.reproduce.mujoco_check` runs the same comparison on COBRA: the robot alone and
# pushing the box (docs/mujoco.md has the numbers).

# %%
np.testing.assert_allclose(d_ball.efc_aref[row] / d_ball.efc_R[row], -k * r - c * v, rtol=1e-9)
np.testing.assert_allclose(d_ball.efc_force[row], -k * r - c * v, rtol=1e-3)
assert sag_hard < 1e-2 * ball.mass[0] * g / k
for name, (hand, sag_ours, sag_mj) in sags.items():
    np.testing.assert_allclose(sag_ours, hand, rtol=1e-6, err_msg=f"ours, {name}")
    np.testing.assert_allclose(sag_mj, hand, rtol=1e-3, err_msg=f"MuJoCo, {name}")
for who, a in decel.items():
    np.testing.assert_allclose(a, box.mu * g, rtol=1e-2, err_msg=who)
assert abs(d_box.qpos[1]) < 1e-9, "MuJoCo's box leaves its straight line"
assert abs(v_ours[-1]) < 1e-3 and abs(v_mj[-1]) < 1e-3, "both boxes have stopped by 0.12 s"
assert abs(sag_coarse - sags["box"][0]) > 1e-2 * sags["box"][0], "0.3 ms should not settle the box"
print("All like-for-like checks passed.")
# a window on an interactive backend; headless (Agg) the PNGs in OUT are the pictures
if plt.get_backend().lower() not in ("agg", "pdf", "ps", "svg", "pgf", "cairo", "template"):
    plt.show()
