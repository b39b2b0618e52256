"""Worked checks of the work, power and contact-force analysis (assumption A18, figs. 4-9)."""

import numpy as np
import pytest

from cobra_ref.reproduce import analysis
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
    computed from the stored q-dot instead of inside the step), on every whole step; a step taken
    in touch-down substeps (A33) logs its substeps' works summed and their torques' mean, so there
    the two differ by the torque's change within the step."""
    P, P_abs = analysis.locomotion_power(pushing_run)
    whole = pushing_run.steps["substeps"] == 1
    assert 0 < np.sum(~whole) < 0.2 * len(whole)  # the J run's touch-downs are sub-stepped
    assert np.allclose((P * pushing_run.dt)[whole], pushing_run.steps["work_actuators"][whole], atol=1e-12, rtol=1e-9)
    assert np.all(P_abs >= np.abs(P) - 1e-12)  # |sum| <= sum of |.|
    W = analysis.locomotion_work(pushing_run)
    assert W[0] == 0.0 and np.all(np.diff(W) >= 0) and W[-1] == pytest.approx(np.sum(P_abs) * pushing_run.dt)


def test_box_energy_balance(pushing_run):
    """The box's kinetic energy changes by the work of everything acting on it: the robot's
    contacts (W_box), the ground's contacts, and gravity, all at midpoint velocities, for which
    Delta KE = u_mid . M Delta u holds exactly (the gyroscopic power omega . (omega x I omega) is
    zero at omega, and second order at omega_mid). Step by step over the whole steps: a step
    taken in touch-down substeps (A33) re-reads the velocity where the step size changes, which
    no logged force does."""
    traj, model = pushing_run, cobra_model(with_box=True)
    box = model.boxes[0].body
    m, I = model.mass[box], model.I_com[box]
    v, w = traj.qd[:, -6:-3], traj.qd[:, -3:]
    ke = 0.5 * m * np.sum(v**2, axis=1) + 0.5 * np.einsum("ki,ij,kj->k", w, I, w)
    v_mid_z = 0.5 * (v[:-1, 2] + v[1:, 2])
    gravity = -m * 9.81 * v_mid_z * traj.dt
    robot = np.diff(analysis.box_work(traj))
    ground = analysis.contact_power_on_box(traj, analysis.BOX_GROUND) * traj.dt
    whole = traj.steps["substeps"] == 1
    assert np.sum(robot[whole]) > 1e-3  # the J hook does push the box in this window
    assert np.sum(ground[whole]) < 0  # the ground's friction takes energy out
    assert np.sum(np.diff(ke)[whole]) == pytest.approx(np.sum((robot + ground + gravity)[whole]),
                                                       abs=1e-4 * np.sum(robot[whole]))


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


# --- the statistics of the claims beyond the rankings (worked examples, no simulation) ---------------------------

def made_up_trajectory(tau, dt, meta=None, joint_rate=1.0):
    """A trajectory with the given torques (N, 11), every joint turning at ``joint_rate`` rad/s, the
    box still, no contacts, and ``meta`` (the gait parameters the steady window comes from)."""
    from cobra_ref.trajectory import CONTACT_KEYS, STEP_KEYS, Trajectory
    n = len(tau)
    qd = np.zeros((n + 1, 6 + 11 + 6))
    qd[:, 6:17] = joint_rate
    box_pose = np.tile([0.0, 0.0, 0.05, 1.0, 0.0, 0.0, 0.0], (n + 1, 1))
    steps = {k: np.zeros(n) for k in STEP_KEYS}
    steps["fp_converged"] = np.ones(n)
    steps["tau_excess"] = np.abs(tau).max(axis=1) - 9.2
    contacts = {k: np.zeros((0, 3)) if k in ("contact_point", "contact_normal", "contact_force") else np.zeros(0)
                for k in CONTACT_KEYS}
    return Trajectory(dt, np.arange(n + 1) * dt, np.zeros((n + 1, 25)), qd, np.asarray(tau, float), box_pose,
                      steps, contacts, meta=meta or {})


def test_phase_correlation_finds_the_known_lags_of_pure_sines():
    """Columns sin(2 pi (t - l_j) / P), scaled and offset, with l_j = 0, 0.1, -0.25, 0.4 periods: each
    correlates 1 with column 0 at lag l_j. A sine of twice the frequency correlates with it at no
    lag: over whole periods the two are orthogonal, and over the overlaps (whole periods plus up to
    half of one) the peak stays below 0.2; fewer than two periods give nan."""
    dt, P = 0.01, 2.0
    t = np.arange(0.0, 8.0, dt)
    lags = [0.0, 0.1, -0.25, 0.4]
    x = np.stack([np.sin(2 * np.pi * (t - l * P) / P) for l in lags] + [np.sin(4 * np.pi * t / P)], axis=1)
    x[:, 2] = 3 * x[:, 2] + 5
    peak, lag = analysis.phase_correlation(x, dt, P, reference=0)
    assert peak[:4] == pytest.approx(1.0, abs=1e-9)
    assert lag[:4] == pytest.approx(lags, abs=1e-9)
    assert abs(peak[4]) < 0.2
    short_peak, short_lag = analysis.phase_correlation(x[: int(1.9 * P / dt)], dt, P)
    assert np.all(np.isnan(short_peak)) and np.all(np.isnan(short_lag))
    x[:, 3] = 2.0  # no variance: no correlation
    assert np.isnan(analysis.phase_correlation(x, dt, P)[0][3])


def test_joint_phase_correlation_uses_the_torques_after_the_ramp():
    """Joint j's torque is sin(2 pi (t - j / 25 P) / P) from the ramp's end (2 s) on and noise before;
    the lags found are j / 25 periods, the peaks 1, and without gait parameters all nan."""
    dt, P = 0.01, 2.0
    t = np.arange(0.0, 10.0, dt)
    tau = np.stack([np.sin(2 * np.pi * (t - j / 25 * P) / P) for j in range(11)], axis=1)
    tau[t < 2.0] = np.random.default_rng(0).normal(size=(int(np.sum(t < 2.0)), 11))
    traj = made_up_trajectory(tau, dt, {"gait_params": {"frequency": 1 / P, "ramp_time": 2.0}})
    assert analysis.steady_start(traj) == 2.0 and analysis.gait_period(traj) == P
    peaks, lags = analysis.joint_phase_correlation(traj)
    assert peaks == pytest.approx([1.0] * 11, abs=1e-9)
    assert lags == pytest.approx([j / 25 for j in range(11)], abs=1e-9)
    s = analysis.summary(traj)
    assert s["joint_phase_lags"] == pytest.approx(lags) and s["steady_start"] == 2.0
    bare = made_up_trajectory(tau, dt)
    assert np.all(np.isnan(analysis.joint_phase_correlation(bare)[0]))
    assert analysis.steady_start(made_up_trajectory(tau, dt, {"gait_params": {"frequency": 0.5, "ramp_time": None}})) \
        == 2.0  # the default ramp: one period


def test_coefficient_of_variation_worked_examples():
    """Constant power: CV 0; the values 1 and 3: mean 2, std 1, CV 0.5; no values or a mean <= 0: nan."""
    assert analysis.coefficient_of_variation([2.0, 2.0, 2.0]) == 0.0
    assert analysis.coefficient_of_variation([1.0, 3.0]) == pytest.approx(0.5)
    assert np.isnan(analysis.coefficient_of_variation([]))
    assert np.isnan(analysis.coefficient_of_variation([-1.0, 1.0]))


def test_power_cv_is_taken_after_the_ramp():
    """Every joint turning at 1 rad/s: |P|_loc = sum_j |tau_j|. Constant torques 0.5 after the ramp's
    1 s (and wild ones before): CV 0. Torques alternating 0.5 and 1.5 after it: |P| alternates 5.5 and
    16.5, CV = 5.5 / 11 = 0.5."""
    dt = 0.01
    t = np.arange(0.0, 3.0, dt)
    tau = np.full((len(t), 11), 0.5)
    tau[t < 1.0] = np.random.default_rng(1).normal(scale=5.0, size=(int(np.sum(t < 1.0)), 11))
    meta = {"gait_params": {"frequency": 1.0, "ramp_time": None}}
    assert analysis.power_cv(made_up_trajectory(tau, dt, meta)) == pytest.approx(0.0, abs=1e-12)
    tau[t >= 1.0] = np.where((np.arange(len(t)) % 2 == 0)[:, None], 0.5, 1.5)[t >= 1.0]
    assert analysis.power_cv(made_up_trajectory(tau, dt, meta)) == pytest.approx(0.5)
    assert np.isnan(analysis.power_cv(made_up_trajectory(tau, dt)))  # no gait parameters: no ramp known


def test_impact_rate_and_the_robot_weight():
    """m g = 12 links x 0.5 kg x 9.81 m/s^2 = 58.86 N; the impact impulse per second is the total
    impact impulse over the duration (here 0.3 N s in 2 s: 0.15 N)."""
    assert analysis.robot_weight() == pytest.approx(58.86)
    dt = 0.01
    traj = made_up_trajectory(np.zeros((200, 11)), dt)
    traj.steps["impact_impulse"][[10, 50]] = [0.1, 0.2]
    s = analysis.summary(traj)
    assert s["impact_impulse_per_second"] == pytest.approx(0.15) and s["robot_weight"] == pytest.approx(58.86)


def test_tracking_errors_are_the_largest_and_the_rms_of_the_per_step_error():
    """Per-step largest joint errors 0.01, 0.02, 0.02 rad: largest 0.02, RMS sqrt(0.0009 / 3)."""
    from types import SimpleNamespace

    traj = SimpleNamespace(steps={"tracking_error": np.array([0.01, 0.02, 0.02])})
    out = analysis.tracking_errors(traj)
    assert out["max_tracking_error"] == 0.02
    assert out["rms_tracking_error"] == pytest.approx(np.sqrt(0.0009 / 3), rel=1e-12)


def test_the_ledger_residual_is_what_the_work_energy_balance_misses():
    """Two steps: the actuators do 3 J, the contacts -1 J, the bodies gain 1.5 J of kinetic and
    potential energy: the balance misses 3 - 1 - 1.5 = 0.5 J, a sixth of the actuators' work (the
    last row's works belong to no step and are left out); an exact balance leaves 0."""
    from types import SimpleNamespace

    steps = {"work_actuators": np.array([1.0, 2.0, 9.0]), "work_contacts": np.array([-0.5, -0.5, 9.0]),
             "kinetic": np.array([0.0, 0.5, 1.0]), "potential": np.array([2.0, 2.2, 2.5])}
    traj = SimpleNamespace(steps=steps, tau=np.zeros((2, 11)))
    assert analysis.ledger_residual(traj) == pytest.approx(0.5 / 3, rel=1e-12)
    steps["potential"] = np.array([2.0, 2.2, 3.0])
    assert analysis.ledger_residual(traj) == pytest.approx(0.0, abs=1e-15)
