"""Worked checks of the work, power and contact-force analysis (assumption A18, figs. 4-9)."""

import numpy as np
import pytest

from cobra_ref import analysis
from cobra_ref.kinematics import forward_kinematics
from cobra_ref.quaternion import quat_to_rot
from cobra_ref.reproduce.runs import RunSpec, run
from cobra_ref.robots import cobra_model


@pytest.fixture(scope="module")
def pushing_run(tmp_path_factory):
    """1.2 s of J rolling: the hook reaches the box at about 0.87 s (about 4 s of computing)."""
    traj, cached = run(RunSpec("J", duration=1.2), str(tmp_path_factory.mktemp("cache")))
    assert not cached and traj.error == ""
    return traj


def test_locomotion_power_integrates_to_the_steppers_actuator_work(pushing_run):
    """sum_k P_loc,k dt = sum_k dt tau_k . u_mid,k, the stepper's own energy ledger (same formula,
    computed from the stored q-dot instead of inside the step)."""
    P, P_abs = analysis.locomotion_power(pushing_run)
    assert np.allclose(P * pushing_run.dt, pushing_run.steps["work_actuators"], atol=1e-12, rtol=1e-9)
    assert np.all(P_abs >= np.abs(P) - 1e-12)  # |sum| <= sum of |.|
    W = analysis.locomotion_work(pushing_run)
    assert W[0] == 0.0 and np.all(np.diff(W) >= 0) and W[-1] == pytest.approx(np.sum(P_abs) * pushing_run.dt)


def test_box_energy_balance(pushing_run):
    """The box's kinetic energy changes by the work of everything acting on it: the robot's
    contacts (W_box), the ground's contacts, and gravity, all at midpoint velocities, for which
    Delta KE = u_mid . M Delta u holds exactly (the gyroscopic power omega . (omega x I omega) is
    zero at omega, and second order at omega_mid)."""
    traj, model = pushing_run, cobra_model(with_box=True)
    box = model.boxes[0].body
    m, I = model.mass[box], model.I_com[box]
    v, w = traj.qd[:, -6:-3], traj.qd[:, -3:]
    ke = 0.5 * m * np.sum(v**2, axis=1) + 0.5 * np.einsum("ki,ij,kj->k", w, I, w)
    v_mid_z = 0.5 * (v[:-1, 2] + v[1:, 2])
    gravity = -m * 9.81 * v_mid_z * traj.dt
    robot = analysis.box_work(traj)[-1]
    ground = np.sum(analysis.contact_power_on_box(traj, analysis.BOX_GROUND)) * traj.dt
    assert robot > 1e-3  # the J hook does push the box in this window
    assert ground < 0  # the ground's friction takes energy out
    assert ke[-1] - ke[0] == pytest.approx(robot + ground + np.sum(gravity), abs=1e-4 * robot)


def test_ground_reactions_carry_the_weight(pushing_run):
    """Vertical impulse balance of the whole system: sum of the ground's normal impulses =
    M g T + Delta P_z, with the momentum from the COM's last step (the run starts at rest)."""
    traj, model = pushing_run, cobra_model(with_box=True)
    nb = model.nb
    f_rg = analysis.contact_forces(traj, analysis.ROBOT_GROUND, nb).normal
    f_bg = analysis.contact_forces(traj, analysis.BOX_GROUND, nb).normal
    impulse = (f_rg.sum() + f_bg.sum()) * traj.dt
    total_mass = sum(model.mass)

    def com_z(q):
        kin = forward_kinematics(model, q)
        return sum(model.mass[i] * (kin.o[i] + kin.R[i] @ model.com[i])[2] for i in range(nb)) / total_mass

    vz_end = (com_z(traj.q[-1]) - com_z(traj.q[-2])) / traj.dt
    expected = total_mass * 9.81 * traj.duration + total_mass * vz_end
    assert impulse == pytest.approx(expected, rel=1e-3)


def test_box_work_by_hand(pushing_run):
    """W_box recomputed row by row from the contact log with the box's pose and midpoint velocity."""
    traj = pushing_run
    c = traj.contacts
    total = 0.0
    for k, kind, point, force in zip(c["contact_step"], c["contact_kind"], c["contact_point"], c["contact_force"]):
        if kind != analysis.ROBOT_BOX:
            continue
        u = 0.5 * (traj.qd[k, -6:] + traj.qd[k + 1, -6:])
        R = quat_to_rot(traj.box_pose[k, 3:])
        v_point = u[:3] + np.cross(R @ u[3:], point - traj.box_pose[k, :3])
        total += -force @ v_point * traj.dt
    assert analysis.box_work(traj)[-1] == pytest.approx(total, rel=1e-12)


def test_efficiency_fit_is_the_least_squares_line_over_the_push(pushing_run, monkeypatch):
    """With W_loc = 3 W_box + 2 from the first robot-box contact on (and anything before it), the
    fit returns slope 3 and intercept 2; with no robot-box contact the slope is infinite."""
    traj = pushing_run
    k0 = int(traj.contacts["contact_step"][traj.contacts["contact_kind"] == analysis.ROBOT_BOX].min())
    w_box = np.concatenate([np.zeros(k0), np.linspace(0.0, 1.0, len(traj.t) - k0)])
    w_loc = 3 * w_box + 2
    w_loc[:k0] = np.linspace(0.0, 2.0, k0)  # the approach: work without any on the box
    monkeypatch.setattr(analysis, "box_work", lambda t: w_box)
    monkeypatch.setattr(analysis, "locomotion_work", lambda t: w_loc)
    slope, intercept = analysis.efficiency_fit(traj)
    assert slope == pytest.approx(3.0) and intercept == pytest.approx(2.0)
    assert analysis.efficiency_slope(traj) == pytest.approx(3.0)
    no_push = dict(traj.contacts, contact_kind=np.where(traj.contacts["contact_kind"] == analysis.ROBOT_BOX, 0,
                                                         traj.contacts["contact_kind"]))
    monkeypatch.setattr(traj, "contacts", no_push)
    assert analysis.efficiency_slope(traj) == float("inf")


def test_box_distance(pushing_run):
    d = analysis.box_distance(pushing_run)
    assert d[0] == 0.0
    assert d[-1] == pytest.approx(np.linalg.norm(pushing_run.box_pose[-1, :2] - pushing_run.box_pose[0, :2]))
