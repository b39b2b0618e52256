"""The robust statistics of ``analysis.summary``: the 99th percentile beside each maximum, worked by
hand on a small made-up trajectory (no simulation)."""

import numpy as np
import pytest

from cobra_ref.reproduce import analysis
from cobra_ref.gaits import N_JOINTS
from cobra_ref.trajectory import CONTACT_KEYS, STEP_KEYS, Trajectory

N = 51  # steps: the 99th percentile's rank 0.99 (N - 1) = 49.5 falls between two samples


def by_hand_p99(values):
    """The 99th percentile by hand: sort, rank r = 0.99 (n - 1), interpolate between s_floor(r)
    and the next sample."""
    s = sorted(float(v) for v in values)
    r = 0.99 * (len(s) - 1)
    i = int(r)
    return s[i] + (r - i) * (s[i + 1] - s[i]) if i + 1 < len(s) else s[i]


@pytest.fixture
def made_up(rng):
    """N steps with joint J1 turning at 1 rad/s and the other joints still, so |P|_loc,k = |tau_1,k|;
    the torques, the steps' torque excess and 20 contact onsets' approach speeds (6 of them 0) are
    shuffled random numbers, with one spike each."""
    tau = rng.uniform(-3.0, 3.0, size=(N, N_JOINTS))
    tau[rng.integers(N), rng.integers(N_JOINTS)] = 50.0  # one spike, in whichever joint
    qd = np.zeros((N + 1, 6 + N_JOINTS + 6))
    qd[:, 6] = 1.0  # J1's rate; the midpoint rate is 1 too
    box_pose = np.tile([0.0, 0.0, 0.05, 1.0, 0.0, 0.0, 0.0], (N + 1, 1))
    steps = {k: np.zeros(N) for k in STEP_KEYS}
    steps["fp_converged"] = np.ones(N)
    steps["tau_excess"] = np.abs(tau).max(axis=1) - 9.2
    m = 20
    contacts = {k: np.zeros((m, 3)) if k in ("contact_point", "contact_normal", "contact_force") else np.zeros(m)
                for k in CONTACT_KEYS}
    contacts["contact_step"] = np.arange(m)
    contacts["contact_onset_speed"] = rng.permutation(np.r_[np.zeros(6), rng.uniform(0.0, 0.02, m - 7), 0.3])
    return Trajectory(1e-3, np.arange(N + 1) * 1e-3, np.zeros((N + 1, 25)), qd, tau, box_pose, steps, contacts)


def test_summary_reports_the_99th_percentile_beside_each_maximum(made_up):
    """p99 of |P|_loc, of the per-step largest |tau|, of the torque excess and of the onsets'
    approach speeds, each equal to the hand computation and at most the maximum beside it, which
    the one spike sets (so the two differ)."""
    s = analysis.summary(made_up)
    tau_step = np.abs(made_up.tau).max(axis=1)
    P_abs = np.abs(made_up.tau[:, 0])
    speeds = made_up.contacts["contact_onset_speed"]
    expected = {("peak_abs_power", "p99_abs_power"): P_abs,
                ("peak_abs_tau", "p99_abs_tau"): tau_step,
                ("max_tau_excess", "p99_tau_excess"): made_up.steps["tau_excess"],
                ("max_approach_speed", "p99_approach_speed"): speeds[speeds > 0]}
    for (peak, p99), values in expected.items():
        assert s[p99] == pytest.approx(by_hand_p99(values), abs=1e-12), p99
        assert s[peak] == pytest.approx(max(values), abs=1e-12), peak
        assert s[p99] <= s[peak], p99
    assert s["peak_abs_tau"] == 50.0 and s["p99_abs_tau"] < 50.0  # the spike sets the max, not the p99
    assert s["max_approach_speed"] == 0.3 and s["p99_approach_speed"] < 0.3


def test_the_new_keys_are_added_to_the_old_ones(made_up):
    """Additive: every key the claims report and the other readers use is still there."""
    old = {"duration", "locomotion_work", "box_work", "efficiency_slope", "peak_abs_power", "mean_abs_power",
           "box_displacement", "box_distance", "robot_box_steps", "max_tau_excess", "fixed_point_converged",
           "impacts_per_second", "impact_impulse", "impact_energy", "max_approach_speed"}
    assert old <= set(analysis.summary(made_up))


def test_percentile_99_of_nothing_is_the_given_empty_value():
    assert analysis.percentile_99([]) == 0.0 and analysis.percentile_99(np.zeros(0), empty=-np.inf) == -np.inf
    assert analysis.percentile_99([7.0]) == 7.0
