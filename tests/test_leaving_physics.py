"""A run that leaves physics says so (A32): prescribed joints that need torques beyond tau_max, or a
contact's normal force beyond ``simulate.contact_force_bound``, warn once (``LeftPhysicsWarning``)
and are recorded in the summary and the NPZ; a run within physics does not warn.

Worked example: COBRA with tau_max = 0.5 N m and prescribed joints needs about 3.9 N m to hold its
links up in the first steps of the C gait, on every step: one warning, share 1.0, worst ~3.9 N m.
"""

import importlib
import json
import warnings

import numpy as np
import pytest

from cobra_ref.cli import main
from cobra_ref.gaits import gait
from cobra_ref.params import CobraParameters
from cobra_ref.reproduce.sweep import penetration_error
from cobra_ref.robots import cobra_model

# the module (the package's attribute ``simulate`` is the function of the same name)
sim = importlib.import_module("cobra_ref.simulate")
from cobra_ref.step import StepSettings
from cobra_ref.trajectory import STEP_KEYS, Trajectory


def _run(params=CobraParameters(), servo="prescribed", duration=0.03):
    """(trajectory, the LeftPhysicsWarnings it issued) of a short run of the C gait."""
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        traj = sim.simulate(cobra_model(params), gait("C"), duration, StepSettings(servo=servo))
    return traj, [w for w in caught if issubclass(w.category, sim.LeftPhysicsWarning)]


def test_prescribed_joints_beyond_tau_max_warn_once_and_are_recorded(tmp_path):
    traj, caught = _run(CobraParameters(tau_max=0.5))
    assert len(caught) == 1
    message = str(caught[0].message)
    assert "tau_max = 0.5 N m" in message and "100 % of the steps" in message and "normal force" not in message
    tau = traj.summary()["tau_beyond_limit"]
    worst = float(np.abs(traj.tau).max())
    assert tau == {"share_of_steps": 1.0, "worst_N_m": worst, "limit_N_m": 0.5}
    assert 3.0 < worst < 5.0 and f"worst {worst:.4g} N m" in message
    assert traj.summary()["contact_force_beyond_bound"]["share_of_steps"] == 0.0
    # the NPZ holds the per-step records and the limits: the summary reads back the same
    path = str(tmp_path / "run.npz")
    traj.to_npz(path)
    back = Trajectory.from_npz(path)
    np.testing.assert_array_equal(back.steps["max_normal_force"], traj.steps["max_normal_force"])
    np.testing.assert_array_equal(back.steps["tau_excess"], traj.steps["tau_excess"])
    assert back.beyond_limits() == traj.beyond_limits()


def test_a_run_within_physics_does_not_warn():
    traj, caught = _run(servo="prescribed")
    assert caught == []
    limits = traj.summary()
    assert limits["tau_beyond_limit"]["share_of_steps"] == 0.0
    assert limits["contact_force_beyond_bound"] == {"share_of_steps": 0.0, "worst_N": pytest.approx(23.9, abs=2.0),
                                                    "bound_N": pytest.approx(30 * 6.5 * 9.81)}
    # the position servo bounds its torques by construction: share 0, said so
    traj, caught = _run(servo="position", duration=0.01)
    assert caught == []
    tau = traj.summary()["tau_beyond_limit"]
    assert tau["share_of_steps"] == 0.0 and "position servo" in tau["note"] and tau["worst_N_m"] <= 9.2


def test_the_bound_is_thirty_weights_of_every_body():
    assert sim.contact_force_bound(cobra_model()) == pytest.approx(30 * 6.5 * 9.81)
    assert sim.contact_force_bound(cobra_model(CobraParameters(box_mass=2.0))) == pytest.approx(30 * 8.0 * 9.81)


def test_a_contact_force_beyond_the_bound_warns_once(monkeypatch):
    # a bound of 0.2 weights (12.8 N): with the position servo a ground contact carries about 15.6 N
    monkeypatch.setattr(sim, "CONTACT_FORCE_WEIGHTS", 0.2)
    traj, caught = _run(servo="position", duration=0.01)
    assert len(caught) == 1 and "normal force beyond the bound 12.75 N" in str(caught[0].message)
    assert "tau_max" not in str(caught[0].message)
    force = traj.summary()["contact_force_beyond_bound"]
    assert force["bound_N"] == pytest.approx(0.2 * 6.5 * 9.81) == traj.meta["limits"]["contact_force_bound_N"]
    assert force["share_of_steps"] == 1.0 and force["worst_N"] == traj.steps["max_normal_force"].max() > 12.75


def test_the_command_line_prints_the_warning_as_one_line(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(sim, "CONTACT_FORCE_WEIGHTS", 0.2)
    out = str(tmp_path / "run.npz")
    assert main(["simulate", "--duration", "0.01", "--out", out, "--quiet"]) == 0
    captured = capsys.readouterr()
    lines = [ln for ln in captured.err.splitlines() if "left physics" in ln]
    assert len(lines) == 1 and lines[0].startswith("warning: the run left physics: ")
    summary = json.loads(captured.out.strip().splitlines()[-1])
    assert summary["contact_force_beyond_bound"]["share_of_steps"] == 1.0
    assert summary["tau_beyond_limit"]["share_of_steps"] == 0.0


def test_an_older_npz_without_the_normal_force_reads_as_zeros(tmp_path):
    traj, _ = _run(duration=0.005)
    path = str(tmp_path / "old.npz")
    traj.to_npz(path)
    with np.load(path) as z:
        arrays = {k: z[k] for k in z.files if k != "max_normal_force"}
    np.savez(path, **arrays)
    back = Trajectory.from_npz(path)
    assert set(back.steps) == set(STEP_KEYS)
    np.testing.assert_array_equal(back.steps["max_normal_force"], np.zeros(len(traj.tau)))


def _log(gap, force_n, contact="compliant"):
    """A one-step Trajectory whose contact log holds contacts at ``gap`` [m] pressed by ``force_n`` [N]."""
    m = len(gap)
    normal = np.tile([0.0, 0.0, 1.0], (m, 1))
    contacts = {"contact_gap": np.array(gap), "contact_normal": normal,
                "contact_force": normal * np.array(force_n)[:, None]}
    steps = {"max_penetration": np.array([max(0.0, -min(gap))])}
    return Trajectory(1e-3, np.zeros(2), np.zeros((2, 1)), np.zeros((2, 1)), np.zeros((1, 1)), np.zeros((2, 7)),
                      steps, contacts, meta={"settings": {"contact": contact}})


def test_the_penetration_error_is_the_penetration_beyond_the_springs_deflection():
    # 5 mm deep under 5 kN is the spring's own deflection F / k: no error; 3 mm under 1 kN is 2 mm too deep
    assert penetration_error(_log([-0.005], [5000.0]), 1e6) == pytest.approx(0.0, abs=1e-12)
    assert penetration_error(_log([-0.005, -0.003], [5000.0, 1000.0]), 1e6) == pytest.approx(0.002)
    # a contact apart at the step's start (the damper closing it) has no error
    assert penetration_error(_log([0.001], [10.0]), 1e6) == 0.0
    # the rigid law has no spring: the penetration itself
    assert penetration_error(_log([-0.005], [5000.0], "rigid"), 1e6) == 0.005
