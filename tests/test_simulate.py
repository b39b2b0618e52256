"""simulate() on COBRA and the box: the 10 s rolling push, its ledger, both steppers, mirror runs, failures."""

import numpy as np
import pytest

from cobra_ref.fast.stepper import FastStepper
from cobra_ref.gaits import RollingGait, gait
from cobra_ref.robots import cobra_model
from cobra_ref.simulate import simulate
from cobra_ref.start import SETTLE_SPEED, BoxPlacement, Hold, initial_state, placed_state
from cobra_ref.step import SimulationError, StepSettings, step


@pytest.fixture(scope="module")
def rolling_push():
    """10 s of the built-in C rolling with the box beside the middle of the snake (the defaults:
    compliant contact, position servo, dt = 1 ms, the fast stepper, a settled start)."""
    return simulate(cobra_model(), RollingGait(), 10.0)


def test_ten_seconds_of_rolling_push_the_box_within_the_laws_and_the_limits(rolling_push):
    """The run's health, each a condition of eq. (2)-(6): no NaN; penetration below 1 mm (the
    compliant contact sinks by its sag, about 10 um); friction inside Coulomb's circle on every
    contact of every step; the friction fixed point converged on at least 99.9 % of the steps;
    the position servo never beyond tau_max (eq. (6) constraint (3)); the box pushed and never
    tipped (its z axis within 10 degrees of vertical) or sunk."""
    traj = rolling_push
    s = traj.steps
    assert not traj.error and len(traj.tau) == 10_000
    for name in ("q", "qd", "tau", "box_pose"):
        assert np.all(np.isfinite(getattr(traj, name))), name
    assert s["max_penetration"].max() < 1e-3, "max penetration below 1 mm"
    assert s["cone_residual"].max() <= 1e-12, "friction inside the circle"
    assert s["fp_converged"].mean() >= 0.999, f"fixed point converged on {100 * s['fp_converged'].mean():.2f} %"
    assert s["tau_excess"].max() <= 1e-12, "the servo torque stays within tau_max"
    moved = np.linalg.norm(traj.box_pose[-1, :2] - traj.box_pose[0, :2])
    assert moved > 0.1, f"the box must move: {moved:.3f} m"
    assert np.any(traj.contacts["contact_kind"] == 1)
    qx, qy = traj.box_pose[:, 4], traj.box_pose[:, 5]
    tilt = np.degrees(np.arccos(np.clip(1 - 2 * (qx**2 + qy**2), -1.0, 1.0)))
    assert tilt.max() < 10.0, f"the box tilts {tilt.max():.1f} degrees"
    assert np.all(traj.box_pose[:, 2] > 0.05 - 1e-3), "the box does not sink into the ground"


def test_the_energy_ledger_closes_within_1_percent_of_the_actuator_work(rolling_push):
    """Work-energy of the bodies over the run: W_act + W_contact = Delta (KE + PE), within 1 % of W_act.

    Per step k: W_act,k = dt tau . u_mid over the joints, W_contact,k = x_c . J_c u_mid (the
    work of the contacts' impulses on the bodies), with u_mid = (u + u+) / 2; KE and PE are
    logged at each step's start, so steps 0 .. N-2 span E[N-1] - E[0]. Per step,
    Delta KE = u_mid . M (u+ - u) holds exactly at the step's M; the residual comes from M and
    PE changing along the step (second order in dt on smooth motion, step.midpoint_velocity; first order
    across impacts). The contacts' work itself splits into the
    springs' stored energy and what the dampers and friction dissipate: -W_contact - Delta
    E_elastic >= 0.
    """
    s = rolling_push.steps
    W_act, W_contact = s["work_actuators"][:-1].sum(), s["work_contacts"][:-1].sum()
    E = s["kinetic"] + s["potential"]
    residual = W_act + W_contact - (E[-1] - E[0])
    assert W_act > 1.0, "the joints do work"
    assert -W_contact - (s["elastic"][-1] - s["elastic"][0]) > 0, "contact dissipates"
    assert abs(residual) <= 0.01 * abs(W_act), (W_act, W_contact, E[-1] - E[0], residual)


def test_the_fast_and_the_reference_stepper_push_the_box_alike_for_half_a_second():
    """The two steppers side by side over 0.5 s of pushing: from the step the robot first loads
    the box (the box 5 mm from the middle link), each takes its own 500 steps; the states stay
    equal to 1e-9 (measured: 1e-15 in q), the box moving by about 2.5 cm meanwhile."""
    model, reference, settings = cobra_model(), RollingGait(), StepSettings()
    q, qd = initial_state(model, reference, settings, BoxPlacement(gap=0.005))
    fast = FastStepper(model, settings)
    k = 0
    while True:
        result = fast.step(q, qd, k * settings.dt, reference)
        q, qd, k = result.q, result.qd, k + 1
        if np.any(result.p[0::3][result.contacts.kind == 1] > 0):
            break
    q_f, qd_f, q_r, qd_r, previous = q, qd, q, qd, fast.memory
    for j in range(500):
        t = (k + j) * settings.dt
        a = fast.step(q_f, qd_f, t, reference)
        b = step(model, q_r, qd_r, t, reference, settings, previous)
        (q_f, qd_f), (q_r, qd_r), previous = (a.q, a.qd), (b.q, b.qd), b.memory
    box = model.q_idx[model.boxes[0].body]
    assert np.linalg.norm(q_f[box][:2] - q[box][:2]) > 0.01, "the box was pushed"
    np.testing.assert_allclose(q_f, q_r, atol=1e-9)
    np.testing.assert_allclose(qd_f, qd_r, atol=1e-9)


def test_j_and_the_mirrored_j_stay_mirror_images():
    """J-mirror is J reflected in the robot's vertical plane (y -> -y), its box placed in the
    mirror too; with one answer per step (the compliant QP is strictly convex) the runs stay
    mirror images: box positions within 1e-6 m after 3 s."""
    model = cobra_model()
    runs = [simulate(model, gait(name), 3.0) for name in ("J", "J-mirror")]
    box_J, box_M = runs[0].box_pose[:, :3], runs[1].box_pose[:, :3]
    np.testing.assert_allclose(box_M, box_J * [1.0, -1.0, 1.0], atol=1e-6)
    assert np.abs(box_J[-1, :2] - box_J[0, :2]).max() > 0.01, "the box was pushed"


def test_a_start_in_deep_penetration_is_refused_naming_the_body():
    model = cobra_model()
    reference = RollingGait()
    q, qd = placed_state(model, reference), np.zeros(model.nv)
    q[2] -= 0.02  # sink the whole robot 2 cm into the ground
    with pytest.raises(SimulationError, match=r"deep penetration: robot-ground contact on body '.+' is 20\.0 mm"):
        simulate(model, reference, 1.0, q0=q, qd0=qd)


def test_a_failure_mid_run_names_step_and_time_and_keeps_what_was_computed():
    """A reference that turns NaN after t = 0.02 s: step 20 (t = 0.020 s) needs q_ref(0.021)."""
    model = cobra_model()
    rolling = RollingGait()

    def breaks(t):
        q, qd, qdd = rolling(t)
        return (q * np.nan, qd, qdd) if t > 0.02 else (q, qd, qdd)

    q0, qd0 = placed_state(model, rolling), np.zeros(model.nv)
    with pytest.raises(SimulationError, match=r"step failed at step 20, t = 0\.0200 s: the joint reference is not finite") as err:
        simulate(model, breaks, 1.0, q0=q0, qd0=qd0)
    traj = err.value.trajectory
    assert len(traj.tau) == 20 and len(traj.t) == 21 and "step 20" in traj.error
    assert np.all(np.isfinite(traj.q)) and traj.t[-1] == pytest.approx(0.020)


def _com_plane_normal(model, q):
    """Unit normal of the least-squares plane through the robot bodies' centres of mass."""
    from cobra_ref.kinematics import forward_kinematics

    kin = forward_kinematics(model, q)
    robot = [i for i in range(model.nb) if i != model.boxes[0].body]
    com = np.array([kin.o[i] + kin.R[i] @ model.com[i] for i in robot])
    return np.linalg.svd(com - com.mean(axis=0))[2][-1]


def test_a_3d_start_shape_is_laid_on_its_flattest_side():
    """Sidewinding's t = 0 shape is not planar; placed_state turns the base so that the best-fit
    plane of the bodies' centres of mass is horizontal (normal = +-z), and the lowest sphere
    touches the ground. A planar rolling shape is not turned at all (identity quaternion)."""
    model = cobra_model()
    q = placed_state(model, gait("sidewinding"))
    assert abs(_com_plane_normal(model, q)[2]) == pytest.approx(1.0, abs=1e-12)
    assert not np.allclose(q[3:7], [1, 0, 0, 0]), "sidewinding's start must be turned"
    q_c = placed_state(model, gait("C"))
    np.testing.assert_array_equal(q_c[3:7], [1.0, 0.0, 0.0, 0.0])
    from cobra_ref.kinematics import forward_kinematics

    kin, sph = forward_kinematics(model, q), model.spheres
    robot = sph.body != model.boxes[0].body
    bottoms = [kin.o[b][2] + (kin.R[b] @ c)[2] - r for b, c, r in zip(sph.body[robot], sph.center[robot],
                                                                      sph.radius[robot])]
    assert min(bottoms) == pytest.approx(0.0, abs=1e-12)


def test_box_direction_puts_the_box_that_way_facing_the_robot():
    """With box_direction d the box centre is at middle + (r + a/2 + gap) d, yawed along d; a zero
    or non-finite direction is refused."""
    from cobra_ref.kinematics import forward_kinematics

    model = cobra_model()
    ref = RollingGait()
    d = np.array([-0.6, -0.8])
    q = placed_state(model, ref, BoxPlacement(direction=d))
    kin = forward_kinematics(model, q)
    mids = [model.body_names.index(n) for n in ("L5", "L6")]
    middle = np.mean([kin.o[i] + kin.R[i] @ model.com[i] for i in mids], axis=0)[:2]
    box = model.boxes[0]
    r = max(model.spheres.radius[np.isin(model.spheres.body, mids)])
    centre = q[model.q_idx[box.body]][:2]
    np.testing.assert_allclose(centre, middle + (r + box.half[0] + 0.05) * d, atol=1e-12)
    qw, qz = q[model.q_idx[box.body]][3], q[model.q_idx[box.body]][6]
    assert 2 * np.arctan2(qz, qw) == pytest.approx(np.arctan2(d[1], d[0]))
    for bad in ([0.0, 0.0], [np.nan, 1.0]):
        with pytest.raises(ValueError, match="box_direction"):
            BoxPlacement(direction=bad)


@pytest.mark.parametrize("name", ["C", "sidewinding"])
def test_the_start_is_settled_every_loaded_sphere_on_the_ground_and_at_rest(name):
    """initial_state lets the placed scene settle (joints holding the start shape; sidewinding's
    3-D shape first rolls onto a stable side): then nothing falls: no coordinate moves faster
    than SETTLE_SPEED = 1 cm/s, and each sphere that carries weight touches the ground (its gap
    between -1e-4 m, the compliant sag, and 0); held 0.5 s longer, the robot moves by less than
    1 mm (at rest, not at a slow turning point of its roll: SETTLE_STILL)."""
    model, settings = cobra_model(), StepSettings()
    q, qd = initial_state(model, gait(name), settings)
    assert np.abs(qd).max() < SETTLE_SPEED, np.abs(qd).max()
    result = FastStepper(model, settings).step(q, qd, 0.0, gait(name))
    loaded = result.p[0::3] > 0
    ground = result.contacts.kind == 0
    assert (loaded & ground).sum() >= 3
    assert np.all(result.contacts.g[loaded] > -1e-4) and np.all(result.contacts.g[loaded] < 1e-6)
    stepper, hold, q0 = FastStepper(model, settings), Hold(gait(name)(0.0)[0]), q.copy()
    for k in range(500):
        res = stepper.step(q, qd, k * settings.dt, hold)
        q, qd = res.q, res.qd
    assert np.abs(q[:3] - q0[:3]).max() < 1e-3


def test_kinetic_damping_reaches_the_undamped_rest_sooner(monkeypatch):
    """Dynamic relaxation (initial_state's settle): zeroing the velocities at each peak of the
    kinetic energy removes the swing, not a force, so sidewinding's 3-D start comes to the rest
    the plain model reaches after its slow rocking (stepped 3 s with the joints held): the same
    side (base orientation within 0.01) and place (within 5 mm, friction's path dependence), in
    under a third of the steps the plain model needs to meet the same rest rule (measured: 428
    against 1856)."""
    import cobra_ref.fast.stepper
    from cobra_ref.start import SETTLE_STILL, SETTLE_TIME

    model, settings, ref = cobra_model(with_box=False), StepSettings(), gait("sidewinding")
    steps = []

    class Counting(FastStepper):
        def step(self, *args, **kwargs):
            steps.append(1)
            return super().step(*args, **kwargs)

    monkeypatch.setattr(cobra_ref.fast.stepper, "FastStepper", Counting)
    q, qd = initial_state(model, ref, settings)
    # the plain model: held in its start shape, stepped 3 s; when it first met the rest rule
    q_plain, qd_plain = placed_state(model, ref), np.zeros(model.nv)
    stepper, hold = FastStepper(model, settings), Hold(ref(0.0)[0])
    calm, plain_steps = 0, None
    for k in range(3000):
        res = stepper.step(q_plain, qd_plain, k * settings.dt, hold)
        q_plain, qd_plain = res.q, res.qd
        calm = calm + 1 if np.abs(qd_plain).max() < SETTLE_SPEED else 0
        if plain_steps is None and k + 1 >= SETTLE_TIME / settings.dt and calm >= SETTLE_STILL / settings.dt:
            plain_steps = k + 1
    assert plain_steps is not None and np.abs(qd_plain).max() < SETTLE_SPEED  # the plain model is at rest
    assert np.abs(q[3:7] - q_plain[3:7]).max() < 0.01
    assert np.abs(q[:3] - q_plain[:3]).max() < 5e-3
    assert len(steps) < plain_steps / 3, (len(steps), plain_steps)


class _StuckQP:
    """A box-QP solver that answers every QP with the same impulses (1 mN s on every row, within
    the bounds), whatever H and c: the friction fixed point cannot converge on it."""

    def new_step(self):
        pass

    def __call__(self, H, c, lo, hi, x0):
        from cobra_ref.qp import BoxQPSolution

        return BoxQPSolution(np.clip(np.full(len(c), 1e-3), lo, hi), np.zeros(len(c)), 0, "solved", 0)


def test_a_step_the_certified_solves_leave_unconverged_is_solved_by_the_reference_loop():
    """The fast stepper's certified QP solves are an acceleration: where its fixed point ends
    unconverged (here forced, by a QP solver that never moves), it solves the step again with the
    reference step's loop, OSQP on every iterate, from the same start. J's first step from its
    settled start then equals the reference step's, converged, and counts both loops' iterates."""
    model, settings, reference = cobra_model(), StepSettings(), gait("J")
    q, qd = initial_state(model, reference, settings)
    fast = FastStepper(model, settings)
    fast.qp = _StuckQP()
    a = fast.step(q, qd, 0.0, reference)
    b = step(model, q, qd, 0.0, reference, settings)
    assert a.info.converged and b.info.converged
    # 50 stuck iterates, then the reference loop's; OSQP's answer lands within its tolerance of the
    # fixed point's, so the two loops may stop one iterate apart
    assert 50 + b.info.iterations <= a.info.iterations <= 50 + b.info.iterations + 1
    np.testing.assert_allclose(a.qd, b.qd, atol=1e-9)
    np.testing.assert_allclose(a.p, b.p, atol=1e-9)
